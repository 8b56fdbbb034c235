"""Per-axis kinematic limits and planner settings."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class AxisLimits:
    max_velocity: float = 400.0  # mm/s (or deg/s) — also the interpolated rapid speed of the axis
    max_acceleration: float = 4000.0  # mm/s²
    max_jerk: float = 200_000.0  # mm/s³


@dataclass
class MotionConfig:
    cycle: float = 0.001  # s
    axes: tuple[str, ...] = ("X", "Z")
    limits: dict[str, AxisLimits] = field(default_factory=dict)

    def limit(self, axis: str) -> AxisLimits:
        return self.limits.get(axis, AxisLimits())
