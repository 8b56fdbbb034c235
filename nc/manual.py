"""Manual motion for the JOG, INC, MPG and HOME modes: one jerk-limited ruckig generator per axis.

JOG is hold-to-run (velocity interface: the target velocity is ±jog speed while the relay is on,
zero when it drops). INC, MPG and HOME are position moves (position interface: the target moves by
the step, by pulses × ratio × unit, or to the home position). Soft limits clamp every target and
the interlocks stop motion in a locked direction, so a manual move can never run past them.

The generator knows nothing of relays: the MLC signal layer (`mlc.nc_link`) turns Delta's special
M/D devices into the calls below, once per cycle, before the channel step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from ruckig import ControlInterface, InputParameter, OutputParameter, Result, Ruckig

from nc.exit_release import release_at_exit
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
    # NC-side homing against a home switch (active on the negative side of its edge). The bench
    # wires `home_input(axis) -> (switch active, actual machine position)` or None when the axis
    # has no switch (then HOME is a plain move to the home position), and `shift_origin(axis, d)`
    # which adds d to the drive-count → machine-coordinate offset of the axis.
    home_input: Callable[[str], tuple[bool, float] | None] | None = None
    shift_origin: Callable[[str, float], None] | None = None
    home_creep: float = 1.0  # mm/s, the first approach of the edge from the active side
    home_fine: float = 0.002  # mm/s, the latching approach (about one drive count per cycle)
    home_backoff: float = 0.01  # mm, backed off into the active side before the fine approach

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
        release_at_exit(self, "_otg", "_out", "_inp")  # in the bench's cycles: nanobind's leak report at exit (B83)
        self._mode: list[str | None] = [None] * n  # "velocity", "position" or None (at rest)
        self._target = self.position.copy()
        self._vcap = np.array([self.cfg.limit(a).max_velocity for a in self.cfg.axes])
        # homing phase per axis: None, "leave", "search", "creep", "back", "fine", "return"
        self._phase: list[str | None] = [None] * n
        self.clamped: set[str] = set()  # axes whose last step was cut at a soft limit, or ended on one
        self._cut: set[str] = set()  # axes moving to a position target that was cut at a soft limit

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
        wanted, target = target, self._clamp(axis, target)
        if target != wanted:
            self._cut.add(axis)  # an INC/MPG target cut at a soft limit: the axis will reach it
        else:
            self._cut.discard(axis)
        if (target > self.position[i] and st.lock_pos) or (target < self.position[i] and st.lock_neg):
            return
        self._move_raw(i, target, speed or self._vcap[i])

    def home(self, axis: str) -> None:
        st = self.axes[axis]
        st.homing, st.home_done = True, False
        sw = self.home_input(axis) if self.home_input is not None else None
        if sw is None:
            self.move_to(axis, self.home_position.get(axis, 0.0), self.home_speed)
            return
        # Leave the switch first when starting on it, so every homing latches the same edge
        # from the same side at the same (fine) speed.
        self._home_jog(axis, "leave" if sw[0] else "search")

    def _home_jog(self, axis: str, phase: str) -> None:
        i = self.index(axis)
        self._phase[i] = phase
        speed = {"leave": self.home_speed, "search": -self.home_speed, "creep": self.home_creep,
                 "fine": self.home_fine}[phase]
        st = self.axes[axis]
        locks = st.lock_pos, st.lock_neg
        st.lock_pos = st.lock_neg = False  # homing is the one manual move allowed before limits are known
        self.jog(axis, 1 if speed > 0 else -1, abs(speed))
        st.lock_pos, st.lock_neg = locks

    def _home_cycle(self, i: int) -> None:
        """One cycle of the homing sequence of axis i (after its generator stepped)."""
        a = self.cfg.axes[i]
        phase = self._phase[i]
        sw = self.home_input(a) if self.home_input is not None else None
        if sw is None:
            self._phase[i] = None
            return
        active, actual = sw
        inp = self._inp[i]
        stopping = inp.control_interface == ControlInterface.Velocity and inp.target_velocity[0] == 0.0
        if phase in ("leave", "creep", "fine") and not stopping and not active:
            if phase == "fine":
                # The edge: this machine position becomes the home position.
                shift = self.home_position.get(a, 0.0) - actual
                if self.shift_origin is not None:
                    self.shift_origin(a, shift)
                self.position[i] += shift
                self._target[i] += shift
            self._stop_axis(i)
        elif phase == "search" and not stopping and active:
            self._stop_axis(i)
        if self._mode[i] is not None:
            return
        # at rest: next phase
        if phase == "leave":
            self._home_jog(a, "search")
        elif phase == "search":
            self._home_jog(a, "creep")
        elif phase == "creep":
            self._phase[i] = "back"
            self._move_raw(i, self.position[i] - self.home_backoff, self.home_speed)
        elif phase == "back":
            self._home_jog(a, "fine")
        elif phase == "fine":
            self._phase[i] = "return"
            self._move_raw(i, self.home_position.get(a, 0.0), self.home_creep)
        elif phase == "return":
            self._phase[i] = None
            st = self.axes[a]
            st.homing = False
            st.homed = st.home_done = abs(self.position[i] - self.home_position.get(a, 0.0)) < 1e-9

    def _stop_axis(self, i: int) -> None:
        self._mode[i] = "velocity"
        inp = self._inp[i]
        inp.control_interface = ControlInterface.Velocity
        inp.target_velocity = [0.0]
        inp.target_acceleration = [0.0]

    def _move_raw(self, i: int, target: float, speed: float) -> None:
        """Position move without soft limits or interlocks (they assume a homed axis)."""
        self._target[i] = target
        self._mode[i] = "position"
        inp = self._inp[i]
        inp.control_interface = ControlInterface.Position
        inp.target_position = [target]
        inp.target_velocity = [0.0]
        inp.target_acceleration = [0.0]
        inp.max_velocity = [min(speed, self._vcap[i])]

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
            self._phase[i] = None

    def halt(self) -> None:
        """E-stop: the setpoints freeze where they are this cycle."""
        self.velocity[:] = 0.0
        self.acceleration[:] = 0.0
        self._mode = [None] * len(self._mode)
        self._phase = [None] * len(self._phase)
        for st in self.axes.values():
            st.homing = False

    def take_over(self, positions: np.ndarray) -> None:
        """Adopt the channel's position when entering a manual mode (after a program, after enable)."""
        if not self.busy:
            self.position[:] = positions
            self._target[:] = positions

    def hold_at(self, axis: str, position: float) -> None:
        """The axis's drive stopped it on a hardware limit switch: the command stops there at once, so a move away
        starts from where the axis stands (App. A 0x0402 / 0x0A06, mlc.manual_alarms)."""
        i = self.index(axis)
        self.position[i] = self._target[i] = position
        self.velocity[i] = self.acceleration[i] = 0.0
        self._mode[i] = self._phase[i] = None
        self.axes[axis].homing = False
        self._cut.discard(axis)

    @property
    def busy(self) -> bool:
        return any(m is not None for m in self._mode)

    def moving(self, axis: str) -> bool:
        return self._mode[self.index(axis)] is not None

    # ---- per cycle ----------------------------------------------------------------------------
    def step(self) -> np.ndarray:
        self.clamped = set()
        for i, mode in enumerate(self._mode):
            if mode is None:
                if self._phase[i] is not None:
                    self._home_cycle(i)
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
            if clamped != new:
                self.clamped.add(a)  # cut at a soft limit: the axis reached it (App. A 0x0A01/0x0A03)
            self.position[i] = clamped
            self.velocity[i] = out.new_velocity[0] if clamped == new else 0.0
            self.acceleration[i] = out.new_acceleration[0] if clamped == new else 0.0
            at_rest = abs(self.velocity[i]) < 1e-9 and abs(self.acceleration[i]) < 1e-9
            # In the velocity interface "Finished" only means the target velocity is reached.
            done = at_rest and inp.target_velocity[0] == 0.0 if mode == "velocity" else res == Result.Finished
            if done and a in self._cut:
                self._cut.discard(a)
                self.clamped.add(a)
            if done:
                self._mode[i] = None
                self.velocity[i] = self.acceleration[i] = 0.0
                st = self.axes[a]
                if self._phase[i] is not None:
                    self._home_cycle(i)
                elif st.homing:
                    st.homing = False
                    st.homed = st.home_done = abs(self.position[i] - self.home_position.get(a, 0.0)) < 1e-9
            elif self._phase[i] is not None:
                self._home_cycle(i)
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
