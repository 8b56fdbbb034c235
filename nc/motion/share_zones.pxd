# Types for nc/motion/share_zones.py where setup.py compiles it with Cython (issue 17, session 28, decision bench
# B157): the zones' bounds are C doubles and the planner's questions to them (`Planner._corner`: inside, blend_allowed,
# hard; one each a pushed block) C calls. The .py is the source of truth and runs as it is where nothing was compiled.
cimport cython

cdef double _RAMP
cdef double _INF

cdef class Zone:
    cdef public double lo, c0, c1, rr, hi
    cpdef double lam(self, double s) except? -1.0

cdef class ShareZones:
    cdef public double window, _stop, _hard
    cdef public object zones
    cpdef double reach(self, double vtop) except? -1.0
    cpdef stop(self, double s)
    cpdef bint blend_allowed(self, double start, double vtop, double now, bint rest) except -1
    cpdef add_blend(self, double start, double end, double vtop)
    cpdef block(self, double start, double vtop)
    cpdef bint inside(self, double s, double vtop) except -1
    cpdef bint hard(self, double s, double vtop) except -1
    cpdef double lam(self, double s) except? -1.0
    cpdef bint near(self, double lo, double hi) except -1
