# Types for nc/motion/planner.py where setup.py compiles it with Cython (issue 17, decision bench B115). `_push`
# calls the junction model, the corner and the share zones in C (session 28, decision bench B157).
from nc.motion.block cimport Block
from nc.motion.lookahead cimport Limits
from nc.motion.planner_corners cimport _corner_at
from nc.motion.share_zones cimport ShareZones
