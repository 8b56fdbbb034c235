"""One MLC axis's own motion (NC5 App. B.2: M2x416+i / M2x448+i / M2x464+i, D2x256+2i / D2x288+2i).

While the MLC controls an axis (M2x432+i, see hil/mlc_axes.py), the NC plans no path for it: the MLC asks for
a move and this object turns it into one jerk-limited position setpoint per cycle, solved by ruckig through
`nc.motion.profile` (no home-made profile):

    position mode  to an absolute or incremental target at the target velocity (capped at the axis's limit),
                   ending at rest exactly on the target: `reached` (M3x448+i)
    speed mode     to the target velocity (signed: its sign is the direction), held until the MLC stops it or
                   changes it: `reached` once the velocity is there ("speed reached", App. B.2)
    stop           a jerk-limited ramp to rest where the axis happens to be (reset, alarm, trigger dropped in
                   speed mode)

Acceleration and jerk are always the axis's own limits (the bench's [[axes]] limits), as for the NC's moves.
Units: the device's velocity is mm/min for a linear axis and rpm for a rotary one (App. B.2 D2x288, "A/B/C: RPM").
"""

from __future__ import annotations

from dataclasses import dataclass

from nc.motion.limits import AxisLimits
from nc.motion.profile import Piecewise, solve_position, solve_velocity


def velocity_units(value: float, rotary: bool) -> float:
    """D2x288's value in the axis's units per second: mm/min → mm/s, rpm → deg/s."""
    return value * 6.0 if rotary else value / 60.0


@dataclass
class MlcAxis:
    name: str
    limits: AxisLimits
    cycle: float = 0.001
    p: float = 0.0  # the setpoint (machine units)
    v: float = 0.0
    a: float = 0.0
    goal: float | None = None  # position mode: the move's target; None: a speed (or a stop) ramp
    speed: float = 0.0  # speed mode: the velocity asked for (units/s, signed)
    reached: bool = False  # M3x448+i
    stopping: bool = False  # the ramp under way is a stop (`stop`), not a speed the MLC asked for
    _prof: Piecewise | None = None
    _t: float = 0.0

    @property
    def moving(self) -> bool:
        return self._prof is not None or self.v != 0.0

    def hold(self, position: float) -> None:
        """At rest at `position` (the switch from the NC, or after an E-stop's quick stop): nothing planned."""
        self.p, self.v, self.a, self._prof, self.goal, self.speed = position, 0.0, 0.0, None, None, 0.0
        self.reached = self.stopping = False

    def move_to(self, target: float, velocity: float) -> bool:
        """Position mode: to `target` at |velocity| units/s (at most the axis's). False: no move (velocity 0)."""
        vmax = min(abs(velocity), self.limits.max_velocity)
        if vmax <= 0.0:
            return False
        prof = solve_position(self.p, self.v, self.a, target, 0.0, vmax, self.limits.max_acceleration,
                              self.limits.max_jerk)
        if prof is None:
            return False
        self._prof, self._t, self.goal, self.reached, self.stopping = prof, 0.0, target, False, False
        return True

    def run_at(self, velocity: float) -> None:
        """Speed mode: ramp to `velocity` units/s (signed, capped at the axis's velocity) and hold it."""
        lim = self.limits.max_velocity
        velocity = max(-lim, min(lim, velocity))
        self.speed, self.goal, self.reached, self.stopping = velocity, None, False, False
        self._prof = solve_velocity(self.p, self.v, self.a, velocity, self.limits.max_acceleration,
                                    self.limits.max_jerk)
        self._t = 0.0

    def stop(self) -> None:
        """A controlled stop where the axis is: the target, if any, is given up (`reached` stays OFF)."""
        if self.moving:
            self.run_at(0.0)
            self.stopping = True

    def step(self) -> float:
        """The next cycle's setpoint."""
        prof = self._prof
        if prof is None:
            if self.v != 0.0:  # speed mode at its velocity: constant speed
                self.p += self.v * self.cycle
            return self.p
        self._t += self.cycle
        if self._t >= prof.duration:
            self._prof = None
            if self.goal is not None:  # position mode: exactly on the target, at rest
                self.p, self.v, self.a = self.goal, 0.0, 0.0
            else:
                end = prof.at(prof.duration)
                self.p = end[0] + self.speed * (self._t - prof.duration)
                self.v, self.a = self.speed, 0.0
            self.reached = not self.stopping  # a stop gives the target up: nothing was reached
            self.stopping = False
            return self.p
        self.p, self.v, self.a = prof.at(self._t)
        return self.p
