"""The CiA 402 modes a Delta ASDA-E drive runs besides CSP and CSV: profile position (1), profile
velocity (3), homing (6) and cyclic synchronous torque (10), with their objects.

`Cia402Drive` (virtual_bus/drive.py) keeps the state machine, the loops and the physics; it asks
`DriveModes` for the velocity command of each sub-step while one of these modes is active, and for
the mode's statusword bits. Both buses store the objects below in `ModeObjects` (`MODE_OBJECTS` maps
index/subindex to the field), so EtherCAT and CANopen share one numeric core.

Units are Delta's (ASDA-A3 manual, CoE/CANopen object list; docs/decisions/ethercat.md E15):
positions in PUU (= counts here), 0x6081 profile velocity in PUU/s, 0x6083/0x6084/0x609A as the time
in ms to go from 0 to 3000 rpm, 0x6099 homing speeds in 0.1 rpm, torques in 0.1 % of rated torque.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING

from fieldbus.cia402 import SW_FOLLOWING, SW_FOLLOWING_ERROR, SW_TARGET_REACHED
from virtual_bus.servo_params import ServoParamError  # an SDO refused, with its abort code (.code)

if TYPE_CHECKING:
    from virtual_bus.drive import Cia402Drive

PP, PV, HM, CSP, CSV, CST = 1, 3, 6, 8, 9, 10
SUPPORTED_MODES = (PP, PV, HM, CSP, CSV, CST)
SUPPORTED_MASK = sum(1 << (m - 1) for m in SUPPORTED_MODES)  # 0x6502 = 0x000003A5
PROFILE_MODES = frozenset((PP, PV, HM, CST))

# controlword bits of the operation modes (CiA 402-2)
CW_NEW_SETPOINT = 1 << 4  # PP: new set-point; HM: homing operation start
CW_CHANGE_IMMEDIATELY = 1 << 5
CW_RELATIVE = 1 << 6
CW_HALT = 1 << 8
# statusword bits of the operation modes
SW_SETPOINT_ACK = SW_FOLLOWING  # bit 12 — PP set-point acknowledge, HM homing attained, PV speed = 0
SW_HOMING_ERROR = SW_FOLLOWING_ERROR  # bit 13

RPM_REF = 3000.0  # 0x6083/0x6084/0x609A: ms from 0 to this speed (Delta)
HOMING_METHODS = (1, 2, 3, 4, 5, 6, 17, 18, 19, 20, 21, 22, 33, 34, 35, 37)


@dataclass
class ModeObjects:
    """The objects of the profile modes, raw as they travel over SDO; defaults are the packaged ESI's/EDS's."""

    profile_velocity: int = 1_000_000  # 0x6081, PUU/s
    profile_acceleration: int = 200  # 0x6083, ms 0 → 3000 rpm
    profile_deceleration: int = 200  # 0x6084
    home_offset: int = 0  # 0x607C, PUU: position actual at the home position
    homing_method: int = 0  # 0x6098 (0 = none assigned)
    homing_speed_switch: int = 1000  # 0x6099:1, 0.1 rpm
    homing_speed_zero: int = 200  # 0x6099:2, 0.1 rpm
    homing_acceleration: int = 200  # 0x609A, ms 0 → 3000 rpm
    max_torque: int = 3000  # 0x6072, 0.1 % rated
    positive_torque_limit: int = 3000  # 0x60E0
    negative_torque_limit: int = 3000  # 0x60E1
    min_position_limit: int = -0x80000000  # 0x607D:1, PUU (both at their extremes: no software limit)
    max_position_limit: int = 0x7FFFFFFF  # 0x607D:2
    gear_motor: int = 1  # 0x6091:1 motor revolutions
    gear_shaft: int = 1  # 0x6091:2 shaft revolutions
    quick_stop_option: int = 2  # 0x605A


MODE_OBJECTS: dict[tuple[int, int], str] = {
    (0x6081, 0): "profile_velocity", (0x6083, 0): "profile_acceleration", (0x6084, 0): "profile_deceleration",
    (0x607C, 0): "home_offset", (0x6098, 0): "homing_method", (0x6099, 1): "homing_speed_switch",
    (0x6099, 2): "homing_speed_zero", (0x609A, 0): "homing_acceleration", (0x6072, 0): "max_torque",
    (0x60E0, 0): "positive_torque_limit", (0x60E1, 0): "negative_torque_limit",
    (0x607D, 1): "min_position_limit", (0x607D, 2): "max_position_limit",
    (0x6091, 1): "gear_motor", (0x6091, 2): "gear_shaft", (0x605A, 0): "quick_stop_option",
}
assert set(MODE_OBJECTS.values()) == {f.name for f in fields(ModeObjects)}
# their CoE/CANopen data types, as struct formats (the packaged ESI and EDS give the same)
FORMATS: dict[tuple[int, int], str] = {
    (0x6081, 0): "<I", (0x6083, 0): "<I", (0x6084, 0): "<I", (0x607C, 0): "<i", (0x6098, 0): "<b",
    (0x6099, 1): "<I", (0x6099, 2): "<I", (0x609A, 0): "<I", (0x6072, 0): "<H", (0x60E0, 0): "<H",
    (0x60E1, 0): "<H", (0x607D, 1): "<i", (0x607D, 2): "<i", (0x6091, 1): "<I", (0x6091, 2): "<I", (0x605A, 0): "<h",
}
ABORT_VALUE_RANGE = 0x06090030
ABORT_TYPE_LENGTH = 0x06070010


def check_value(index: int, sub: int, value: int, objects: ModeObjects) -> bool:
    """Whether the drive takes `value` for a mode object (False: abort 0x06090030, value range).
    Advertise only what runs: homing methods the model implements, an electronic gear of 1:1 (the
    bench's counts are PUU), quick stop option 2 (quick-stop ramp 0x6085, then switch on disabled)."""
    if index == 0x6098:
        return value == 0 or value in HOMING_METHODS
    if index == 0x6091:
        other = objects.gear_shaft if sub == 1 else objects.gear_motor
        return value > 0 and value == other
    if index == 0x605A:
        return value == 2
    if index in (0x6083, 0x6084, 0x609A):
        return value > 0
    return True


POSITION_WINDOW = 100  # PUU: 0x6067 position window (Delta default)


def _cps(drive: Cia402Drive, raw: float) -> float:
    """counts/s from the drive's velocity units (0x6099, 0x606D: 0.1 rpm)."""
    return drive.params.units.raw_to_velocity(raw, drive.params.counts_per_rev)


def accel_of(ms: int, counts_per_rev: int) -> float:
    """counts/s² from Delta's 'ms from 0 to 3000 rpm'."""
    return RPM_REF / 60.0 * counts_per_rev / (max(1, ms) / 1000.0)


@dataclass
class _Homing:
    """One homing run: the switch it looks for, the direction and edge of its final approach."""

    switch: str  # "home", "neg", "pos", "index" or "here"
    final_dir: int  # +1 / -1
    to_active: bool  # the edge: the switch becomes active (True) or inactive moving in final_dir
    index: bool  # then on to the next index pulse
    phase: str = "start"  # start, search, approach, index, back, done, error
    home: float = 0.0  # physical counts of the home position once found


# method → (switch, final direction, edge becomes active, index pulse after the edge) — CiA 402-2 §10.7
_METHODS: dict[int, tuple[str, int, bool, bool]] = {
    1: ("neg", +1, False, True), 2: ("pos", -1, False, True), 17: ("neg", +1, False, False),
    18: ("pos", -1, False, False),
    3: ("home+", -1, False, True), 4: ("home+", +1, True, True), 19: ("home+", -1, False, False),
    20: ("home+", +1, True, False),
    5: ("home", +1, False, True), 6: ("home", -1, True, True), 21: ("home", +1, False, False),
    22: ("home", -1, True, False),
    33: ("index", -1, True, True), 34: ("index", +1, True, True), 35: ("here", 0, True, False),
    37: ("here", 0, True, False),
}


@dataclass
class DriveModes:
    """Set-point generators of PP, PV, HM and CST, stepped by the drive once per sub-step."""

    objects: ModeObjects = field(default_factory=ModeObjects)
    origin: float = 0.0  # PUU of position actual minus the physical counts (set by homing)
    cmd: float = 0.0  # the generator's position, physical counts
    vel: float = 0.0  # its velocity, counts/s
    target: float | None = None  # PP: the set-point in progress (physical counts)
    pending: float | None = None  # PP: a set-point buffered behind it
    ack: bool = False  # PP set-point acknowledge / buffer full
    homing: _Homing | None = None
    homed: bool = False
    torque_cmd: float = 0.0  # CST: 0.1 % rated
    _cw: int = 0
    _seen: float = 0.0  # HM: the encoder position at the previous sub-step
    _fresh: bool = True  # the generator starts from the drive's actual state

    # ---- SDO on the in-process bench (SimLink); the buses keep their own object dictionaries --------
    def holds(self, index: int, sub: int) -> bool:
        return (index, sub) in MODE_OBJECTS

    def sdo_read(self, index: int, sub: int = 0) -> bytes:
        return struct.pack(FORMATS[(index, sub)], getattr(self.objects, MODE_OBJECTS[(index, sub)]))

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        fmt = FORMATS[(index, sub)]
        if len(data) != struct.calcsize(fmt):
            raise ServoParamError(ABORT_TYPE_LENGTH, f"object 0x{index:04X}:{sub}: {len(data)} data bytes")
        value = struct.unpack(fmt, data)[0]
        if not check_value(index, sub, value, self.objects):
            raise ServoParamError(ABORT_VALUE_RANGE, f"object 0x{index:04X}:{sub}: {value} is not taken")
        setattr(self.objects, MODE_OBJECTS[(index, sub)], value)

    def reset(self) -> None:
        """Power-on (CANopen Reset Node): the objects back to their defaults, the origin lost."""
        self.__init__()  # type: ignore[misc]

    # ---- latched outputs -----------------------------------------------------------------------
    def restart(self, cw: int) -> None:
        """Enable or mode change: the generators take over where the drive stands; a controlword bit
        already set then is no edge."""
        self._cw = cw
        self._fresh = True
        self.target = self.pending = None
        self.ack = False
        self.homing = None

    def apply(self, drive: Cia402Drive, cw: int, target_position: int, target_torque: int) -> None:
        """A new controlword and targets (one per bus cycle or SDO write): PP set-points, homing start."""
        rising = cw & ~self._cw
        falling = self._cw & ~cw
        self._cw = cw
        self.torque_cmd = float(target_torque)
        mode = drive.mode
        if mode == PP:
            if rising & CW_NEW_SETPOINT and not self.ack:
                goal = float(target_position) - self.origin
                if cw & CW_RELATIVE:
                    goal += self.target if self.target is not None else self.cmd
                lo, hi = self.objects.min_position_limit, self.objects.max_position_limit
                if lo < hi:  # 0x607D: the set-point is clipped to the software limits
                    goal = min(max(goal, lo - self.origin), hi - self.origin)
                if self.target is None or cw & CW_CHANGE_IMMEDIATELY:
                    self.target = goal
                else:
                    self.pending = goal
                self.ack = True
            elif falling & CW_NEW_SETPOINT:
                self.ack = False
        elif mode == HM:
            if rising & CW_NEW_SETPOINT:
                self._start_homing(drive)
            elif falling & CW_NEW_SETPOINT and self.homing is not None and self.homing.phase not in ("done", "error"):
                self.homing.phase = "interrupted"

    def _start_homing(self, drive: Cia402Drive) -> None:
        method = self.objects.homing_method
        if method not in _METHODS:
            self.homing = _Homing("here", 0, True, False, phase="error")
            return
        self.homed = False
        self.homing = _Homing(*_METHODS[method])

    # ---- per sub-step --------------------------------------------------------------------------
    def velocity_command(self, drive: Cia402Drive, h: float) -> float:
        """The velocity the drive's loop follows this sub-step (counts/s)."""
        p = drive.params
        if self._fresh:
            self.cmd, self.vel, self._seen, self._fresh = drive.position, drive.velocity, drive.position, False
        mode = drive.mode
        cpr = p.counts_per_rev
        if mode == CST:
            return self._torque_velocity(drive, h)
        if mode == PV:
            want = 0.0 if self._cw & CW_HALT else drive._want_cps
            acc = accel_of(self.objects.profile_acceleration, cpr)
            dec = accel_of(self.objects.profile_deceleration, cpr)
            self._ramp(want, acc, dec, h)
        elif mode == PP:
            self._step_pp(drive, h)
        else:
            self._step_homing(drive, h)
        drive.command = self.cmd
        return p.kff * self.vel + p.kp * (self.cmd - drive.position)

    def _ramp(self, want: float, acc: float, dec: float, h: float) -> None:
        rate = acc if abs(want) > abs(self.vel) and want * self.vel >= 0 else dec
        self.vel += max(-rate * h, min(rate * h, want - self.vel))
        self.cmd += self.vel * h

    def _move(self, goal: float, vmax: float, acc: float, dec: float, h: float) -> bool:
        """One sub-step towards `goal` on a trapezoid (decelerating in time: v ≤ √(2·dec·distance)); True there."""
        rest = goal - self.cmd
        if abs(rest) < 0.5 and abs(self.vel) <= dec * h:
            self.cmd, self.vel = goal, 0.0
            return True
        direction = math.copysign(1.0, rest)
        v = self.vel * direction  # speed towards the goal (negative: moving away)
        limit = min(vmax, math.sqrt(2.0 * dec * abs(rest)))
        v = v + acc * h if v < limit else max(limit, v - dec * h)
        v = min(v, limit, abs(rest) / h)
        self.vel = v * direction
        self.cmd += self.vel * h
        return False

    def _step_pp(self, drive: Cia402Drive, h: float) -> None:
        o, cpr = self.objects, drive.params.counts_per_rev
        acc, dec = accel_of(o.profile_acceleration, cpr), accel_of(o.profile_deceleration, cpr)
        if self._cw & CW_HALT or self.target is None:
            self._ramp(0.0, acc, dec, h)
            return
        vmax = min(float(o.profile_velocity), drive._max_cps)
        if self._move(self.target, vmax, acc, dec, h) and self.pending is not None:
            self.target, self.pending = self.pending, None

    def _switch(self, drive: Cia402Drive, kind: str, pos: float) -> bool:
        p = drive.params
        if kind == "neg":
            return p.negative_limit is not None and pos <= p.negative_limit
        if kind == "pos":
            return p.positive_limit is not None and pos >= p.positive_limit
        # The drive's home input (0x60FD bit 2) reads active below the switch edge (DriveParams.home_switch).
        return p.home_switch is not None and pos < p.home_switch

    def _step_homing(self, drive: Cia402Drive, h: float) -> None:
        o, p, hm = self.objects, drive.params, self.homing
        cpr = p.counts_per_rev
        acc = accel_of(o.homing_acceleration, cpr)
        fast = _cps(drive, o.homing_speed_switch)
        slow = _cps(drive, o.homing_speed_zero)
        if hm is None or hm.phase in ("done", "error", "interrupted") or self._cw & CW_HALT:
            self._ramp(0.0, acc, acc, h)
            return
        if hm.phase == "back":  # after the home position was found: stop and return onto it
            if self._move(hm.home, slow, acc, acc, h):
                hm.phase = "done"
                self.homed = True
            return
        if hm.switch == "here":
            self._found(drive, self.cmd)
            return
        # Switches and the index are judged on the encoder (the physical position), not the set-point.
        before, pos = self._seen, drive.position
        self._seen = pos
        kind = hm.switch.rstrip("+")
        if hm.phase == "start":
            if kind == "index":
                hm.phase = "index"
            else:
                # already on the side the final approach starts from?
                hm.phase = "approach" if self._switch(drive, kind, pos) != hm.to_active else "search"
            before = pos
        if hm.phase == "search":  # away from the final direction until the switch changes state
            self._ramp(-hm.final_dir * fast, acc, acc, h)
            if self._switch(drive, kind, before) != self._switch(drive, kind, pos):
                hm.phase = "approach"
                self.cmd = pos  # turn round from where the axis is (it may stand on a limit switch)
        elif hm.phase == "approach":
            self._ramp(hm.final_dir * slow, acc, acc, h)
            now = self._switch(drive, kind, pos)
            if self._switch(drive, kind, before) != now and now == hm.to_active:
                if hm.index:
                    hm.phase = "index"
                else:
                    self._found(drive, self._edge(drive, kind, pos))
        elif hm.phase == "index":
            self._ramp(hm.final_dir * slow, acc, acc, h)
            every = p.index_pulse_every or cpr
            a, b = math.floor(before / every), math.floor(pos / every)
            if a != b:
                self._found(drive, max(a, b) * every)
        # A limit switch the method does not look for ends the homing with an error (CiA 402: bit 13).
        if hm.phase not in ("back", "done") and kind not in ("neg", "pos") and (
                self._switch(drive, "neg", pos) or self._switch(drive, "pos", pos)):
            hm.phase = "error"

    def _edge(self, drive: Cia402Drive, kind: str, near: float) -> float:
        p = drive.params
        edge = {"neg": p.negative_limit, "pos": p.positive_limit}.get(kind, p.home_switch)
        return float(edge) if edge is not None else near

    def _found(self, drive: Cia402Drive, home: float) -> None:
        """The home position: from now on position actual reads 0x607C there."""
        hm = self.homing
        assert hm is not None
        hm.home = home
        self.origin = self.objects.home_offset - home
        hm.phase = "back"

    def _torque_velocity(self, drive: Cia402Drive, h: float) -> float:
        """CST: the motor accelerates by target torque minus friction over inertia (0x6072, 0x60E0/E1 clip it)."""
        p, o = drive.params, self.objects
        t = max(-min(o.max_torque, o.negative_torque_limit), min(min(o.max_torque, o.positive_torque_limit),
                                                                   self.torque_cmd))
        if self._cw & CW_HALT:
            t = 0.0
        rad = 2.0 * math.pi / p.counts_per_rev
        w = drive.velocity * rad
        friction = p.viscous * w + (math.copysign(p.coulomb, w) if abs(drive.velocity) > 1 else 0.0)
        torque = t / 1000.0 * p.rated_torque
        if abs(drive.velocity) <= 1 and abs(torque) <= p.coulomb:
            friction = torque  # static friction holds the shaft
        a = (torque - friction) / p.inertia / rad
        self.cmd = drive.position
        return drive.velocity + a * h

    # ---- statusword ------------------------------------------------------------------------------
    def status_bits(self, drive: Cia402Drive) -> int:
        """Bits 10, 12, 13 of the statusword in operation enabled, per mode (CiA 402-2)."""
        mode = drive.mode
        standing = abs(drive.velocity) < 0.001 * drive._max_cps and abs(self.vel) < 1e-9
        if mode == PP:
            sw = SW_SETPOINT_ACK if self.ack else 0
            halted = bool(self._cw & CW_HALT)
            on_target = self.target is not None and abs(self.cmd - self.target) < 0.5 \
                and abs(drive.position - self.target) <= POSITION_WINDOW
            if standing and (halted or on_target or self.target is None):
                sw |= SW_TARGET_REACHED
            if abs(self.cmd - drive.position) > drive.params.following_error_window:
                sw |= SW_HOMING_ERROR
            return sw
        if mode == PV:
            sw = 0
            want = 0.0 if self._cw & CW_HALT else drive._want_cps
            window = _cps(drive, 100)  # 0x606D default: 10 rpm
            if abs(drive.velocity - want) <= window:
                sw |= SW_TARGET_REACHED
            if abs(drive.velocity) <= window:  # 0x606F threshold: "speed = 0"
                sw |= SW_SETPOINT_ACK
            return sw
        if mode == HM:
            hm = self.homing
            if hm is None:
                return SW_TARGET_REACHED | (SW_SETPOINT_ACK if self.homed else 0)  # not started (or done before)
            if hm.phase == "error":
                return SW_HOMING_ERROR | (SW_TARGET_REACHED if standing else 0)
            if hm.phase == "interrupted":
                return SW_TARGET_REACHED
            if hm.phase == "done":
                there = standing and abs(drive.position - hm.home) <= POSITION_WINDOW
                return SW_SETPOINT_ACK | (SW_TARGET_REACHED if there else 0)
            return 0
        if mode == CST:
            return SW_FOLLOWING if not self._cw & CW_HALT else 0
        return 0
