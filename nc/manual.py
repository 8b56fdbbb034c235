"""Manual motion for the JOG, INC, MPG and HOME modes: one jerk-limited ruckig generator per axis.

JOG is hold-to-run (velocity interface: the target velocity is ±jog speed while the relay is on,
zero when it drops). INC, MPG and HOME are position moves (position interface: the target moves by
the step, by pulses × ratio × unit, or to the home position). Soft limits clamp every target and
the interlocks stop motion in a locked direction, so a manual move can never run past them.

The generator knows nothing of relays: the MLC signal layer (`mlc.nc_link`) turns Delta's special
M/D devices into the calls below, once per cycle, before the channel step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from ruckig import ControlInterface, InputParameter, OutputParameter, Result, Ruckig

from nc.motion.limits import MotionConfig


@dataclass
class AxisState:
    homed: bool = False
    homing: bool = False
    home_done: bool = False  # the homing procedure finished (M3x336)
    lock_pos: bool = False  # interlocks M2x336 / M2x352
    lock_neg: bool = False
    soft_min: float | None = None
    soft_max: float | None = None
    soft_limit_disabled: bool = False  # M2x368


@dataclass
class ManualMotion:
    cfg: MotionConfig
    position: np.ndarray
    home_position: dict[str, float] = field(default_factory=dict)
    jog_speed: dict[str, float] = field(default_factory=dict)  # mm/s at 100 % (N2.030 role)
    home_speed: float = 20.0  # mm/s

    def __post_init__(self) -> None:
        n = len(self.cfg.axes)
        self.position = np.asarray(self.position, dtype=float).copy()
        self.velocity = np.zeros(n)
        self.acceleration = np.zeros(n)
        self.axes = {a: AxisState() for a in self.cfg.axes}
        # One online generator and output per axis: ruckig keeps the running trajectory in them.
        self._otg = [Ruckig(1, self.cfg.cycle) for _ in range(n)]
        self._out = [OutputParameter(1) for _ in range(n)]
        self._inp = [self._make_input(i) for i in range(n)]
        self._mode: list[str | None] = [None] * n  # "velocity", "position" or None (at rest)
        self._target = self.position.copy()
        self._vcap = np.array([self.cfg.limit(a).max_velocity for a in self.cfg.axes])

    def _make_input(self, i: int) -> InputParameter:
        lim = self.cfg.limit(self.cfg.axes[i])
        inp = InputParameter(1)
        inp.max_velocity = [lim.max_velocity]
        inp.max_acceleration = [lim.max_acceleration]
        inp.max_jerk = [lim.max_jerk]
        return inp

    def index(self, axis: str) -> int:
        return self.cfg.axes.index(axis)

    # ---- commands ---------------------------------------------------------------------------
    def jog(self, axis: str, direction: int, speed: float) -> None:
        """Hold-to-run: call every cycle with direction ±1 while the relay is on, 0 to stop."""
        i = self.index(axis)
        st = self.axes[axis]
        if (direction > 0 and st.lock_pos) or (direction < 0 and st.lock_neg):
            direction = 0
        v = direction * min(abs(speed), self._vcap[i])
        if direction == 0 and self._mode[i] != "velocity":
            return
        self._mode[i] = "velocity"
        inp = self._inp[i]
        inp.control_interface = ControlInterface.Velocity
        inp.target_velocity = [v]
        inp.target_acceleration = [0.0]

    def move_by(self, axis: str, distance: float, speed: float | None = None) -> None:
        """INC step or MPG pulses: move the axis target by `distance` (accumulates while moving)."""
        i = self.index(axis)
        base = self._target[i] if self._mode[i] == "position" else self.position[i]
        self.move_to(axis, base + distance, speed)

    def move_to(self, axis: str, target: float, speed: float | None = None) -> None:
        i = self.index(axis)
        st = self.axes[axis]
        target = self._clamp(axis, target)
        if (target > self.position[i] and st.lock_pos) or (target < self.position[i] and st.lock_neg):
            return
        self._target[i] = target
        self._mode[i] = "position"
        inp = self._inp[i]
        inp.control_interface = ControlInterface.Position
        inp.target_position = [target]
        inp.target_velocity = [0.0]
        inp.target_acceleration = [0.0]
        inp.max_velocity = [min(speed, self._vcap[i]) if speed else self._vcap[i]]

    def home(self, axis: str) -> None:
        st = self.axes[axis]
        st.homing, st.home_done = True, False
        self.move_to(axis, self.home_position.get(axis, 0.0), self.home_speed)

    def stop(self, axis: str | None = None) -> None:
        """Jerk-limited stop of one or every axis (feed hold, mode change, reset)."""
        for a in ([axis] if axis else list(self.cfg.axes)):
            i = self.index(a)
            if self._mode[i] is not None:
                self._mode[i] = "velocity"
                inp = self._inp[i]
                inp.control_interface = ControlInterface.Velocity
                inp.target_velocity = [0.0]
                inp.target_acceleration = [0.0]
            self.axes[a].homing = False

    def halt(self) -> None:
        """E-stop: the setpoints freeze where they are this cycle."""
        self.velocity[:] = 0.0
        self.acceleration[:] = 0.0
        self._mode = [None] * len(self._mode)
        for st in self.axes.values():
            st.homing = False

    def take_over(self, positions: np.ndarray) -> None:
        """Adopt the channel's position when entering a manual mode (after a program, after enable)."""
        if not self.busy:
            self.position[:] = positions
            self._target[:] = positions

    @property
    def busy(self) -> bool:
        return any(m is not None for m in self._mode)

    def moving(self, axis: str) -> bool:
        return self._mode[self.index(axis)] is not None

    # ---- per cycle ----------------------------------------------------------------------------
    def step(self) -> np.ndarray:
        for i, mode in enumerate(self._mode):
            if mode is None:
                continue
            inp = self._inp[i]
            inp.current_position = [self.position[i]]
            inp.current_velocity = [self.velocity[i]]
            inp.current_acceleration = [self.acceleration[i]]
            if mode == "velocity":
                inp.max_velocity = [self._vcap[i]]
            out = self._out[i]
            res = self._otg[i].update(inp, out)
            if res not in (Result.Working, Result.Finished):
                self.halt()
                break
            new = out.new_position[0]
            a = self.cfg.axes[i]
            clamped = self._clamp(a, new)
            self.position[i] = clamped
            self.velocity[i] = out.new_velocity[0] if clamped == new else 0.0
            self.acceleration[i] = out.new_acceleration[0] if clamped == new else 0.0
            at_rest = abs(self.velocity[i]) < 1e-9 and abs(self.acceleration[i]) < 1e-9
            # In the velocity interface "Finished" only means the target velocity is reached.
            done = at_rest and inp.target_velocity[0] == 0.0 if mode == "velocity" else res == Result.Finished
            if done:
                self._mode[i] = None
                self.velocity[i] = self.acceleration[i] = 0.0
                st = self.axes[a]
                if st.homing:
                    st.homing = False
                    st.homed = st.home_done = abs(self.position[i] - self.home_position.get(a, 0.0)) < 1e-9
        return self.position

    def _clamp(self, axis: str, value: float) -> float:
        st = self.axes[axis]
        if st.soft_limit_disabled:
            return value
        if st.soft_min is not None and value < st.soft_min:
            return st.soft_min
        if st.soft_max is not None and value > st.soft_max:
            return st.soft_max
        return value
