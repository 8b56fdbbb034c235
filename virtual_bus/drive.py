"""A CiA 402 servo drive model: the slave-side state machine, CSP and CSV modes, a cascaded
position/velocity loop with second-order dynamics, feedback objects, travel limits and faults.

The numeric core works in counts and counts/s; the objects it exchanges carry the drive's declared
units (`DriveParams.units`: Delta's 0.1 rpm for 0x606C/0x60FF, 0.1 % of rated torque for 0x6077),
converted only in `apply` and `feedback`. The physics is stepped in substeps per bus cycle so the
velocity loop stays stable at any cycle time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from fieldbus.cia402 import (STATE_BITS, SW_FOLLOWING, SW_FOLLOWING_ERROR, SW_INTERNAL_LIMIT, SW_REMOTE,
                             SW_TARGET_REACHED, SW_VOLTAGE, SW_QUICK_STOP, State, command_of)
from fieldbus.pdo import RxPdo, TxPdo
from fieldbus.units import DELTA_UNITS, DriveUnits
from virtual_bus.drive_modes import CST, HM, PROFILE_MODES, DriveModes
from virtual_bus.servo_params import ServoParams
from virtual_bus.kernels import drive_kernel
from virtual_bus.drive_params import DriveParams  # noqa: F401  (its home before; the settings alone load light)

# Delta ASDA alarm numbers as the drive reports them in 0x603F (the NC shows 0xF002 + this code)
AL_OVERSPEED = 0x0007
AL_FOLLOWING_ERROR = 0x0009
AL_REVERSE_LIMIT = 0x0014
AL_FORWARD_LIMIT = 0x0015
AL_EMERGENCY = 0x0013


def _status_base(state: State) -> int:
    """The statusword bits a state always shows (0x6041: state, remote, voltage, quick stop)."""
    sw = STATE_BITS[state] | SW_REMOTE
    if state not in (State.SWITCH_ON_DISABLED, State.NOT_READY_TO_SWITCH_ON):
        sw |= SW_VOLTAGE
    if state is not State.QUICK_STOP_ACTIVE and state is not State.FAULT:
        sw |= SW_QUICK_STOP
    return sw


_STATUS_BASE = {s: _status_base(s) for s in State}
_ENABLED = State.OPERATION_ENABLED
_SW_FOLLOWING = _STATUS_BASE[_ENABLED] | SW_FOLLOWING  # an enabled CSP / CSV drive's statusword, before its flags


@dataclass
class Cia402Drive:
    params: DriveParams = field(default_factory=DriveParams)
    name: str = "drive"
    state: State = State.SWITCH_ON_DISABLED
    position: float = 0.0  # counts (load side, as the encoder reads)
    velocity: float = 0.0  # counts/s
    acceleration: float = 0.0
    command: float = 0.0  # interpolated position command, counts
    target_velocity: float = 0.0  # counts/s, the CSV ramp's current value
    mode: int = 8
    error_code: int = 0
    torque: float = 0.0  # 0.1 % of rated
    time: float = 0.0
    external_fault: int = 0  # set by a test/fault injector: the drive faults with this code
    _prev_target: float | None = None
    _rx: RxPdo = field(default_factory=RxPdo)
    _last_cw: int = 0
    _probe_latched: bool = False
    _probe_pos: int = 0
    _limit_flags: int = 0
    _want_cps: float = 0.0  # 0x60FF converted to counts/s
    servo_params: ServoParams = field(default_factory=ServoParams)  # P0-xx…P6-xx over SDO / Modbus (issue 8)
    modes: DriveModes = field(default_factory=DriveModes)  # PP, PV, HM, CST and the home origin (drive_modes.py)

    # ---- process data -----------------------------------------------------------------
    def apply(self, rx: RxPdo) -> None:
        """Latch the master's outputs (what a SYNC event does on a real drive)."""
        self._rx = rx
        self._want_cps = self.params.units.raw_to_velocity(rx.target_velocity, self.params.counts_per_rev)
        self._state_machine(rx.controlword)
        if rx.mode != self.mode:
            self.select_mode(rx.mode)
        if self.mode in PROFILE_MODES:
            self.modes.apply(self, rx.controlword, rx.target_position, rx.target_torque)

    def select_mode(self, mode: int) -> None:
        """Switch to `mode` (0x6060, by PDO or SDO): 0x6061 shows it from now on; a profile mode starts afresh."""
        self.mode = mode
        self._prev_target = None
        self.modes.restart(self._rx.controlword)

    def feedback(self) -> TxPdo:
        p, state, mode = self.params, self.state, self.mode
        sw = _STATUS_BASE[state]
        gap = self.command - self.position
        profile = mode in PROFILE_MODES
        if state is State.OPERATION_ENABLED:
            if profile:
                sw |= self.modes.status_bits(self)
            else:
                sw |= SW_FOLLOWING
                if abs(self.velocity) < 0.001 * (p.max_speed_rpm / 60.0 * p.counts_per_rev) and abs(gap) < 10:
                    sw |= SW_TARGET_REACHED
        di = self._limit_flags
        if di and mode != HM:  # homing on a limit switch is no limit violation
            sw |= SW_INTERNAL_LIMIT
        if abs(gap) > p.following_error_window and not profile:
            sw |= SW_FOLLOWING_ERROR
        if p.home_switch is not None and self.position < p.home_switch:
            di |= 0x4
        return TxPdo(
            statusword=sw,
            position_actual=int(round(self.position + self.modes.origin)),
            velocity_actual=p.units.velocity_to_raw(self.velocity, p.counts_per_rev),
            torque_actual=int(round(self.torque * 0.1 / p.units.torque_percent)),
            following_error=int(round(gap)) if mode == 8 else 0,
            error_code=self.error_code,
            mode_display=self.mode,
            touch_probe_status=0x0003 if self._probe_latched else (0x0001 if self._rx.touch_probe_function & 1 else 0),
            touch_probe_pos1=self._probe_pos + int(round(self.modes.origin)),
            digital_inputs=di,
        )

    def exchange(self, rx: RxPdo, dt: float) -> TxPdo:
        cw, mode = rx.controlword, self.mode
        if (self.state is not _ENABLED or cw != self._last_cw or cw & 0x8F != 0x0F or rx.mode != mode
                or (mode != 8 and mode != 9) or self.external_fault):
            self.apply(rx)
            self.step(dt)
            return self.feedback()
        return self._exchange_following(rx, dt, mode == 8)

    def _exchange_following(self, rx: RxPdo, dt: float, csp: bool) -> TxPdo:
        """`apply`, `step` and `feedback` of the usual cycle (issue 17): enabled in CSP or CSV, the
        controlword held, no mode change, no injected fault. The same operations in the same order as
        those three, on local variables: the state machine returns at once, no profile mode applies, and
        the state stays enabled unless `_supervise` faults (then `feedback` builds the image)."""
        p = self.params
        self._rx = rx
        cpr, units = p.counts_per_rev, p.units
        rpc = 600.0 / cpr if units.velocity == "0.1 rpm" else 1.0  # DriveUnits.raw_per_count_per_s
        self._want_cps = rx.target_velocity / rpc
        origin = self.modes.origin
        if p.negative_limit is not None or p.positive_limit is not None:
            self.step(dt)
        else:
            n = max(1, p.substeps)
            h = dt / n
            prev, target, ff_vel = self._setpoint(float(rx.target_position) - origin, csp, dt)
            v_before = self.velocity
            max_cps = p.max_speed_rpm / 60.0 * cpr
            alpha = 1.0 - math.exp(-p.velocity_bandwidth * h)
            self._step_following(n, h, prev, target, ff_vel, max_cps, alpha, csp,
                                 bool(rx.touch_probe_function & 1))
            vel = self.velocity
            acc = self.acceleration = (vel - v_before) / dt
            rad = 2.0 * math.pi / cpr
            torque_nm = (p.inertia * acc * rad + p.viscous * vel * rad
                         + (math.copysign(p.coulomb, vel) if abs(vel) > 1 else 0.0))
            self.torque = torque_nm / p.rated_torque * 1000.0
            gap = self.command - self.position
            if (csp and abs(gap) > p.following_error_window) or abs(vel) > 1.2 * max_cps:
                self._supervise()
        if self.state is not _ENABLED or self._limit_flags:
            return self.feedback()
        # feedback() of an enabled CSP / CSV drive off its limit switches
        vel, pos, gap = self.velocity, self.position, self.command - self.position
        sw = _SW_FOLLOWING
        if abs(vel) < 0.001 * (p.max_speed_rpm / 60.0 * cpr) and abs(gap) < 10:
            sw |= SW_TARGET_REACHED
        if abs(gap) > p.following_error_window:
            sw |= SW_FOLLOWING_ERROR
        raw = round(vel * rpc)  # DriveUnits.velocity_to_raw
        return TxPdo(sw, int(round(pos + origin)), max(-0x7FFFFFFF, min(0x7FFFFFFF, int(raw))),
                     int(round(self.torque * 0.1 / units.torque_percent)), int(round(gap)) if csp else 0,
                     self.error_code, self.mode,
                     0x0003 if self._probe_latched else (0x0001 if rx.touch_probe_function & 1 else 0),
                     self._probe_pos + int(round(origin)),
                     0x4 if p.home_switch is not None and pos < p.home_switch else 0)

    # ---- state machine ------------------------------------------------------------------
    def _state_machine(self, cw: int) -> None:
        if cw == self._last_cw and cw & 0x8F == 0x0F and self.state is State.OPERATION_ENABLED:
            return  # enable operation held while enabled, the usual cycle: no transition, no edge
        cmd = command_of(cw)
        rising_reset = bool(cw & 0x80) and not (self._last_cw & 0x80)
        self._last_cw = cw
        s = self.state
        if s is State.FAULT:
            if rising_reset and not self.external_fault:
                self.error_code = 0
                self.state = State.SWITCH_ON_DISABLED
            return
        if s is State.FAULT_REACTION_ACTIVE:
            return
        if cmd == "disable_voltage":
            if s is not State.QUICK_STOP_ACTIVE or abs(self.velocity) < 1:
                self.state = State.SWITCH_ON_DISABLED
            return
        if cmd == "quick_stop":
            if s is State.OPERATION_ENABLED:
                self.state = State.QUICK_STOP_ACTIVE
            elif s in (State.READY_TO_SWITCH_ON, State.SWITCHED_ON):
                self.state = State.SWITCH_ON_DISABLED
            return
        if cmd == "shutdown":
            if s in (State.SWITCH_ON_DISABLED, State.SWITCHED_ON, State.OPERATION_ENABLED):
                self.state = State.READY_TO_SWITCH_ON
        elif cmd == "switch_on":
            if s is State.READY_TO_SWITCH_ON:
                self.state = State.SWITCHED_ON
            elif s is State.OPERATION_ENABLED:
                self.state = State.SWITCHED_ON
        elif cmd == "enable_operation":
            if s is State.SWITCHED_ON:
                # The drive takes over the actual position so enabling never jumps.
                self.command = self.position
                self._prev_target = None
                self.modes.restart(cw)
                self.state = State.OPERATION_ENABLED
            elif s is State.READY_TO_SWITCH_ON:
                self.state = State.SWITCHED_ON

    def fault(self, code: int) -> None:
        if self.state not in (State.FAULT, State.FAULT_REACTION_ACTIVE):
            self.error_code = code
            self.state = State.FAULT_REACTION_ACTIVE

    # ---- physics ------------------------------------------------------------------------
    @property
    def _max_cps(self) -> float:
        return self.params.max_speed_rpm / 60.0 * self.params.counts_per_rev

    @property
    def _counts_to_rad(self) -> float:
        return 2.0 * math.pi / self.params.counts_per_rev

    def step(self, dt: float) -> None:
        p = self.params
        if self.external_fault:
            self.fault(self.external_fault)
        n = max(1, p.substeps)
        h = dt / n
        energised = self.state in (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE, State.FAULT_REACTION_ACTIVE)
        target = float(self._rx.target_position) - self.modes.origin  # 0x607A in PUU, homing shifted them
        prev, target, ff_vel = self._setpoint(target, self.state is State.OPERATION_ENABLED and self.mode == 8, dt)
        v_before = self.velocity
        # The state and mode cannot change inside the cycle (faults are taken in _supervise, after
        # it): the branch, the speed limit and the filter gain are chosen once, not per sub-step.
        max_cps = self._max_cps
        alpha = 1.0 - math.exp(-p.velocity_bandwidth * h)
        limited = p.negative_limit is not None or p.positive_limit is not None
        probing = bool(self._rx.touch_probe_function & 1)
        enabled = self.state is State.OPERATION_ENABLED
        csp, csv = enabled and self.mode == 8, enabled and self.mode == 9
        profile = enabled and self.mode in PROFILE_MODES  # PP, PV, HM, CST: virtual_bus/drive_modes.py
        direct = profile and self.mode == CST  # torque mode: the velocity is the motor's, no velocity loop
        if energised and (csp or csv) and not limited:
            self._step_following(n, h, prev, target, ff_vel, max_cps, alpha, csp, probing)
        else:
            self._step_general(n, h, prev, target, ff_vel, max_cps, alpha, energised, csp, csv, profile, direct,
                               limited, probing)
        self.acceleration = (self.velocity - v_before) / dt
        rad = self._counts_to_rad
        torque_nm = (p.inertia * self.acceleration * rad + p.viscous * self.velocity * rad
                     + (math.copysign(p.coulomb, self.velocity) if abs(self.velocity) > 1 else 0.0))
        self.torque = torque_nm / p.rated_torque * 1000.0 if energised else 0.0
        self._supervise()

    def _setpoint(self, target: float, csp: bool, dt: float) -> tuple[float, float, float]:
        """The cycle's interpolation: (start, end, feed-forward speed). In CSP the drive's interpolator spreads
        the new target over the cycle; otherwise the command stays where it is."""
        if csp:
            prev = self._prev_target if self._prev_target is not None else self.command
            self._prev_target = target
            return prev, target, (target - prev) / dt
        return self.command, self.command, 0.0

    def _step_following(self, n: int, h: float, prev: float, target: float, ff_vel: float, max_cps: float,
                        alpha: float, csp: bool, probing: bool) -> None:
        """The usual cycle: an enabled drive following CSP setpoints (or its CSV ramp) with no limit
        switches. The same arithmetic, in the same order, as _step_general, on local variables: the
        sub-steps are where the bench's drive time goes (issue 17)."""
        p = self.params
        pos, vel, t = self.position, self.velocity, self.time
        kff_ff, kp, span = p.kff * ff_vel, p.kp, target - prev
        ramp, want, tv = p.csv_accel * h, self._want_cps, self.target_velocity
        # an armed probe that has latched stays latched while armed: `_probe` would return at once each sub-step
        latch = probing and not self._probe_latched
        if not latch:  # the usual cycle: the kernel's sub-steps (virtual_bus/drive_kernel.py, compiled)
            if csp:
                cmd, pos, vel, t, _ = drive_kernel.csp_substeps(n, h, prev, span, kff_ff, kp, pos, vel, t, max_cps,
                                                                alpha, False, 0.0, 0.0)
            else:
                cmd, pos, vel, t, tv, _ = drive_kernel.csv_substeps(n, h, ramp, want, tv, pos, vel, t, max_cps, alpha, 0)
        else:
            for k in range(1, n + 1):  # the same sub-steps, the encoder index's edge tested on each
                if csp:
                    cmd = prev + span * k / n
                    v_cmd = kff_ff + kp * (cmd - pos)
                else:
                    tv += max(-ramp, min(ramp, want - tv))
                    v_cmd, cmd = tv, pos  # CSV: the command follows the actual position
                if not -max_cps <= v_cmd <= max_cps:
                    v_cmd = max(-max_cps, min(max_cps, v_cmd))
                if v_cmd != vel:
                    vel += (v_cmd - vel) * alpha
                new_pos = pos + vel * h
                if latch:
                    self._probe(pos, new_pos)
                    latch = not self._probe_latched
                pos = new_pos
                t += h
        if not csp:
            self.target_velocity = tv
        self.command = cmd
        self.position, self.velocity, self.time = pos, vel, t
        self._no_limit()
        if not probing:
            self._probe_latched = False

    def _step_general(self, n: int, h: float, prev: float, target: float, ff_vel: float, max_cps: float,
                      alpha: float, energised: bool, csp: bool, csv: bool, profile: bool, direct: bool,
                      limited: bool, probing: bool) -> None:
        p = self.params
        for k in range(1, n + 1):
            if not energised:
                # Brake engaged / motor free: friction stops it within a few ms.
                self.velocity *= math.exp(-h * 400.0)
                v_cmd = self.velocity
                self.command = self.position
            elif csp:
                self.command = prev + (target - prev) * k / n
                v_cmd = p.kff * ff_vel + p.kp * (self.command - self.position)
            elif profile:
                v_cmd = self.modes.velocity_command(self, h)
            elif csv:
                want = self._want_cps
                step = p.csv_accel * h
                self.target_velocity += max(-step, min(step, want - self.target_velocity))
                v_cmd = self.target_velocity
                self.command = self.position
            else:  # quick stop or fault reaction: the drive ramps speed down itself at 0x6085
                step = p.quick_stop_decel * h
                self.velocity -= max(-step, min(step, self.velocity))
                v_cmd = self.velocity
                self.command = self.position
            v_cmd = max(-max_cps, min(max_cps, v_cmd))
            if energised and v_cmd != self.velocity:
                self.velocity = v_cmd if direct else self.velocity + (v_cmd - self.velocity) * alpha
            new_pos = self.position + self.velocity * h
            if limited:
                new_pos = self._limit(new_pos)
            else:
                self._no_limit()
            if probing:
                self._probe(self.position, new_pos)
            else:
                self._probe_latched = False
            self.position = new_pos
            self.time += h

    def _no_limit(self) -> None:
        """_limit on a drive without limit switches: only a stale limit alarm code is cleared."""
        self._limit_flags = 0
        if self.error_code in (AL_REVERSE_LIMIT, AL_FORWARD_LIMIT) and self.state is not State.FAULT:
            self.error_code = 0

    def _limit(self, new_pos: float) -> float:
        p = self.params
        self._limit_flags = 0
        if p.negative_limit is not None and new_pos <= p.negative_limit:
            self._limit_flags |= 0x1
            if new_pos < self.position or new_pos < p.negative_limit:
                new_pos = max(new_pos, min(self.position, float(p.negative_limit)))
                self.velocity = max(self.velocity, 0.0)
                self.error_code = AL_REVERSE_LIMIT
        if p.positive_limit is not None and new_pos >= p.positive_limit:
            self._limit_flags |= 0x2
            if new_pos > self.position or new_pos > p.positive_limit:
                new_pos = min(new_pos, max(self.position, float(p.positive_limit)))
                self.velocity = min(self.velocity, 0.0)
                self.error_code = AL_FORWARD_LIMIT
        if not self._limit_flags and self.error_code in (AL_REVERSE_LIMIT, AL_FORWARD_LIMIT) \
                and self.state is not State.FAULT:
            self.error_code = 0
        return new_pos

    def _probe(self, old: float, new: float) -> None:
        """Touch probe 1 latches the encoder index (0x60B8 bit 0 enable, bit 2 = index source)."""
        tp = self._rx.touch_probe_function
        if not tp & 1:
            self._probe_latched = False
            return
        if self._probe_latched:
            return
        pp = self.params.probe_position
        if pp is not None:  # a probe wired to touch probe 1 (G31): latch the encoder at the switch point
            if old != new and (old - pp) * (new - pp) <= 0:
                self._probe_pos = int(pp)
                self._probe_latched = True
            return
        every = self.params.index_pulse_every or self.params.counts_per_rev
        a, b = math.floor(old / every), math.floor(new / every)
        if a != b:
            edge = max(a, b) * every
            self._probe_pos = int(edge)
            self._probe_latched = True

    def _supervise(self) -> None:
        p = self.params
        if self.state is State.OPERATION_ENABLED and self.mode == 8:
            if abs(self.command - self.position) > p.following_error_window:
                self.fault(AL_FOLLOWING_ERROR)
        if abs(self.velocity) > 1.2 * self._max_cps:
            self.fault(AL_OVERSPEED)
        if self.state is State.QUICK_STOP_ACTIVE and abs(self.velocity) < 1:
            self.state = State.SWITCH_ON_DISABLED
        if self.state is State.FAULT_REACTION_ACTIVE and abs(self.velocity) < 1:
            self.state = State.FAULT
