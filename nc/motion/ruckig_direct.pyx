# distutils: language = c++
"""ruckig's C++ called directly for the planner's 1-DoF solves (issue 17, decision bench B162).

nc/motion/profile.py solves each path and velocity ramp through ruckig's Python module; two thirds of such a solve
was pybind writing the input's fields and copying the Trajectory's profiles out (session 28). `solve` does the same
calculation (ruckig_direct.hpp: validate, the state-to-state calculator, profile.py's two retries) on ruckig's own
C++ (libruckig.a and the headers of the ruckig that setup.py found) and reads the phases out as profile.py's
`_phases` does, so the answers are the same bits. RUCKIG_VERSION is the ruckig it was built against:
nc/motion/compiled.py uses it only where the ruckig imported at run time is that version.
"""

from cpython.list cimport PyList_New, PyList_SET_ITEM
from cpython.ref cimport Py_INCREF
from libcpp cimport bool as cbool

cdef extern from "ruckig_direct.hpp" namespace "deltahil":
    cdef cppclass OneDof:
        OneDof() except +
        int n
        double t0[10]
        double p[10]
        double v[10]
        double a[10]
        double j[10]
        double duration
        double p_max
        cbool solve(cbool velocity, double p0, double v0, double a0, double p1, double v1, double v_max,
                    double a_max, double j_max) except +

cdef extern from *:
    const char* RUCKIG_BUILT_VERSION  # setup.py's define: the ruckig whose headers and library were compiled in

RUCKIG_VERSION: str = RUCKIG_BUILT_VERSION.decode()

# One calculator, input and trajectory for the process, as profile.py pools its Python ones: ruckig's velocity control
# leaves the trajectory's final position (pf) as the solve before set it, and the extrema (p_max) include it, so
# every 1-DoF solve goes through the same trajectory in the same order either way (profile.solve_axes with one axis)
cdef OneDof* _one = new OneDof()


def reset() -> None:
    """A new calculator, input and trajectory, as a fresh process has (the tests compare sequences of solves)."""
    global _one
    cdef OneDof* old = _one
    _one = new OneDof()
    del old


cdef list _row(double* xs, int n):
    # the list sized once and each float set in place, not appended (session 31, decision bench B204)
    cdef list out = PyList_New(n)
    cdef object x
    cdef int k
    for k in range(n):
        x = xs[k]
        Py_INCREF(x)  # PyList_SET_ITEM steals the reference that `x` keeps
        PyList_SET_ITEM(out, k, x)
    return out


def solve(bint velocity, double p0, double v0, double a0, double p1, double v1, double v_max, double a_max,
          double j_max):
    """(p0, v0, a0) → (p1, v1, 0) within the limits, to the target velocity only where `velocity`: the phases as
    profile.py's `_phases` gives them ((t0, p, v, a, j) lists), the duration and the highest position, or None where
    ruckig cannot solve it (after profile.py's `_calculate` retries)."""
    cdef OneDof* o = _one
    if not o.solve(velocity, p0, v0, a0, p1, v1, v_max, a_max, j_max):
        return None
    cdef int n = o.n
    return (_row(o.t0, n), _row(o.p, n), _row(o.v, n), _row(o.a, n), _row(o.j, n)), o.duration, o.p_max
