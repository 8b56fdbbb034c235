# Types for virtual_bus/drive_kernel.py when setup.py compiles it with Cython (issue 17): the floats become C
# doubles, each operation the same IEEE one Python does (setup.py turns fused multiply-add off). The .py is the
# source of truth and runs as it is where nothing was compiled.
cimport cython

cdef long SW_TARGET_REACHED
cdef long RAW_MAX
cdef double _EXACT

# the feedback columns of a stretch (virtual_bus/drive_stretch.py re-exports it): typed fields, which the kernels
# read and write as C fields (decision bench B196)
cdef class Stretch:
    cdef public Py_ssize_t done
    cdef public list position_actual, velocity_actual, torque_actual, following_error, statusword
    cdef public object last
    cdef public double limit
    cdef public Py_ssize_t over_at

@cython.locals(i=Py_ssize_t, k=Py_ssize_t, cpu=double, o=double, t=list)
cpdef to_counts(list rows, Py_ssize_t c, list scales, list targets)

@cython.locals(k=int, cmd=double, v_cmd=double, neg=double, inside=bint)
cpdef tuple csp_substeps(int n, double h, double prev, double span, double kff_ff, double kp, double pos,
                         double vel, double t, double max_cps, double alpha, bint limited, double lo, double hi)

@cython.locals(_k=int, cmd=double, v_cmd=double, neg=double, edge=bint, new_pos=double)
cpdef tuple csv_substeps(int n, double h, double ramp, double want, double tv, double pos, double vel, double t,
                         double max_cps, double alpha, long every)

cpdef tuple csp_cycles(object targets, tuple consts, tuple state, object still, Stretch out)

# a CSP drive between the parts of a stretch (decision bench B198): its constants and state as C fields
cdef class CspCore:
    cdef public int n
    cdef public double h, max_cps, alpha, rad, reached_v, kp, kff, window, origin, k_raw, t_pct, inertia, viscous
    cdef public double coulomb, rated, lo, hi, dt
    cdef public long base
    cdef public bint limited
    cdef public double pos, vel, t, command, last_target, acc, torque
    cdef public bint has_prev, ok
    cdef public object still
    cdef public Py_ssize_t lag
    cdef public Stretch out

    cpdef set_state(self, tuple state)
    cpdef tuple state(self)
    @cython.locals(k=Py_ssize_t)
    cpdef step(self, list targets, Py_ssize_t a, Py_ssize_t b)
    cpdef settle(self)
    @cython.locals(n=int, h=double, max_cps=double, alpha=double, rad=double, reached_v=double, kp=double, kff=double,
                   window=double, origin=double, k_raw=double, t_pct=double, inertia=double, viscous=double,
                   coulomb=double, rated=double, lo=double, hi=double, base=long, dt=double, limited=bint,
                   pos=double, vel=double, t=double, command=double, acc=double, torque=double, over=double,
                   ok=bint, rep=Py_ssize_t, target=double, prev=double, ff_vel=double, kff_ff=double, span=double,
                   c_pos=double, c_vel=double, c_t=double, cmd=double, inside=bint, c_acc=double,
                   gap=double, moved=bint, pa=list, va=list, ta=list, fe=list, sws=list, lim=double, first=Py_ssize_t,
                   v_raw=long, neg=double, has_prev=bint, last_target=double, k=int, j=Py_ssize_t, out=Stretch,
                   v_cmd=double)
    cpdef bint cycles(self, list targets, Py_ssize_t a, Py_ssize_t b) except? False

@cython.locals(m=Py_ssize_t, i=Py_ssize_t, core=CspCore, out=Stretch)
cpdef Py_ssize_t drive_parts(list runs, list targets, Py_ssize_t a, Py_ssize_t upto, Py_ssize_t n_axes) except? -1

@cython.locals(n=int, h=double, max_cps=double, alpha=double, rad=double, reached_v=double, origin=double,
               ramp=double, want=double, every=long, k_raw=double, t_pct=double, inertia=double, viscous=double,
               coulomb=double, rated=double, base=long, dt=double, pos=double, vel=double, t=double,
               command=double, tv=double, acc=double, torque=double, neg=double, over=double, ok=bint,
               c=Py_ssize_t, v_cmd=double, c_acc=double, c_torque=double, done=Py_ssize_t, c_pos=double,
               c_vel=double, c_t=double, c_tv=double, cmd=double, edge=bint, moved=bint,
               pa=list, va=list, ta=list, sws=list)
cpdef tuple csv_cycles(Py_ssize_t cycles, tuple consts, tuple state, bint still, Stretch out)

@cython.locals(_k=Py_ssize_t)
cpdef double repeat(Stretch out, double t, double h, int n, bint csp, Py_ssize_t times) except? -1.0

@cython.locals(done=Py_ssize_t, c_pos=double, c_t=double, cmd=double, edge=bint, _k=int, new_pos=double,
               pa=list, va=list, ta=list, sws=list)
cpdef tuple at_speed(Stretch out, Py_ssize_t cycles, double pos, double t, double command, double dp, double h,
                     int n, long every, object va_raw, object ta_raw, long base, bint slow, double origin)

@cython.locals(f=double, d=double)
cpdef object nearest(double x)

cpdef double coulomb_of(double coulomb, double vel)
