"""Timed pokes at MLC devices during `hil run`: ``--at "t=1.1:pulse M21019"`` or ``--events FILE``.

Grammar (one event per ``--at`` or per line of an events file; ``#`` starts a comment)::

    EVENT   := TRIGGER ":" ACTION
    TRIGGER := "t=" SECONDS        simulated time since power-up (the trace's t column)
             | "cycle=" N          bench cycle N (the trace's cycle column)
             | "line=" N           the first cycle the channel executes program line N
             | AXIS "<" VALUE      the axis's actual machine position crosses below VALUE
             | AXIS ">" VALUE      … crosses above VALUE (it must have been on the other side first)
    ACTION  := "set" DEVICE "=" VALUE     M/X/Y/A: 0|1|on|off; D: an integer (a float for f32 registers)
             | "reset" DEVICE             the same as set DEVICE=0
             | "pulse" DEVICE             ON for one MLC scan, then OFF (relays and X/Y points)
             | "cycle-start" | "feed-hold" | "reset" | "interrupt"    the operator buttons (pulses)
             | "estop" | "estop-off"                                   M2x013 ON / OFF

DEVICE is an address (``M21019``, ``D21002``, ``X5``, ``Y0``, ``A3``) or an App. B name
(``FEED_OVERRIDE``); only what the MLC may write is accepted: the MLC → NC block (M2xxxx/D2xxxx),
ordinary M/D, user alarms A, remote inputs X (through the simulated terminal when an [[io]] station maps
the point) and outputs Y. NC → MLC status (M3xxxx/D3xxxx, the clock relays M29032-M29035) is refused.

Timing: an action fires at the end of a cycle and the MLC sees it in the next scan; that scan's time is
what the summary prints and the row where the trace's ``event`` column names it. A ``t=`` event lands on
the first scan at or after t; ``line=N`` on the scan after the first cycle of line N (the MLC learns the
NC's line one scan late, as on the controller). Each event fires once.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mlc.memory import DeviceError
from mlc.signals import NC_TO_MLC, Signal, m2, resolve
from mlc.tracing import value_of


class EventSpecError(ValueError):
    """A malformed event, or one the bench cannot carry out (unknown device, NC → MLC status …)."""


# ---- parsing ---------------------------------------------------------------------------------------
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
# ASCII digits only (B106): `\d` and float() also take '٥' and '1_0', which no NC5 screen or manual writes
_TIME = re.compile(rf"^t\s*=\s*({_NUM})$", re.IGNORECASE | re.ASCII)
_COUNT = re.compile(r"^(line|cycle)\s*=\s*(\d+)$", re.IGNORECASE | re.ASCII)
_AXIS = re.compile(rf"^([A-Za-z][A-Za-z0-9]*)\s*([<>])\s*({_NUM})$", re.ASCII)
_VALUE = re.compile(_NUM, re.ASCII)
_SET = re.compile(r"^set\s+(\S+?)\s*=\s*(\S+)$", re.IGNORECASE)
_ONE = re.compile(r"^(pulse|reset)\s+(\S+)$", re.IGNORECASE)


@dataclass(frozen=True)
class Trigger:
    kind: str  # "t" | "cycle" | "line" | "<" | ">"
    value: float
    axis: str = ""

    def __str__(self) -> str:
        if self.kind in ("<", ">"):
            return f"{self.axis}{self.kind}{self.value:g}"
        return f"{self.kind}={self.value:g}"


@dataclass(frozen=True)
class Action:
    verb: str  # "set" | "pulse"
    signal: Signal
    value: float | int = 1
    label: str = ""  # the operator name it came from ("feed-hold"), if any

    def __str__(self) -> str:
        what = (f"pulse {self.signal.address}" if self.verb == "pulse"
                else f"set {self.signal.address}={self.value:g}")
        return f"{self.label} ({what})" if self.label else what


@dataclass
class RunEvent:
    spec: str
    trigger: Trigger
    action: Action
    fired_time: float | None = None  # simulated time of the scan that saw it
    fired_cycle: int | None = None
    fired_line: int = 0


def parse_trigger(text: str, axes: Sequence[str]) -> Trigger:
    text = text.strip()
    if m := _TIME.match(text):
        t = float(m.group(1))
        if t < 0 or not math.isfinite(t):
            raise EventSpecError(f"trigger {text!r}: the time must be a finite number of seconds ≥ 0")
        return Trigger("t", t)
    if m := _COUNT.match(text):
        kind, n = m.group(1).lower(), int(m.group(2))
        if n < 1:  # line 0 is what the trace names before the program and after its end: it fired there
            raise EventSpecError(f"trigger {text!r}: " + ("program lines start at 1" if kind == "line"
                                                          else "bench cycles start at 1"))
        return Trigger(kind, n)
    if m := _AXIS.match(text):
        axis = m.group(1).upper()
        if axis not in axes:
            raise EventSpecError(f"trigger {text!r}: axis {axis} is not on the bench (axes: {', '.join(axes)})")
        return Trigger(m.group(2), float(m.group(3)), axis)
    raise EventSpecError(f"trigger {text!r}: expected t=SECONDS, line=N, cycle=N or AXIS<VALUE / AXIS>VALUE")


def writable_signal(device: str, channel: int) -> Signal:
    """The device an event may write; EventSpecError for an unknown one or NC → MLC status."""
    try:
        sig = resolve(device, channel)
    except DeviceError as exc:
        raise EventSpecError(str(exc)) from None
    if sig.direction == NC_TO_MLC:
        raise EventSpecError(f"{sig.address} ({sig.name}) is NC → MLC status, written by the NC every scan; "
                             "an event may only write MLC → NC devices (M2xxxx/D2xxxx), ordinary M/D, A, X or Y")
    return sig


def _value(text: str, sig: Signal) -> float | int:
    word = text.strip().lower()
    if sig.kind in ("M", "X", "Y", "A"):
        if word in ("1", "on", "true"):
            return 1
        if word in ("0", "off", "false"):
            return 0
        raise EventSpecError(f"{sig.address} is a bit: its value is 0/1 or on/off, not {text!r}")
    v = float(text) if _VALUE.fullmatch(text.strip()) else math.nan  # nan, inf, '٥', '1_0': not a number
    if not math.isfinite(v):  # 1e400 too; int() of it was an internal error (0x0000) at the run's first scan
        raise EventSpecError(f"{sig.address}: {text!r} is not a finite number")
    if sig.width == "f32":
        return v
    if v != int(v):
        raise EventSpecError(f"{sig.address} holds an integer ({sig.width}); {text!r} has a fraction")
    lo, hi = {"s16": (-0x8000, 0x7FFF), "u32": (-0x8000_0000, 0xFFFF_FFFF)}.get(sig.width, (0, 0xFFFF))
    if not lo <= v <= hi:
        raise EventSpecError(f"{sig.address} ({sig.width}) takes {lo}…{hi}, not {text}")
    return int(v)


def parse_action(text: str, channel: int) -> Action:
    from hil.scripting import ESTOP_RELAY, OPERATOR_BUTTONS

    text = text.strip()
    name = re.sub(r"[\s_]+", "-", text.lower())
    if name in OPERATOR_BUTTONS:
        return Action("pulse", writable_signal(f"M{m2(channel, OPERATOR_BUTTONS[name])}", channel), 1, name)
    if name in ("estop", "estop-off"):
        return Action("set", writable_signal(f"M{m2(channel, ESTOP_RELAY)}", channel), int(name == "estop"), name)
    if m := _SET.match(text):
        sig = writable_signal(m.group(1), channel)
        return Action("set", sig, _value(m.group(2), sig))
    if m := _ONE.match(text):
        sig = writable_signal(m.group(2), channel)
        if m.group(1).lower() == "reset":
            return Action("set", sig, 0)
        if sig.kind == "D":
            raise EventSpecError(f"pulse {sig.address}: a D register has no ON/OFF; use set {sig.address}=VALUE")
        return Action("pulse", sig, 1)
    raise EventSpecError(f"action {text!r}: expected set DEVICE=VALUE, reset DEVICE, pulse DEVICE or one of "
                         f"{', '.join(sorted(OPERATOR_BUTTONS))}, estop, estop-off")


def parse_event(spec: str, axes: Sequence[str], channel: int = 1) -> RunEvent:
    trigger, sep, action = spec.partition(":")
    if not sep or not action.strip():
        raise EventSpecError(f"{spec!r}: expected TRIGGER:ACTION, e.g. \"t=1.1:pulse M21019\"")
    return RunEvent(spec.strip(), parse_trigger(trigger, axes), parse_action(action, channel))


def read_events_file(path: str) -> list[tuple[str, str]]:
    """(where, spec) per event line of an events file: ``FILE:LINE`` and the text without its comment."""
    p = Path(path)
    try:
        text = p.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise EventSpecError(f"cannot read events file {path}: {getattr(exc, 'strerror', None) or exc}") from None
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        spec = line.split("#", 1)[0].strip()
        if spec:
            out.append((f"{path}:{n}", spec))
    return out


def parse_events(at: Sequence[str], files: Sequence[str], axes: Sequence[str], channel: int = 1,
                 cycle_s: float | None = None) -> list[RunEvent]:
    """Every ``--at`` then every events file line, in order; EventSpecError names the bad one. `cycle_s`: the
    bench's cycle, to compare ``t=`` with ``cycle=`` triggers (refuse_after_estop)."""
    items = [("--at", s) for s in at] + [item for f in files for item in read_events_file(f)]
    events = []
    for where, spec in items:
        try:
            events.append(parse_event(spec, axes, channel))
        except EventSpecError as exc:
            raise EventSpecError(f"{where}: {exc}") from None
    refuse_after_estop(list(zip((w for w, _ in items), events)), cycle_s)
    return events


