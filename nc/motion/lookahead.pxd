# Types for nc/motion/lookahead.py where setup.py compiles it with Cython (issue 17, decision bench B115). The
# passes' constants are C doubles and their square root C's (session 27, decision bench B148): math.sqrt calls the
# same C sqrt, and _sqrt raises its ValueError below 0.
from nc.motion.block cimport Block

cdef double _MARGIN
cdef double _INF

cdef double _sqrt(double x) except? -1.0
