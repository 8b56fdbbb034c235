"""A jerk-limited 1-DoF profile along path length, solved once by ruckig and sampled per cycle.

Never pass intermediate positions to ruckig: the community build sends those to a web service.
"""

from __future__ import annotations

from dataclasses import dataclass

from ruckig import InputParameter, Result, Ruckig, Trajectory

from nc.alarms import NcAlarm

_OTG = Ruckig(1)
_INP = InputParameter(1)


@dataclass
class PathProfile:
    length: float
    duration: float
    _traj: Trajectory

    def at(self, t: float) -> tuple[float, float, float]:
        """(s, ds/dt, d²s/dt²) at time t, clamped to the profile's ends."""
        if t >= self.duration:
            p, v, a = self._traj.at_time(self.duration)
            return self.length, v[0], a[0]
        p, v, a = self._traj.at_time(max(t, 0.0))
        return p[0], v[0], a[0]


def solve(length: float, v_max: float, a_max: float, j_max: float, v0: float = 0.0, a0: float = 0.0,
          v1: float = 0.0) -> PathProfile:
    """Time-optimal jerk-limited profile from (0, v0, a0) to (length, v1, 0)."""
    if v_max <= 0 or a_max <= 0 or j_max <= 0:
        raise NcAlarm(0x1001, f"non-positive path limit (v={v_max:g}, a={a_max:g}, j={j_max:g})")
    _INP.current_position = [0.0]
    _INP.current_velocity = [v0]
    _INP.current_acceleration = [a0]
    _INP.target_position = [length]
    _INP.target_velocity = [v1]
    _INP.target_acceleration = [0.0]
    _INP.max_velocity = [v_max]
    _INP.max_acceleration = [a_max]
    _INP.max_jerk = [j_max]
    traj = Trajectory(1)
    result = _OTG.calculate(_INP, traj)
    if result not in (Result.Working, Result.Finished):
        raise NcAlarm(0x0000, f"trajectory generation failed ({result}) for a {length:g} mm segment")
    return PathProfile(length, traj.duration, traj)
