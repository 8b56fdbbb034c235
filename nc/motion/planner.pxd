# Types for nc/motion/planner.py where setup.py compiles it with Cython (issue 17, decision bench B115). `_push`
# calls the junction model, the corner and the share zones in C (session 28, decision bench B157).
cimport cython
from nc.motion.blending cimport FilterCorners
from nc.motion.block cimport Block, new_block
from nc.motion.path cimport Segment
from nc.motion.plan_core cimport PlanCore
from nc.motion.profile cimport fits_queue, later, time_at  # the kept profile's checks in C (session 31, bench B184)
from nc.motion.lookahead cimport Limits, backward
from nc.motion.planner_corners cimport _corner_at
from nc.motion.share_zones cimport ShareZones
from nc.motion.shares cimport jerk_factor

# Planner._jerk_factor and _factor_over's work in C (session 29, decision bench B164)
@cython.locals(start=double, span=double, zones=ShareZones, blend=FilterCorners)
cdef tuple _factor_span(object planner, Limits lim, Block b, double s, double dist)

# Planner._start_plan's `_near` on the segment's kept floats, a C loop (session 31, decision bench B186)
@cython.locals(k=Py_ssize_t, x=double, y=double)
cdef bint _near_floats(list a, list b) except -1

# Planner._update_cap's work in C, the push's call (session 31, decision bench B181)
@cython.locals(cap=double, x=double, feed=double)
cdef double _cap_of(PlanCore self, Block b, object rpm) except? -1.0

# Planner._run_target's work in C, called so from `_plan_path`, `_run_through` and `_jerk_factor` (session 31, B204)
@cython.locals(b=Block, nx=Block, dist=double, ra=double, rj=double, vmax=double, cap_lo=double, x=double,
               k=Py_ssize_t, kmax=Py_ssize_t)
cdef tuple _target_run(PlanCore self, double cap, bint extend, double cruise_from, double jf, double through,
                       object limit)
