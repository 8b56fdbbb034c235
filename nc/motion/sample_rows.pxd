# Types for nc/motion/sample_rows.py where setup.py compiles it with Cython (issue 17, decision bench B115).
cimport cython

@cython.locals(s=double)
cdef tuple _row(dict rows, object pw, double t, double base, Py_ssize_t i)
