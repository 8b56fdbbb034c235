"""The planner: a queue of moves turned into one setpoint per bus cycle.

The foundation plans every move from rest to rest (exact stop); look-ahead blending across
blocks is layered on the same queue/segment/profile split.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from nc.alarms import NcAlarm
from nc.motion.limits import MotionConfig
from nc.motion.path import Segment
from nc.motion.profile import PathProfile, solve
from nc.moves import Move


@dataclass
class Setpoint:
    positions: np.ndarray  # machine coordinates per axis, in MotionConfig.axes order
    line: int  # program line of the active move (0 when idle before any move)
    path_velocity: float  # mm/s along the path
    move: Move | None


@dataclass
class _Active:
    move: Move
    segment: Segment | None  # None for a dwell
    profile: PathProfile | None
    duration: float
    t: float = 0.0
    stopping: bool = False  # the profile ends short of the segment end (controlled stop)


class Planner:
    def __init__(self, cfg: MotionConfig, start: dict[str, float] | None = None,
                 spindle_rpm: Callable[[], float] | None = None) -> None:
        self.cfg = cfg
        self.axes = cfg.axes
        self.position = np.array([(start or {}).get(a, 0.0) for a in self.axes], dtype=float)
        self.queue: deque[Move] = deque()
        self.active: _Active | None = None
        self.spindle_rpm = spindle_rpm or (lambda: 0.0)
        self.line = 0
        self._vmax = np.array([cfg.limit(a).max_velocity for a in self.axes])
        self._amax = np.array([cfg.limit(a).max_acceleration for a in self.axes])
        self._jmax = np.array([cfg.limit(a).max_jerk for a in self.axes])

    # ---- queue ----------------------------------------------------------------------------
    def push(self, move: Move) -> None:
        self.queue.append(move)

    @property
    def idle(self) -> bool:
        return self.active is None and not self.queue

    def reset_position(self, pos: dict[str, float]) -> None:
        """Take over the actual position (after enable, or after a stop)."""
        self.position = np.array([pos.get(a, 0.0) for a in self.axes], dtype=float)

    # ---- per cycle ------------------------------------------------------------------------
    def step(self) -> Setpoint:
        dt = self.cfg.cycle
        carry = dt
        velocity = 0.0
        while carry > 0.0:
            if self.active is None:
                if not self.queue:
                    break
                self.active = self._start(self.queue.popleft())
            act = self.active
            act.t += carry
            if act.t >= act.duration - 1e-12:
                carry = act.t - act.duration
                self._finish(act)
                self.active = None
                if carry <= 1e-12:
                    break
                continue
            carry = 0.0
            if act.segment is not None and act.profile is not None:
                s, velocity, _ = act.profile.at(act.t)
                self.position = act.segment.points(np.array([s]))[0]
        move = self.active.move if self.active else None
        return Setpoint(self.position.copy(), self.line, velocity, move)

    def stop(self) -> None:
        """Controlled stop: decelerate along the current path at the path limits, then flush the queue."""
        self.queue.clear()
        act = self.active
        if act is None or act.segment is None or act.profile is None:
            self.active = None
            return
        s, v, a = act.profile.at(act.t)
        if v <= 1e-9:
            self.active = None
            return
        _, amax, jmax = self._limits(act.move, act.segment)
        s_end, traj = _stop_profile(s, v, a, amax, jmax)
        if s_end >= act.segment.length:
            return  # the segment already ends at rest sooner than a fresh stop would
        # The stop trajectory starts at the current absolute path length s, so it samples in place.
        self.active = _Active(act.move, act.segment, PathProfile(s_end, traj.duration, traj), traj.duration,
                              stopping=True)

    def _finish(self, act: _Active) -> None:
        if act.segment is None:
            return
        if act.stopping and act.profile is not None:
            self.position = act.segment.points(np.array([act.profile.length]))[0]
        else:
            self.position = act.segment.end.copy()

    def _start(self, move: Move) -> _Active:
        self.line = move.line
        if move.kind == "dwell":
            return _Active(move, None, None, float(move.duration or 0.0))
        seg = Segment.of(move, self.axes)
        seg.start = self.position.copy() if np.allclose(seg.start, self.position, atol=1e-6) else seg.start
        if seg.length < 1e-9:
            return _Active(move, None, None, 0.0)
        v, a, j = self._limits(move, seg)
        prof = solve(seg.length, v, a, j)
        return _Active(move, seg, prof, prof.duration)

    def _limits(self, move: Move, seg: Segment) -> tuple[float, float, float]:
        d = seg.max_direction_cosines()
        mask = d > 1e-12
        v = float(np.min(self._vmax[mask] / d[mask]))
        a = float(np.min(self._amax[mask] / d[mask]))
        j = float(np.min(self._jmax[mask] / d[mask]))
        if move.kind != "rapid":
            feed = self._feed_mm_s(move)
            v = min(v, feed)
        if seg.kind == "arc" and seg.radius > 0:
            # Keep centripetal acceleration and jerk inside the plane axes' limits.
            pa = min(self._amax[seg.i1], self._amax[seg.i2])
            pj = min(self._jmax[seg.i1], self._jmax[seg.i2])
            r = seg.radius
            k = seg.arc_len / seg.length  # fraction of path speed that is circular
            v = min(v, math.sqrt(0.5 * pa * r) / k, (0.25 * pj * r * r) ** (1.0 / 3.0) / k)
            a = min(a, 0.5 * pa, pj * r / (12.0 * max(v * k, 1e-9)))
            j = min(j, 0.5 * pj)
        return v, a, j

    def _feed_mm_s(self, move: Move) -> float:
        feed = move.feed or 0.0
        if move.per_rev:
            rpm = abs(self.spindle_rpm())
            if rpm <= 0:
                raise NcAlarm(0x1001, "feed per revolution with the spindle stopped (S0)", line=move.line,
                              block=move.block, program=move.program)
            feed *= rpm
        return feed / 60.0


def _stop_profile(s: float, v: float, a: float, a_max: float, j_max: float) -> tuple[float, "object"]:
    """Jerk-limited stop from (v, a): returns the distance it needs and the ruckig trajectory."""
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, Trajectory

    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position = [s]
    inp.current_velocity = [v]
    inp.current_acceleration = [a]
    inp.target_velocity = [0.0]
    inp.target_acceleration = [0.0]
    inp.max_velocity = [max(abs(v), 1e-6)]
    inp.max_acceleration = [a_max]
    inp.max_jerk = [j_max]
    traj = Trajectory(1)
    if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
        raise NcAlarm(0x0000, "stop trajectory failed")
    p, _, _ = traj.at_time(traj.duration)
    return p[0], traj
