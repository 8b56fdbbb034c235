# Types for nc/motion/shares.py where setup.py compiles it with Cython (issue 17, decision bench B115). The scan's
# helpers are C functions on C doubles and indices (session 27, decision bench B140): each comparison the one the
# builtins they replace (max, bisect_left, bisect_right) make on the same floats. FilterCorners is not cimported:
# nc.motion.blending imports MAX_FACTOR from here, so shares' import would import it half-made.
cimport cython
from nc.motion.block cimport Block
from nc.motion.profile cimport _first_above

cdef double _INF  # math.inf as a C constant

@cython.locals(x=double, m=double, k=Py_ssize_t)
cdef double _largest(list xs, Py_ssize_t lo, Py_ssize_t hi) except? -1.0

@cython.locals(lo=Py_ssize_t, hi=Py_ssize_t, mid=Py_ssize_t, y=double)
cdef Py_ssize_t _first_at_or_above(list xs, double x) except -1


cdef tuple _joined(Py_ssize_t lo, Py_ssize_t hi, Py_ssize_t k_lo, Py_ssize_t k_hi)
