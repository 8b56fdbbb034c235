# Types for nc/motion/shares.py where setup.py compiles it with Cython (issue 17, decision bench B115). The scan's
# helpers are C functions on C doubles and indices (session 27, decision bench B140): each comparison the one the
# builtins they replace (max, bisect_left, bisect_right) make on the same floats. FilterCorners is cimported (session
# 31, decision bench B182): its fields the scan reads (_sc, _hist, _sc_ok, …) are C reads; blending imports nothing
# from here (MAX_FACTOR lives in nc.motion.limits), so importing shares first imports blending whole.
cimport cython
from nc.motion.block cimport Block
from nc.motion.blending cimport FilterCorners as _FilterCorners
from nc.motion.profile cimport _at_or_above, _first_above

cdef double _INF  # math.inf as a C constant

@cython.locals(x=double, m=double, k=Py_ssize_t)
cdef double _largest(list xs, Py_ssize_t lo, Py_ssize_t hi) except? -1.0



cdef tuple _joined(Py_ssize_t lo, Py_ssize_t hi, Py_ssize_t k_lo, Py_ssize_t k_hi)

# The scan's steps as C calls (session 29, decision bench B164): Python calls, their float arguments boxed and
# unpacked each time, from the planner's `_factor_over` to jerk_factor, _scan, _verdicts and _tolerance_free. cpdef:
# the tests call them from Python too; the planner cimports jerk_factor. _verdicts' NONE and SKIP stay the objects
# stored in the verdict list (`none`, `skip`: no new float a store).
@cython.locals(st=double, pool=double, t_w=double, v_hi=double, x=double, reach=double, use=double, seen=double,
               f=double, saturates=bint, head=Block, tail=Block, v_stop=double)
cpdef tuple jerk_factor(object cfg, _FilterCorners fc, object blocks, double pos, double run_end, bint closed)

@cython.locals(hi=double, seen=double, stop_s=double, s_end=double, vt=double, use=double, top=double, x=double,
               m=double, y=double, none=double, covered=bint, plain=bint, stop=bint, i=Py_ssize_t, k=Py_ssize_t,
               k_lo=Py_ssize_t, k_hi=Py_ssize_t, q_lo=Py_ssize_t, q_hi=Py_ssize_t, n_pre=Py_ssize_t, b=Block,
               last=Block, sc=list, vts=list, hist_s=list)
cpdef object _scan(_FilterCorners fc, object blocks, double pos, double run_end, double reach, bint closed,
                   double v_stop=*)

@cython.locals(n=Py_ssize_t, d=Py_ssize_t, ok_lo=Py_ssize_t, ok_hi=Py_ssize_t, k=Py_ssize_t, i=Py_ssize_t,
               n_ends=Py_ssize_t, h=Py_ssize_t, j=Block, b=Block, head=Block, vbud=double, cap=double, c2=double,
               tcap=double, r=double, s_j=double, x=double, sc=list, ends=list, hist=list)
cpdef list _verdicts(_FilterCorners fc, object blocks, Py_ssize_t k_lo, Py_ssize_t k_hi, Py_ssize_t n_pre)

@cython.locals(b=Block, k=Py_ssize_t, cap=double, c2=double, tcap=double, unb=double, x=double, ok=bint, tol=double)
cpdef bint _tolerance_free(_FilterCorners fc, Block j, object blocks, list ends) except -1
