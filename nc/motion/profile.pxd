# Types for nc/motion/profile.py where setup.py compiles it with Cython (issue 17, decision bench B115). A solve's
# own steps are C functions (session 27, decision bench B140): the calls between them were Python calls, and the
# phases' start times are summed on a C double in the order the .py sums them.
cimport cython
from nc.motion.block cimport Block

cdef tuple _calc(Py_ssize_t dofs)

cdef inline bint _same(double x, double y)

cdef double _S0, _S1, _S2, _S3, _S4, _S5, _S6, _S7  # solve_position's last inputs
cdef object _S_PW

@cython.locals(w=list)
cdef tuple _one_dof(object interface, double p0, double v0, double a0, double p1, double v1, double v_max,
                    double a_max, double j_max)

cdef object _calculate(object otg, object inp, Py_ssize_t n)

cdef object _of(object traj, object cls)

@cython.locals(x=double, k=Py_ssize_t)
cdef double _gather(double t, Py_ssize_t n, object pt, object pp, object pv, object pa, object pj, list t0, list p,
                    list v, list a, list j) except? -1.0

@cython.locals(t=double, h=double, pl=double, vl=double, al=double, jl=double, pe=double,
               ve=double, ae=double, t0=list, p=list, v=list, a=list, j=list)
cdef tuple _phases(object pr)

@cython.locals(lo=Py_ssize_t, hi=Py_ssize_t, mid=Py_ssize_t, y=double)
cpdef Py_ssize_t _first_above(list xs, double x) except -1

@cython.locals(mid=Py_ssize_t, y=double)
cpdef Py_ssize_t _at_or_above(list xs, double x, Py_ssize_t lo, Py_ssize_t hi) except -1

# Piecewise.at's steps as C functions (session 29, decision bench B169): sample_rows takes the lists once and probes
# on C doubles; cpdef so sample_rows imports them as Python too (run without Cython).
cpdef tuple _lists0(object pw)

@cython.locals(dt=double, jk=double, ak=double, vk=double, pk=double, x=double, k=Py_ssize_t)
cpdef double _pos_at(double t, double dur, list t0, list p, list v, list a, list j) except? -1.0

@cython.locals(dt=double, jk=double, ak=double, vk=double, pk=double, x=double, k=Py_ssize_t)
cpdef tuple _row_at(double t, double base, double dur, list t0, list p, list v, list a, list j)

# A kept profile's checks as C functions (nc.motion.hold_stop re-exports them; session 31, decision bench B184)
@cython.locals(c=tuple, hi=double, t=double, ps=double, vs=double, r=tuple, i=Py_ssize_t)
cpdef double time_at(object pw, double x, double lo=*) except? -1.0

@cython.locals(c=tuple, t0=list, a=list, j=list, dur=double, top=double, x=double, lo=double, hi=double, tz=double,
               jk=double, k=Py_ssize_t, n=Py_ssize_t)
cpdef double peak_speed(object pw, double t) except? -1.0

@cython.locals(top=double, at=double, b=Block)
cpdef bint fits_queue(object pw, double t, double end, object blocks) except -1

@cython.locals(c=tuple, t0=list)
cpdef object later(object pw, double t)
