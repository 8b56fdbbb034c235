# Types for nc/motion/lookahead.py where setup.py compiles it with Cython (issue 17, decision bench B115). The
# passes' constants are C doubles and their square root C's (session 27, decision bench B148): math.sqrt calls the
# same C sqrt, and _sqrt raises its ValueError below 0.
cimport cython
from nc.motion.block cimport Block
from nc.motion.path cimport Segment
# as _FilterCorners: the module's name FilterCorners stays the Python class Limits makes (a test makes a subclass)
from nc.motion.blending cimport FilterCorners as _FilterCorners

cdef double _MARGIN
cdef double _INF

cdef double _sqrt(double x) except? -1.0

cpdef double change_distance(double v0, double v1, double a, double j) except? -1.0

# `Limits` an extension type (session 28, decision bench B157): the planner calls `junction` and `block_limits` once
# a pushed block each as C calls, and they read the limits from a struct. Where the hot paths read a field it is
# typed; the others stay Python objects (the values the .py stores, as they were).
cdef class Limits:
    cdef public object cfg, v, acc, jerk, rv, racc, rjerk
    cdef public double T, _min_dur, _share_t
    cdef public tuple _v, _acc, _jerk, _corner_j, _corner_a, _rv, _racc, _rjerk
    cdef public _FilterCorners blend
    cdef public object _coupling, cut_a, cut_js, line_a_lo, line_j_lo
    cdef public bint cut_on
    cdef public object rapid_whole, rapid_share, rapid_v, rapid_a, rapid_js
    cpdef tuple block_limits(self, object seg, bint short_ok=*, Py_ssize_t what=*)
    cpdef double junction(self, Block b1, Block b2, bint raw=*) except? -1.0

# The backward pass a cpdef function (session 31, decision bench B181): Planner.lookahead calls it in C (a Python call
# with a keyword argument was ≈ 1.5k instructions a pass, ≈ one pass in five pushed blocks); Python callers as before.
@cython.locals(n=Py_ssize_t, k=Py_ssize_t, m=Py_ssize_t, k_stop=Py_ssize_t, nx=Block, b=Block, nx_vend=double,
               nx_binding=bint, nx_cap=double, nx_length=double, nx_a=double, nx_j=double, nx_av=double, nx_ad=double,
               nx_aa=double, nx_aj=double, b_cap=double, local=double, v=double, av=double, ad=double, aa=double,
               aj=double, r=double, binding=bint)
cpdef object backward(object blocks, Py_ssize_t lo=*, bint full=*, Py_ssize_t depth=*)