# What the operator does to recover from an E-stop; a run ends at its E-stop, so these can never act after it.
RECOVERY = ("estop-off", "reset", "cycle-start")


def _when(tr: Trigger, cycle_s: float | None) -> float | None:
    """The simulated time a t= / cycle= trigger fires at (None: it depends on the run, or on a cycle not given)."""
    if tr.kind == "t":
        return tr.value
    if tr.kind == "cycle" and cycle_s is not None:
        return tr.value * cycle_s
    return None


def refuse_after_estop(items: Sequence[tuple[str, RunEvent]], cycle_s: float | None) -> None:
    """EventSpecError for an ``estop-off``, ``reset`` or ``cycle-start`` timed after an ``estop`` (decision B58):
    the E-stop aborts the program (alarm 0x0401) and `hil run` ends once the drives stand, so such an event would
    only be reported as never fired. E-stop recovery is exercised with `hil script` (machine.estop(), reset())."""
    stops = [(w, e, t) for w, e in items if e.action.label == "estop" and (t := _when(e.trigger, cycle_s)) is not None]
    if not stops:
        return
    w0, first, t0 = min(stops, key=lambda s: s[2])
    for where, e in items:
        t = _when(e.trigger, cycle_s)
        if e.action.label in RECOVERY and t is not None and t > t0:
            raise EventSpecError(
                f"{where}: {e.spec!r} comes after the E-stop {first.spec!r} ({w0}), and a run ends at its E-stop: "
                "the NC aborts the program with alarm 0x0401 and `hil run` stops once the drives stand, so it could "
                "never act. Exercise E-stop recovery with `hil script` (machine.estop(), machine.estop(False), "
                "machine.reset()); see docs/guide/mlc.md")


