# Types for nc/motion/blending.py where setup.py compiles it with Cython (issue 17, decision bench B115): the
# filter corners' per-push state is a C struct and `window` runs on C doubles and indices, each operation the
# same IEEE one Python does (setup.py turns fused multiply-add off). The .py is the source of truth and runs as it
# is where nothing was compiled.
cimport cython
from nc.motion.block cimport Block

cdef double _INF  # math.inf as a C constant (decision bench B134)
cdef double _NAN  # math.nan, the same (decision bench B187)
cdef double USAGE_SCALE  # window's constants as C ones (decision bench B188: a Python global read boxed a
cdef Py_ssize_t _BULK  # number and compared objects a push)

# bisect_left on a list of floats in C (decision bench B153), nc.motion.profile's (shared with nc.motion.shares)
from nc.motion.profile cimport _at_or_above

@cython.locals(ja=double, x=double)
cdef inline double _axis_cap(double si, double sg, double bj, double ba, double c)

# window's sliding maxima (decision bench B134): C methods, the entries in two C buffers (array.array) read from
# `head` to `n` (decision bench B153)
cdef class _MaxQ:
    cdef public long long[::1] seqs
    cdef public double[::1] vals
    cdef public Py_ssize_t head, n
    @cython.locals(n=Py_ssize_t, i=Py_ssize_t, seqs=object, vals=object)
    cdef int _grow(self) except -1
    @cython.locals(n=Py_ssize_t)
    cdef int push(self, Py_ssize_t seq, double x) except -1
    @cython.locals(n=Py_ssize_t, i=Py_ssize_t)
    cdef int push_front(self, Py_ssize_t seq, double x) except -1
    @cython.locals(h=Py_ssize_t, n=Py_ssize_t, i=Py_ssize_t)
    cdef int drop(self, Py_ssize_t seq_m) except -1
    cdef double front(self) except? -1.0

cdef class FilterCorners:
    cdef public double t_a, t_j, t2sum, _iso_k, _arc_k, span_max, amax, _sc_head, _lim_s, _arc_s
    cdef public object tol, kd, cb, _vq
    cdef public tuple budget_a, budget_j, budget_al, budget_jl, _bmin, budget, _sc_ok, _vq_at, _maxima
    cdef public object _bud_b  # the last window's share (decision bench B188): J's block or None, ...
    cdef public Py_ssize_t _bud_seq  # ... its stretch's first sequence number ...
    cdef public double _bud_c  # ... and c_bud
    cdef public dict _boost
    cdef public list _hist, _hist_s, _vt, _sc
    cdef public Py_ssize_t _axes, _sc_dirty, _h0, _m, _seq0, _seq_v, _mono
    cdef public object _gy, _gg, _gs
    # window's search state for _cap and _taken (decision bench B133)
    cdef public Py_ssize_t _w_last, _w_h0
    cdef public double _w_s_j, _w_top, _w_pad, _w_two_al, _w_t_w2, _w_v_hi
    cdef public tuple _w_ba, _w_bj, _w_bmin
    cdef public Py_ssize_t _w_k1, _w_k2  # the last two caps `_taken` found (decision bench B134)
    # the junctions' running sums, rows beside _hist (decision bench B189)
    cdef public double[::1] _cs  # (public: tests/test_filter_running_sums.py reads the rows)
    cdef public Py_ssize_t _csw, _cs_off
    @cython.locals(cw=Py_ssize_t, off=Py_ssize_t, n=Py_ssize_t, i=Py_ssize_t, cs=double[::1], src=double[::1])
    cdef int _cs_room(self, Py_ssize_t last) except -1
    cdef public double _w_c1, _w_c2
    cdef public double _half, _g0, _tol_v  # kd.half, kd.g0, tol (inf: None) as C doubles (decision bench B153)
    # `_held_caps`' scratch arrays and G's tables as typed memoryviews, kept between calls (decision bench B163)
    cdef double[::1] _x_s, _x_room, _x_ct, _x_rc, _x_vb, _x_se, _x_rm, _x_e, _x_gy, _x_gg, _x_gs
    cdef double[:, ::1] _x_du, _x_w
    # `_refined`'s scratch, the same way (decision bench B187)
    cdef double[::1] _r_s, _r_vb, _r_al, _r_vt, _r_ba, _r_bj
    cdef double[:, ::1] _r_du, _r_pre, _r_sums
    cdef double _cap(self, Py_ssize_t m) except? -1.0
    cdef bint _taken(self, Py_ssize_t k) except -1
    # C calls from Limits.junction, once a pushed junction (session 28, decision bench B157)
    cpdef tuple corner_caps(self, object du, double du_n, bint lines, double acc)
    cpdef double isolated_cap(self, double du_n, double acc, double jerk, Block b1, Block b2) except? -1.0
    # window's tolerance walk, a C call from it (decision bench B171)
    cpdef Py_ssize_t _tolerance(self, object blocks, double v_hi) except -1

