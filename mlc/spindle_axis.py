"""Spindle ↔ C-axis switching and M19 orientation: the NC side, for the first spindle.

The MLC asks, the NC does it on the spindle drive, the NC reports back:

    request C axis   M2x708 (NC5 "Switching C / S Axis of 1st Spindle") or M1126 (lathe manual §3.2)
    request orient   M2x706 (M19 "Spindle Positioning Control")
    C mode done      M2239 ON (lathe manual: "NC finished switching, now in C-axis mode")
    oriented         M3x706 ("Spindle Target Reach")
    drive in CSP     M3x709 ("Is in Position Axis Mode") follows the drive's 0x6061 mode display

Switching to C: the spindle is stopped first (the NC holds its speed at 0, as the lathe manual's
automatic M05), then, if the encoder index has not been latched yet, it turns slowly in CSV until it
has (the automatic M29), then the drive goes to CSP (mode 8) and a jerk-limited move (ruckig) puts
the spindle at the C command's angle from the index. From then on the channel's C axis command is
the spindle's position setpoint. Switching back waits for C to stand still, then the drive returns
to CSV (mode 9). M19 is the same positioning to `orient_angle` from the index, held until M20.
The runner asks `drive(...)` once per cycle for the spindle drive's mode and setpoint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ruckig import InputParameter, OutputParameter, Result, Ruckig

from mlc.memory import DeviceMemory
from nc.exit_release import release_at_exit
from mlc.signals import m2, m3

MODE_CSP = 8
MODE_CSV = 9
M_REQUEST_LATHE = 1126  # lathe manual §3.2: MLC → NC, ON = C-axis mode
M_DONE_LATHE = 2239  # NC → MLC, ON = switching finished, in C-axis mode

SPINDLE, STOPPING, SEEK_INDEX, POSITIONING, C_AXIS, ORIENTED = (
    "spindle", "stopping", "seek-index", "positioning", "c-axis", "oriented")


@dataclass
class SpindleAxisSwitch:
    mem: DeviceMemory
    x: int = 1
    cycle: float = 0.001
    orient_angle: float = 0.0  # degrees from the index where M19 stops
    tolerance: float = 0.01  # degrees: in-position window for C done / M19 target reach
    seek_rpm: float = 30.0  # speed of the automatic index search (M29)
    max_velocity: float = 360.0  # deg/s, positioning move
    max_acceleration: float = 3600.0  # deg/s²
    max_jerk: float = 360000.0  # deg/s³
    check_time: float = 10.0  # s: N0.1025 positioning check time; positioning not done by then is 0x0C01 (0: off)
    failed: bool = False  # the positioning outlasted check_time (Mlc.spindle_drive raises 0x0C01 once)
    state: str = SPINDLE
    purpose: str = ""  # "C" or "orient": where POSITIONING goes when it is done
    goal: float = 0.0  # cumulative spindle degrees of the positioning target
    offset: float = 0.0  # spindle degrees = offset + C command, while in C mode
    log: list[tuple[int, str]] = field(default_factory=list)  # (cycle, state entered)
    _setpoint: float = 0.0
    _started: int | None = None  # cycle the current positioning (C switch or M19) was asked for
    _last_c: float | None = None
    _cycles: int = 0
    _otg: Ruckig | None = None
    _inp: InputParameter | None = None
    _out: OutputParameter | None = None

    # ---- what the MLC asked for ------------------------------------------------------------------
    def _want_c(self) -> bool:
        return self.mem.bit(m2(self.x, 708)) or self.mem.bit(M_REQUEST_LATHE)

    def _want_orient(self) -> bool:
        return self.mem.bit(m2(self.x, 706))

    def _enter(self, state: str) -> None:
        if state == STOPPING:
            self._started = self._cycles
        elif state in (SPINDLE, C_AXIS, ORIENTED):
            self._started = None
        self.state = state
        self.log.append((self._cycles, state))
        self.mem.set_bit(M_DONE_LATHE, state == C_AXIS)
        self.mem.set_bit(m3(self.x, 706), state == ORIENTED)

    # ---- once per cycle, from the runner -------------------------------------------------------------
    def idle(self) -> bool:
        """The usual cycle, counted as `drive` counts it: a spindle that stays a spindle (nothing asked, so
        `drive` would return (MODE_CSV, None, None) at once, reading none of its feedback). True: this
        cycle is done; False: call `drive` (issue 17: the runner skips the feedback it would not read)."""
        m, b2 = self.mem.m, 20000 + 1000 * self.x  # _want_c and _want_orient read straight from the bits
        if self.state != SPINDLE or m[b2 + 708] or m[M_REQUEST_LATHE] or m[b2 + 706]:
            return False
        self._cycles += 1  # SPINDLE has no positioning started: drive()'s check-time test is a no-op here
        return True

    def drive(self, angle: float, rpm: float, index: float | None,
              c_command: float | None) -> tuple[int, float | None, float | None]:
        """(mode of operation, position setpoint in cumulative spindle degrees or None,
        velocity override in rpm or None) for the spindle drive this cycle.

        angle: measured cumulative spindle degrees; rpm: measured speed; index: latched index angle
        (None until seen); c_command: the channel's C axis command in degrees (None when the channel has no C axis)."""
        self._cycles += 1
        if self._started is not None and self.check_time > 0 and \
                (self._cycles - self._started) * self.cycle > self.check_time:
            self.failed = True  # App. A 0x0C01: still stopping, seeking the index or positioning
        want_c, want_orient = self._want_c(), self._want_orient()
        s = self.state
        if s == SPINDLE:
            if want_c or want_orient:
                self.purpose = "C" if want_c else "orient"
                self._enter(STOPPING)
                s = STOPPING
            else:
                return MODE_CSV, None, None
        if s == STOPPING:
            if not (want_c or want_orient):
                self._enter(SPINDLE)
                return MODE_CSV, None, None
            if abs(rpm) >= 1.0:
                return MODE_CSV, None, 0.0  # the automatic M05: speed 0 until zero speed
            if index is None:
                self._enter(SEEK_INDEX)  # the automatic M29: find the index first
                return MODE_CSV, None, self.seek_rpm
            self._start_positioning(angle, 0.0, index, c_command)
        if s == SEEK_INDEX:
            if index is None:
                return MODE_CSV, None, self.seek_rpm
            self._start_positioning(angle, rpm * 6.0, index, c_command)
        if self.state == POSITIONING:
            done = self._step_positioning()
            if done and abs(angle - self.goal) <= self.tolerance and abs(rpm) < 0.5:
                if self.purpose == "C":
                    self.offset = self.goal - (c_command or 0.0)
                    self._last_c = c_command
                    self._enter(C_AXIS)
                else:
                    self._enter(ORIENTED)
            return MODE_CSP, self._setpoint, None
        if self.state == C_AXIS:
            still = c_command is None or (self._last_c is not None and abs(c_command - self._last_c) < 1e-9)
            self._last_c = c_command
            self._setpoint = self.offset + (c_command or 0.0)
            settled = abs(angle - self._setpoint) <= self.tolerance and abs(rpm) < 0.5
            if not want_c and still and settled:
                self._enter(SPINDLE)  # C stands still: back to the spindle (8 → 9)
                return MODE_CSV, None, None
            return MODE_CSP, self._setpoint, None
        if self.state == ORIENTED:
            if want_c:
                self.offset = self.goal - (c_command or 0.0)
                self._last_c = c_command
                self._enter(C_AXIS)
            elif not want_orient:
                self._enter(SPINDLE)  # M20
                return MODE_CSV, None, None
            return MODE_CSP, self._setpoint, None
        return MODE_CSV, None, None

    # ---- positioning ------------------------------------------------------------------------------
    def _start_positioning(self, angle: float, velocity: float, index: float, c_command: float | None) -> None:
        target = (c_command or 0.0) if self.purpose == "C" else self.orient_angle
        # The next angle ≡ target (mod 360) from the index, far enough ahead to stop in the turning sense.
        ahead = velocity * abs(velocity) / (2.0 * self.max_acceleration) if velocity else 0.0
        base = index + target
        k = math.ceil((angle + ahead - base - 1e-9) / 360.0) if velocity > 0 else round((angle - base) / 360.0)
        self.goal = base + 360.0 * k
        if self._otg is None:  # the first positioning: in the bench's cycles, so freed at exit (B83)
            release_at_exit(self, "_otg", "_inp", "_out")
        self._otg = Ruckig(1, self.cycle)
        inp = self._inp = InputParameter(1)
        self._out = OutputParameter(1)
        inp.current_position, inp.current_velocity, inp.current_acceleration = [angle], [velocity], [0.0]
        inp.target_position, inp.target_velocity, inp.target_acceleration = [self.goal], [0.0], [0.0]
        inp.max_velocity = [max(self.max_velocity, abs(velocity))]
        inp.max_acceleration, inp.max_jerk = [self.max_acceleration], [self.max_jerk]
        self._setpoint = angle
        self._enter(POSITIONING)

    def _step_positioning(self) -> bool:
        assert self._otg is not None and self._inp is not None and self._out is not None
        if self._setpoint == self.goal:
            return True
        res = self._otg.update(self._inp, self._out)
        self._setpoint = self._out.new_position[0]
        self._out.pass_to_input(self._inp)
        if res == Result.Finished:
            self._setpoint = self.goal
        return self._setpoint == self.goal
