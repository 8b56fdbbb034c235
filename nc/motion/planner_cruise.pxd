# Types for nc/motion/planner_cruise.py where setup.py compiles it with Cython (issue 17, decision bench B115).
from nc.motion.block cimport Block
from nc.motion.plan_core cimport PlanCore
from nc.motion.sample_rows cimport slab_rows

cdef bint _cruises(Block b, double v) except -1

# a buffer row handed out (CruiseSampling._take), in C from cut_rows and Planner._step_path (bench B190)
cdef int _take_row(PlanCore pl, Py_ssize_t i) except -1
