"""The user scan API: what an MLC program (a Python module) sees once per scan.

An MLC program is a module (or any object) with

    def scan(mlc: ScanContext) -> None          # required, called once per bench cycle
    def setup(mlc: ScanContext) -> None         # optional, called once before the first scan

Inside `scan` it reads inputs and writes outputs through `mlc`:

    mlc.m("M_STROBE")          # a relay by App. B name (this channel) or address ("M31064")
    mlc.set("MST_FINISH")      # set / clear a relay: mlc.set(name, False)
    mlc.d("M_CODE")            # a D register, read with the signal's width (u16/s16/u32/f32)
    mlc.put("SPINDLE_ANALOG_1", 500)
    mlc.rising("M_STROBE")     # True in the one scan where the relay went 0 → 1
    mlc.timer("turret", 0.5, running)  # on-delay timer (TON): True once `running` held 0.5 s
    mlc.alarm(12)              # raise user alarm A12 (mlc.alarm(12, False) clears it)
    mlc.io.out(0, 3, True)     # remote I/O module 0, digital output 3; mlc.io.inp(0, 1); analog words
    mlc.x(3), mlc.y(3, True)   # remote I/O by device: input X3, output Y3 (the bench's [[io]] mapping)
    mlc.state                  # a dict that survives between scans, for the program's own data
    mlc.time, mlc.dt, mlc.scan_count

See docs/guide/mlc.md for a worked example.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mlc.memory import DeviceMemory
from mlc.on_change import AREA_IO_INPUTS, AREA_M, AREA_WORDS, AREA_X, AREA_Y, TIMER_EPS, ScanRecord, y_point
from mlc.signals import Signal, resolve

if TYPE_CHECKING:  # a bench with remote I/O builds its maps (hil/bench_file.py); a run without loads none (B84)
    from mlc.remote_io import IoMap


@dataclass
class RemoteIo:
    """Remote I/O modules as the MLC sees them: digital points per module, and the four analog
    words per module of App. B (D20200+4k outputs, D30200+4k inputs). A module with an `IoMap`
    (a bench [[io]] station) keeps its points in X/Y devices, so `inp`/`out` and `mlc.x`/`mlc.y`
    are the same bits."""

    mem: DeviceMemory
    inputs: list[int] = field(default_factory=list)  # digital input image per module (bit mask)
    outputs: list[int] = field(default_factory=list)
    maps: list[IoMap] = field(default_factory=list)  # module k → its X/Y range (mlc/remote_io.py)
    _rec: ScanRecord | None = None  # the scan being recorded (mlc/on_change.py), else None

    def _map(self, module: int) -> IoMap | None:
        return self.maps[module] if module < len(self.maps) else None

    def inp(self, module: int, point: int) -> bool:
        m, rec = self._map(module), self._rec
        if m is not None:
            if point >= m.inputs:
                return False
            if rec is not None:
                rec.read(AREA_X, m.x + point, self.mem.x[m.x + point])
            return bool(self.mem.x[m.x + point])
        if module >= len(self.inputs):
            if rec is not None:
                rec.dirty = True  # a module that may appear later: nothing to compare with
            return False
        if rec is not None:
            rec.read(AREA_IO_INPUTS, module, self.inputs[module])
        return bool(self.inputs[module] >> point & 1)

    def out(self, module: int, point: int, on: bool | None = None) -> bool:
        m = self._map(module)
        if m is not None:
            if point >= m.outputs:
                return False  # a point the station does not have: nothing to switch
            return y_point(self.mem.y, m.y + point, on, self._rec)
        while module >= len(self.outputs):
            self.outputs.append(0)
        if on is not None:
            mask = 1 << point
            new = (self.outputs[module] | mask) if on else (self.outputs[module] & ~mask)
            if self._rec is not None and new != self.outputs[module]:
                self._rec.dirty = True
            self.outputs[module] = new
        return bool(self.outputs[module] >> point & 1)  # only the program writes it: no read to record

    def analog_in(self, module: int, word: int) -> int:
        n = 30200 + 4 * module + word
        if self._rec is not None:
            self._rec.read(AREA_WORDS, n, self.mem.words[n])
        return self.mem.s16(n)

    def analog_out(self, module: int, word: int, value: int) -> None:
        n = 20200 + 4 * module + word
        before = self.mem.words[n]
        self.mem.set_s16(n, value)
        if self._rec is not None and self.mem.words[n] != before:
            self._rec.dirty = True


@dataclass
class ScanContext:
    mem: DeviceMemory
    channel: int = 1
    dt: float = 0.001
    time: float = 0.0
    scan_count: int = 0
    state: dict[str, Any] = field(default_factory=dict)
    io: RemoteIo | None = None
    params: dict[str, Any] = field(default_factory=dict)  # machine data for the program (max rpm, …)
    _prev: dict[str, bool] = field(default_factory=dict)
    _timers: dict[str, float] = field(default_factory=dict)
    _sig: dict[str, Signal] = field(default_factory=dict)
    _rec: ScanRecord | None = None  # the scan being recorded (mlc/on_change.py), else None

    def __post_init__(self) -> None:
        if self.io is None:
            self.io = RemoteIo(self.mem)

    def signal(self, spec: str) -> Signal:
        sig = self._sig.get(spec)
        if sig is None:
            sig = self._sig[spec] = resolve(spec, self.channel)
        return sig

    # ---- relays ------------------------------------------------------------------------------
    def m(self, spec: str) -> bool:
        sig = self.signal(spec)
        rec = self._rec
        if sig.kind in ("X", "Y"):
            if rec is not None:
                area = self.mem.x if sig.kind == "X" else self.mem.y
                rec.read(AREA_X if sig.kind == "X" else AREA_Y, sig.number, area[sig.number])
            return bool(self.mem.get(sig.address))
        if rec is not None:
            rec.read(AREA_M, sig.number, self.mem.m[sig.number])
        return self.mem.bit(sig.number)

    def set(self, spec: str, on: bool = True) -> None:
        sig = self.signal(spec)
        mem, rec = self.mem, self._rec
        if sig.kind in ("X", "Y"):
            area = mem.x if sig.kind == "X" else mem.y
            if rec is not None and area[sig.number] != (1 if on else 0):
                rec.dirty = True
            mem.put(sig.address, on)
        else:
            if rec is not None and mem.m[sig.number] != (1 if on else 0):
                rec.dirty = True
            mem.set_bit(sig.number, on)

    # ---- remote I/O points (X inputs, Y outputs) -------------------------------------------------
    def x(self, n: int) -> bool:
        """Remote input X<n>, as read from its module at the start of this scan."""
        if self._rec is not None:
            self._rec.read(AREA_X, n, self.mem.x[n])
        return bool(self.mem.x[n])

    def y(self, n: int, on: bool | None = None) -> bool:
        """Remote output Y<n>: set it (on=True/False) or read back what this program last wrote."""
        return y_point(self.mem.y, n, on, self._rec)

    def rising(self, spec: str) -> bool:
        now = self.m(spec)
        before = self._prev.get(spec, False)
        self._prev[spec] = now
        return now and not before

    def falling(self, spec: str) -> bool:
        key = "~" + spec
        now = self.m(spec)
        before = self._prev.get(key, False)
        self._prev[key] = now
        return before and not now

    # ---- registers ------------------------------------------------------------------------------
    def d(self, spec: str) -> float:
        sig = self.signal(spec)
        n, mem = sig.number, self.mem
        w = sig.width  # no per-call dict of bound methods: user scans read registers every cycle
        rec = self._rec
        if rec is not None:
            rec.read(AREA_WORDS, n, mem.words[n])
            if w in ("f32", "u32"):
                rec.read(AREA_WORDS, n + 1, mem.words[n + 1])
        if w == "f32":
            return mem.f32(n)
        if w == "u32":
            return mem.u32(n)
        if w == "s16":
            return mem.s16(n)
        return mem.u16(n)

    def put(self, spec: str, value: float) -> None:
        sig = self.signal(spec)
        n, mem = sig.number, self.mem
        rec = self._rec
        if rec is not None:
            before = mem.words[n:n + 2].tobytes()
        if sig.width == "f32":
            mem.set_f32(n, value)
        elif sig.width == "u32":
            mem.set_u32(n, int(value))
        else:
            mem.set_u16(n, int(value))
        if rec is not None and mem.words[n:n + 2].tobytes() != before:
            rec.dirty = True

    # ---- timers and alarms ----------------------------------------------------------------------
    def timer(self, name: str, seconds: float, run: bool) -> bool:
        """On-delay timer: True once `run` has been held for `seconds` (resets when `run` drops)."""
        if not run:
            self._timers.pop(name, None)
            return False
        start = self._timers.setdefault(name, self.time)
        due = self.time - start >= seconds - TIMER_EPS
        if not due and self._rec is not None:
            self._rec.timers.append((start, seconds))  # the scan changes when this comes due
        return due

    def alarm(self, n: int, on: bool = True) -> None:
        rec = self._rec
        if rec is not None and 0 <= n < len(self.mem.a) and self.mem.a[n] != (1 if on else 0):
            rec.dirty = True
        self.mem.set_alarm(n, on)
