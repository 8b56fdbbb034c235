"""Motion: path geometry, jerk-limited profiles along the path (ruckig, 1 DoF), per-cycle setpoints."""

from nc.motion.limits import AxisLimits, MotionConfig
from nc.motion.planner import Planner, Setpoint

__all__ = ["AxisLimits", "MotionConfig", "Planner", "Setpoint"]
