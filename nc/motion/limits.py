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
    # Look-ahead depth in blocks; None = max(100, v_max / (2·a_max·T)) (LinuxCNC's sizing rule).
    lookahead: int | None = None
    # G64 path tolerance (mm) at corners; None = no tolerance limit (best speed), 0 = stop at every corner.
    path_tolerance: float | None = None
    # N1.20 bit 18: 0 = G00 interpolated along a line, 1 = every axis independently at its own speed.
    rapid_independent: bool = False
    # P315 / 0 % rapid override: the slow rapid speed, mm/s along the path.
    slow_rapid: float = 10.0
    # Each segment lasts at least this many cycles (LinuxCNC TP_MIN_SEGMENT_CYCLES).
    min_segment_cycles: float = 1.02
    # Shares of each axis' acceleration and jerk budget: tangential path profile, corner
    # (tangent jumps at junctions) and curvature (arcs, curvature jumps). They add up to 1 so the
    # setpoint stream stays inside the axis limits when all three act in the same cycle.
    share_tangential: float = 0.5
    share_corner: float = 0.25
    share_curvature: float = 0.25
    # Post-interpolation position filter (nc.motion.smoothing): N1.036 look-ahead filter time and
    # N1.037 look-ahead S-curve time, in seconds; 0 leaves that stage out. With the filter on,
    # corners are limited by what the filter turns a tangent jump into (and by path_tolerance),
    # not by a one-cycle velocity step.
    filter_time: float = 0.0
    filter_scurve: float = 0.0
    # Runs of short feed lines fitted as one curve within path_tolerance (nc.motion.spline_feed, issue 18).
    fit_runs: bool = True
    # N1.033 cutting command maximum feed (mm/min): the programmed F of a G94 feed move is limited to it before
    # the feed override (the channel applies it: nc.channel; decision language L25-1). None: no limit.
    max_feed: float | None = None

    def filter_cycles(self) -> tuple[int, int]:
        """Window lengths (cycles) of the two moving averages; (1, 1) = no filter."""
        return (max(1, round(self.filter_time / self.cycle)), max(1, round(self.filter_scurve / self.cycle)))

    @property
    def filtered(self) -> bool:
        return self.filter_cycles() != (1, 1)

    def limit(self, axis: str) -> AxisLimits:
        return self.limits.get(axis, AxisLimits())

    def lookahead_depth(self) -> int:
        if self.lookahead is not None:
            return max(1, int(self.lookahead))
        n = 0.0
        for a in self.axes:
            lim = self.limit(a)
            n = max(n, lim.max_velocity / (2.0 * lim.max_acceleration * self.cycle))
        return max(100, int(n + 0.999))
