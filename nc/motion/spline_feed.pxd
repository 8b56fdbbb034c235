# Types for nc/motion/spline_feed.py where setup.py compiles it with Cython (issue 17, decision bench B136).
# Held is built on every push: as an extension type its dataclass __init__ is C (the fields stay Python objects).

cdef class Held:
    cdef public object moves
    cdef public object behind
    cdef public object fitting
    cdef public object end
    cdef public object u
    cdef public object tail
    cdef public object key
