# Types for nc/motion/block.py where setup.py compiles the planner's hot modules with Cython (issue 17, decision
# bench B115): Block becomes an extension type whose float fields are C doubles, read by the compiled modules
# without a dictionary lookup. The .py is the source of truth and runs as it is where nothing was compiled.

cdef class Block:
    cdef public object move
    cdef public str kind
    cdef public object seg
    cdef public double length
    cdef public double cap_hard
    cdef public double a
    cdef public double j
    cdef public object feed
    cdef public bint rapid
    cdef public double cap
    cdef public double vjunc
    cdef public double vend
    cdef public double anchor_v
    cdef public double anchor_d
    cdef public double anchor_a
    cdef public double anchor_j
    cdef public bint binding
    cdef public double s_end
    cdef public object du
    cdef public double du_n
    cdef public double vtop
    cdef public tuple dv
    cdef public double vbase
    cdef public double ctol
    cdef public double vtol
    cdef public double vbud
    cdef public double vctol
    cdef public double viso
    cdef public double tf_cap
    cdef public double tf_tcap
    cdef public bint tf_ok
    cdef public double trim0
    cdef public bint scan_plain

cdef double _INF, _NAN

# Block(...) as a C call (session 29, decision bench B166)
cpdef Block new_block(object move, str kind, object seg, double length, double cap_hard, double a, double j,
                      object feed, bint rapid)
