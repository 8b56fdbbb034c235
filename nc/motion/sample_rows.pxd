# Types for nc/motion/sample_rows.py where setup.py compiles it with Cython (issue 17, decision bench B115).
cimport cython

# Piecewise.at's steps, called in C (session 29, decision bench B169)
from nc.motion.profile cimport _lists0, _pos_at, _row_at
from nc.motion.block cimport Block

# few_rows' buffers, rows of a slab written from C doubles (session 30, decision bench B175)
cdef class _Slab:
    cdef public Py_ssize_t m, at
    cdef public object pos, vel
    cdef double[:, ::1] _pv
    cdef double[::1] _vv

# the slab rows a caller writes (few_rows, slab_rows), claimed in C
cdef _Slab _claim(Py_ssize_t m, Py_ssize_t rows)

# a cruise's buffers as slab rows (Planner._sample_cruise, session 30, decision bench B176)
@cython.locals(sl=_Slab, at=Py_ssize_t, i=Py_ssize_t, k=Py_ssize_t, r=list)
cpdef tuple slab_rows(list pos, Py_ssize_t m, Py_ssize_t rows, double v)
