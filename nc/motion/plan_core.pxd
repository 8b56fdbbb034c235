# Types for nc/motion/plan_core.py where setup.py compiles it with Cython (issue 17, session 30, decision bench B172):
# the planner's hot fields as C fields of its extension-type base. A field added here goes in plan_core.py's
# DOUBLES/COUNTS/CORE and its _fields/_set_fields too (the state API saves every field).

cdef class PlanCore:
    cdef public double s
    cdef public double v
    cdef public double a
    cdef public double _carry
    cdef public double _path_s
    cdef public double _jf
    cdef public double _end_cap
    cdef public double _feed_ovr
    cdef public double _rapid_ovr
    cdef public double dry_run_feed
    cdef public double _t_step
    cdef public double _lam
    cdef public Py_ssize_t _buf_i
    cdef public Py_ssize_t _buf_popped
    cdef public Py_ssize_t _pushes
    cdef public Py_ssize_t _pushed
    cdef public Py_ssize_t _need
    cdef public Py_ssize_t threads_queued
    cdef public Py_ssize_t solves
    cdef public bint _started
    cdef public bint held
    cdef public bint _stopping
    cdef public bint dry_run
    cdef public bint _closed
    cdef public bint _filling
    cdef public bint _integrate_angle
    cdef public object plan
    cdef public object blocks
    cdef public object lim
    cdef public object cfg
    cdef public object axes
    cdef public object position
    cdef public object output
    cdef public object _buf_pos
    cdef public object _buf_vel
    cdef public object _buf_line
    cdef public object _buf_state
    cdef public object _buf_blk
    cdef public object _buf_carry
    cdef public object _zones
    cdef public object filter
    cdef public object _fs_tail
    cdef public object _fr_plan
    cdef public object _cont
    cdef public object _runs
    cdef public object _held
    cdef public object line
    cdef public object depth
    cdef public object _batch
    cdef public object _seg_hist
    cdef public object _axis_v