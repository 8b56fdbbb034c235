# Types for nc/motion/sample_rows.py where setup.py compiles it with Cython (issue 17, decision bench B115).
cimport cython

# Piecewise.at's steps, called in C (session 29, decision bench B169)
from nc.motion.profile cimport _lists0, _pos_at, _row_at
