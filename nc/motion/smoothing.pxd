# Types for nc/motion/smoothing.py where setup.py compiles it with Cython (issue 17, decision bench B115).
