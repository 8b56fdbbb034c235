# Types for nc/motion/smoothing.py where setup.py compiles it with Cython (issue 17, decision bench B115): the
# position filter is a cdef class whose state is one buffer of C doubles read through a typed memoryview, its push
# a C loop over them with the same IEEE operations in the same order (decision bench B141; setup.py turns fused
# multiply-add off). The .py is the source of truth and runs as it is where nothing was compiled.
cimport cython

cdef Py_ssize_t LAST, S1, S2, REC, W1

cdef class PositionFilter:
    cdef readonly Py_ssize_t n1, n2, span, _still
    cdef Py_ssize_t _lag, _m, _h1, _h2
    cdef object _st  # the array.array that holds the state
    cdef double[::1] _v  # a view of it
    cdef int _fill(self) except -1
    @cython.locals(g=PositionFilter)
    cpdef PositionFilter copy(self)
    cdef list _push(self, list row, double lam)
    cdef int _take(self, bint same, double lam) except -1
    @cython.locals(xv=double[:, ::1], ov=double[:, ::1], lv=double[::1], k=Py_ssize_t, i=Py_ssize_t, n=Py_ssize_t,
                   m=Py_ssize_t, r=Py_ssize_t, same=bint)
    cdef int _many(self, object xs, object lam, object out) except -1
