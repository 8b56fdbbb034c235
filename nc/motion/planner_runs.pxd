# Types for nc/motion/planner_runs.py where setup.py compiles it with Cython (issue 17, decision bench B115).
from nc.motion.block cimport Block
from nc.motion.plan_core cimport PlanCore
# the run feed and the line segment as C calls (session 29, decision bench B166)
from nc.motion.path cimport line_segment
from nc.motion.spline_feed cimport RunFeed
