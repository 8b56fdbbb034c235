# Types for nc/motion/sample_rows.py where setup.py compiles it with Cython (issue 17, decision bench B115).
