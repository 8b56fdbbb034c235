# Types for nc/motion/planner_corners.py where setup.py compiles it with Cython (issue 17, decision bench B136).
from nc.motion.block cimport Block
