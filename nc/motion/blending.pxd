# Types for nc/motion/blending.py where setup.py compiles it with Cython (issue 17, decision bench B115): the
# filter corners' per-push state is a C struct and `window` runs on C doubles and indices, each operation the
# same IEEE one Python does (setup.py turns fused multiply-add off). The .py is the source of truth and runs as it
# is where nothing was compiled.
from nc.motion.block cimport Block

cdef class FilterCorners:
    cdef public double t_a, t_j, t2sum, _iso_k, _arc_k, span_max, amax, _sc_head, _lim_s, _arc_s
    cdef public object tol, kd, cb, _vq, _bud
    cdef public tuple budget_a, budget_j, budget_al, budget_jl, _bmin, budget, _zero, _sc_ok, _vq_at, _maxima
    cdef public dict _boost
    cdef public list _hist, _hist_s, _vt, _sc
    cdef public Py_ssize_t _axes, _sc_dirty, _h0, _m, _seq0, _seq_v, _mono
