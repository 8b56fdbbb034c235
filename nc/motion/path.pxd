# Types for nc/motion/path.py where setup.py compiles it with Cython (issue 17, decision bench B136).
# Segment is made once per block: as an extension type (bench B156) line_of fills its slots from C, and its end
# points are kept as lists until an array is asked for.

cdef class Segment:
    cdef public object axes
    cdef public object _pa
    cdef public object _pb
    cdef public object _fa
    cdef public object _fb
    cdef public object length
    cdef public object kind
    cdef public object i1
    cdef public object i2
    cdef public object center
    cdef public object radius
    cdef public object a0
    cdef public object theta
    cdef public object arc_len
    cdef public object _dir
    cdef public object _cos

# a C call from the planner's run feed (session 29, decision bench B166)
cpdef Segment line_segment(object axes, list ls, list le, object length, list d)