# `_held_caps` and `_kernel_matrix` (decision bench B133): C loops over memoryviews, declared here as
# nc.motion.cython_shadow has no memoryview types for the .py's decorators; their arrays FilterCorners' scratch, the
# product with the steps and its norms `_deviations`' C loops, the least holding cap `_least_held`'s (B163)
@cython.locals(hist=list, hs=list, nseg=Py_ssize_t, h=double, s=double[::1], t_near=double, t_ev=double,
               n0=Py_ssize_t, e0=Py_ssize_t, ne=Py_ssize_t, nn=Py_ssize_t, axes=Py_ssize_t, tol=double,
               t2sum=double, room=double[::1], nl=Py_ssize_t, i=Py_ssize_t, b=Block, nx=Block, rr=double,
               fits=bint, du=double[:, ::1], vb=double[::1], k=Py_ssize_t, a=Py_ssize_t, dv=tuple,
               se=double[::1], rm=double[::1], w=double[:, ::1], e=double[::1], c=double, r=Py_ssize_t, caps=list,
               v=double, lim=double, ct=double[::1], rc=double[::1], held=double[::1], depth=Py_ssize_t,
               i0=Py_ssize_t, u=Py_ssize_t, vt_i=double, far=double)
cdef Py_ssize_t _held_caps(FilterCorners fc, object blocks, Py_ssize_t lo, Py_ssize_t last, double s_j, double vt,
                           double half) except -1

@cython.locals(nseg=Py_ssize_t, inf=double, u=Py_ssize_t, su=double, vt_i=double, k=Py_ssize_t, x=double, c=double)
cdef int _least_held(double[::1] s, double[::1] ct, double[::1] rc, Py_ssize_t n0, double far,
                     double[::1] held) except -1

@cython.locals(nl=Py_ssize_t, nn=Py_ssize_t, axes=Py_ssize_t, order=int, r=Py_ssize_t)
cpdef int _deviations(double[:, ::1] w, double[:, ::1] du, double[::1] e) except -1

# its C loops, in the summation order probed (`_probe_order`, decision bench B163)
@cython.locals(nl=Py_ssize_t, nn=Py_ssize_t, axes=Py_ssize_t, n4=Py_ssize_t, r=Py_ssize_t, a=Py_ssize_t,
               k=Py_ssize_t, k0=Py_ssize_t, kb=Py_ssize_t, q=double, p=double, t=double, l0=double, l1=double,
               l2=double, l3=double, l4=double, l5=double, l6=double, l7=double)
cdef int _c_deviations(double[:, ::1] w, double[:, ::1] du, double[::1] e, int order) except -1

@cython.locals(ny=Py_ssize_t, ymax=double, inv=double, r=Py_ssize_t, k=Py_ssize_t, sr=double, x=double, g=double,
               j0=Py_ssize_t, v=double)
cpdef void _kernel_matrix(double[:, ::1] w, double[::1] s_rows, double[::1] s_all, double[::1] vb, double c,
                          double[::1] gy, double[::1] gg, double[::1] gs)

# `_refined` and its helpers (decision bench B133; scratch arrays, counts stepped on, B187)
@cython.locals(t1=double, t2=double, s_j=double, lo=Py_ssize_t, reach=double, n=Py_ssize_t, axes=Py_ssize_t,
               s=double[::1], vb=double[::1], du=double[:, ::1], al=double[::1], vt=double[::1], i=Py_ssize_t,
               k=Py_ssize_t, b=Block, dv=tuple, best=double, bud=double, nxt=double, v=double, ba=double[::1],
               bj=double[::1], pre=double[:, ::1], sums=double[:, ::1])
cdef tuple _refined(FilterCorners fc, list hist, Py_ssize_t h0, Py_ssize_t last, double c, double top,
                    tuple budget_a, tuple budget_j)

@cython.locals(n=Py_ssize_t, axes=Py_ssize_t, i=Py_ssize_t, k=Py_ssize_t, j=Py_ssize_t, x=double, m=double,
               peak=double, q=double, r=double, vw=double, ca=double, cd=double)
cdef double _cap_at(double v, double t1, double t2, double s_j, double[::1] s, double[::1] vb, double[:, ::1] du,
                    double[::1] al, double[::1] vt, double[::1] ba, double[::1] bj, double[:, ::1] pre,
                    double[:, ::1] sums) except? -1.0

@cython.locals(w1=double, w2=double, top=double, k=Py_ssize_t, i=Py_ssize_t, e=double, x=double,
               ends="Py_ssize_t[::1]")
cdef int _window_sums(double vw, double t1, double t2, double s_j, double[::1] s, double[:, ::1] pre,
                      double[:, ::1] sums, Py_ssize_t row) except -1

@cython.locals(x=double)
cdef int _series_window(double e, double s_j, double top, double w1, double w2, double[::1] s, double[:, ::1] pre,
                        double[:, ::1] sums, Py_ssize_t row, Py_ssize_t[::1] ends, Py_ssize_t c) except -1

@cython.locals(k=Py_ssize_t, mid=double, a=double, d=double, q=double)
cdef int _window_max(double[:, ::1] pre, double[:, ::1] sums, Py_ssize_t row, Py_ssize_t i0, Py_ssize_t i1,
                     Py_ssize_t i2) except -1

@cython.locals(n=Py_ssize_t)
cdef Py_ssize_t _count_from(double[::1] s, double x, Py_ssize_t k) except -1

@cython.locals(lo=Py_ssize_t, hi=Py_ssize_t, mid=Py_ssize_t)
cdef Py_ssize_t _count_at_or_below(double[::1] s, double x) except -1