# ---- playing them during the run ------------------------------------------------------------------
class EventPlayer:
    """The runner's `on_cycle` hook (wrapping the operator panel) and a trace source: an ``event`` column
    naming the actions the MLC saw first in that cycle's scan, and one column per device written."""

    def __init__(self, events: Sequence[RunEvent], mlc: Any, bench: Any, link: Any,
                 inner: Callable[[Any], None] | None = None, traced: Sequence[str] = ()) -> None:
        self.events = list(events)
        self.mlc = mlc
        self.inner = inner
        self._writers = {id(e): self._writer(e.action.signal, bench, link) for e in self.events}
        self._signals = list({e.action.signal.address: e.action.signal for e in self.events
                              if e.action.signal.address not in traced}.values())
        self.columns = ["event"] + [s.address for s in self._signals]
        self._release: list[RunEvent] = []  # pulses to drop after the scan that saw them
        self._labels: dict[int, list[str]] = {}  # cycle → what fired into its scan
        self._side: dict[int, bool] = {}  # AXIS</> events: was the condition false already?

    def _writer(self, sig: Signal, bench: Any, link: Any) -> Callable[[float | int], None]:
        """How to write this device: X points an [[io]] station maps go through its simulated terminal
        (the MLC reads them from the station every scan); everything else straight into device memory."""
        mem = self.mlc.mem
        if sig.kind == "X":
            from hil.remote_io import IoNotSimulated, io_terminal

            try:
                hit = io_terminal(bench, link, "X", sig.number)
            except IoNotSimulated as exc:
                raise EventSpecError(f"{sig.address}: {exc}") from None
            if hit is not None:
                station, point = hit
                return lambda v: station.set_input(point, bool(v))
        if sig.kind == "D":
            setter = {"f32": mem.set_f32, "u32": mem.set_u32}.get(sig.width, mem.set_u16)
            return lambda v: setter(sig.number, v)
        return lambda v: mem.put(sig.address, int(v))

    def __call__(self, runner: Any) -> None:
        if self.inner is not None:
            self.inner(runner)
        scanned = runner.channel is not None  # the MLC scans only once the channel exists
        if scanned:
            for e in self._release:
                self._writers[id(e)](0)
            self._release.clear()
        nxt = runner.time + runner.bench.cycle
        for e in self.events:
            if e.fired_cycle is None and self._due(e, runner):
                self._writers[id(e)](e.action.value)
                e.fired_time, e.fired_cycle, e.fired_line = nxt, runner.cycle + 1, runner.line
                self._labels.setdefault(e.fired_cycle, []).append(str(e.action))
                if e.action.verb == "pulse":
                    self._release.append(e)

    def _due(self, e: RunEvent, runner: Any) -> bool:
        tr = e.trigger
        if tr.kind == "t":
            return runner.time + runner.bench.cycle >= tr.value - 1e-9
        if tr.kind == "cycle":
            return runner.cycle + 1 >= tr.value
        if tr.kind == "line":
            return runner.channel is not None and runner.line == tr.value
        pos = float(runner.actual[runner.axes.index(tr.axis)])
        now = pos < tr.value if tr.kind == "<" else pos > tr.value
        if not now:
            self._side[id(e)] = True
        return now and self._side.get(id(e), False)

    def values(self, runner: Any) -> list[float | int | str]:
        labels = self._labels.pop(runner.cycle, [])
        return ["; ".join(labels)] + [value_of(self.mlc.mem, s) for s in self._signals]

    def summary(self) -> list[str]:
        fired = sorted((e for e in self.events if e.fired_cycle is not None), key=lambda e: e.fired_cycle)
        missed = [e for e in self.events if e.fired_cycle is None]
        why = self.why_unfired()
        head = f"events         {len(fired)} applied" + (f", {len(missed)} never triggered" if missed else "")
        out = [head]
        for e in fired:
            out.append(f"  t={e.fired_time:.3f} s  cycle {e.fired_cycle}  line {e.fired_line}  {e.action}"
                       f"   [{e.trigger}]")
        for e in missed:
            out.append(f"  never triggered: {e.spec}{why}")
        return out

    def why_unfired(self) -> str:
        """Why events after an E-stop never fired: the E-stop ended the run (decision B58); "" without one."""
        stop = next((e for e in self.events if e.action.label == "estop" and e.fired_time is not None), None)
        if stop is None:
            return ""
        return f"  (the E-stop at t={stop.fired_time:.3f} s ended the run)"


__all__ = ["EventPlayer", "EventSpecError", "RunEvent", "parse_event", "parse_events", "read_events_file"]
