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
