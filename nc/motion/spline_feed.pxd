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

cdef bint _joined(list p, list q) except -1
cdef double _step(list p, list q) except? -1.0

# RunFeed an extension type (session 29, decision bench B166): the planner calls `feed` and `_line` once a push as C
# calls, and their fields (the last line's geometry among them) are a struct's.
cdef class RunFeed:
    cdef public double tol, acc, corner_j
    cdef public object axes, blend, memo, out
    cdef public dict _pay
    cdef public bint spans
    cdef public object _gm
    cdef public list _ga, _gb, _gu
    cdef public double _gn
    cdef bint _line(self, object mv) except -1
    cpdef Held feed(self, Held st, object mv)
