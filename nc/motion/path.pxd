# Types for nc/motion/path.py where setup.py compiles it with Cython (issue 17, decision bench B136).
