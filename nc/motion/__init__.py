"""Motion: path geometry, jerk-limited profiles along the path (ruckig, 1 DoF), per-cycle setpoints."""

import nc.motion.compiled  # noqa: F401  (first: it decides whether the planner's builds or sources load, B115)
from nc.motion.limits import AxisLimits, MotionConfig


def __getattr__(name: str):
    """Planner and Setpoint load on first use: the planner pulls numpy and ruckig, which a bench
    description (hil.bench, nc.motion.limits) and `hil path` do not need (issue 16, start-up)."""
    if name in ("Planner", "Setpoint"):
        from nc.motion import planner
        return getattr(planner, name)
    raise AttributeError(f"module 'nc.motion' has no attribute {name!r}")

__all__ = ["AxisLimits", "MotionConfig", "Planner", "Setpoint"]
