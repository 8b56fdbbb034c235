# Types for nc/motion/planner_corners.py where setup.py compiles it with Cython (issue 17, decision bench B136).
# `_corner` and its helpers are C functions (`Planner._push` calls `_corner_at` in C), and they call the share zones,
# the junction model and `change_distance` in C (session 28, decision bench B157).
from nc.motion.block cimport Block
from nc.motion.plan_core cimport PlanCore
from nc.motion.lookahead cimport Limits, change_distance
from nc.motion.share_zones cimport ShareZones

cpdef Py_ssize_t _corner_at(object pl, Block prev, Block b) except -1
cdef bint _blend_room(object pl, Block prev) except -1
cdef double _path_now(object pl) except? -1.0
