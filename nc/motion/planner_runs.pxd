# Types for nc/motion/planner_runs.py where setup.py compiles it with Cython (issue 17, decision bench B115).
from nc.motion.block cimport Block
