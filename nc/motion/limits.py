"""Per-axis kinematic limits and planner settings."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

# The most a solve raises the tangential jerk (2: the whole corner and curvature share; decision motion 39). Here, not
# in nc.motion.shares whose constant it is (it imports it from here): nc.motion.blending uses it and shares cimports
# blending's FilterCorners where compiled, so blending must not import shares (session 31, decision bench B182).
MAX_FACTOR = 2.0

@dataclass(frozen=True)
class AxisLimits:
    max_velocity: float = 400.0  # mm/s (or deg/s) — also the interpolated rapid speed of the axis
    max_acceleration: float = 4000.0  # mm/s²
    max_jerk: float = 200_000.0  # mm/s³


@dataclass(frozen=True)
class MoveKindLimits:
    """An NC5 channel's limits for one kind of move (decision motion 90): G00 N1.030-N1.032, cutting
    N1.033-N1.035 (its speed is `MotionConfig.max_feed`, applied to the programmed F). None: not set, the
    planner's own (the axis limits) in force; a time of 0 sets no limit either."""

    speed: float | None = None  # mm/s along the path (N1.030 / 60)
    acc_time: float | None = None  # s from rest to `speed` (N1.031, N1.034): acceleration = speed / acc_time
    scurve_time: float | None = None  # s the acceleration takes to build up (N1.032, N1.035): jerk = acc / it

    @property
    def set(self) -> bool:
        return self.speed is not None or self.acc_time is not None or self.scurve_time is not None

    @property
    def own_budget(self) -> bool:
        """An acceleration or S-curve time is given: the move's acceleration is the parameters' (decision 91)."""
        return self.acc_time is not None or self.scurve_time is not None


def acceleration(speed: float | None, acc_time: float | None) -> float:
    """speed / acc_time (the manual's own reading of an "acc. and dec. time", N§3.5.4 (4)-(5): N1.033 / N1.028,
    N2.020 / N2.021); inf where either is missing or the time is 0."""
    if speed is None or not acc_time:
        return math.inf
    return speed / acc_time


def jerk_per_acc(scurve_time: float | None) -> float:
    """1 / S-curve time: jerk = acceleration · this; inf (no limit) where missing or 0."""
    return 1.0 / scurve_time if scurve_time else math.inf


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
    # NC5 G00 rapid (N1.030-N1.032) and cutting (N1.034/N1.035 over N1.033 = max_feed) limits, and each axis's
    # G00 rapid limits N2.020-N2.022 (speed mm/s, times s): decisions motion 90-94. Unset: today's planning.
    rapid: MoveKindLimits = field(default_factory=MoveKindLimits)
    cutting: MoveKindLimits = field(default_factory=MoveKindLimits)
    axis_rapid: dict[str, MoveKindLimits] = field(default_factory=dict)

    @property
    def rapid_whole(self) -> bool:
        """A G00 runs on the axes' whole acceleration and jerk, not the tangential share (decision motion 91):
        an acc. and dec. or S-curve time is set, for the path (N1.031/N1.032) or an axis (N2.021/N2.022)."""
        return self.rapid.own_budget or any(k.own_budget for k in self.axis_rapid.values())

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
