"""Exercising scripts: drive the bench through the MLC's special relays, as an operator panel would.

A script is a Python file with ``def main(machine): ...`` (or top-level code using the global
``machine``). `hil script FILE.py` builds the bench, powers the drives up and hands the script a
`Machine`; afterwards it prints what every drive did. Everything the script does goes through the
NC5 special M/D devices (mode D2x000, jog M2x384…, MPG D2x008/D2x009 + pulses, home M2x320…,
cycle start M2x000 …) and the real NC channel, never around them.

    def main(machine):
        machine.mode("MPG")
        machine.mpg("X", pulses=100, ratio=10)     # 100 detents at ×10 → 1.000 mm
        machine.spindle(1200)                      # M03 S1200 through MDI
        machine.wait(1.0)
        machine.report()

Remote I/O (bench [[io]] stations): ``machine.set_input("X3")`` switches the simulated terminal,
``machine.get_output("Y0")`` reads one, ``machine.get("X3")`` / ``machine.set("Y0", 1)`` the MLC devices.
"""

from __future__ import annotations

import math
from numbers import Integral, Real
import runpy
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from hil.bench import Bench
from hil.remote_io import IoNotSimulated, attach_remote_io, io_terminal
from hil.runner import BenchRunner
from hil import script_args as arg
from hil.script_args import ScriptError
from hil.session import make_link
from hil.stop_signals import SignalStop
from mlc.machine import Mlc
from mlc.nc_link import MODE_NAMES
from mlc.signals import d2, d3, m2, m3
from nc.alarms import Alarm, NcAlarm
from nc.softlimits import SoftLimits
from nc.channel import Channel, RunState
from nc.interp import Interpreter
from nc.interrupt import m96_link
from nc.motion import Planner
from nc.profiles import make_profile
from nc.store import ProgramStore


# The operator's buttons: relay M2x<index> of the channel, pressed as a pulse (rising edge). Shared by
# the script API below and `hil run --at "t=…:feed-hold"` (hil/run_events.py).
OPERATOR_BUTTONS = {"cycle-start": 0, "feed-hold": 1, "reset": 4, "interrupt": 19}
ESTOP_RELAY = 13  # M2x013: emergency stop, a level (ON = stopped)


@dataclass
class OperatorPanel:
    """The operator: presses Cycle Start `resume_after` seconds after an M00/M01 hold."""

    mlc: Mlc
    resume_after: float | None = 0.5
    _held_since: float | None = None
    _pressed: bool = False

    def __call__(self, runner: BenchRunner) -> None:
        x, mem = self.mlc.link.x, self.mlc.mem
        if self._pressed:
            mem.set_bit(m2(x, 0), False)
            self._pressed = False
        m, b3 = mem.m, 30000 + 1000 * x  # M3x037 / M3x038 read straight from the bits: this runs every cycle
        if not (m[b3 + 37] or m[b3 + 38]) or self.resume_after is None:
            self._held_since = None
            return
        if self._held_since is None:
            self._held_since = runner.time
        if runner.time - self._held_since >= self.resume_after - 1e-12:
            mem.set_bit(m2(x, 0), True)
            self._pressed = True
            self._held_since = None


@dataclass
class DriveRecord:
    start: float = 0.0
    end: float = 0.0
    min: float = float("inf")
    max: float = float("-inf")
    peak_velocity: float = 0.0
    peak_rpm: float = 0.0
    modes: list[int] = field(default_factory=list)  # modes of operation seen (0x6061), in order


class Machine:
    """One bench, powered up, cycling in lock-step; the script's handle."""

    def __init__(self, bench: Bench, mlc: Mlc | None = None, link: Any = None, trace: Any = None) -> None:
        self.bench = bench
        self.mlc = mlc or Mlc(axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config(),
                              max_rpm=min((s.max_rpm for s in bench.spindles), default=6000.0))
        self.panel = OperatorPanel(self.mlc)
        self.link = link or make_link(bench)
        attach_remote_io(bench, self.mlc, self.link)  # [[io]] stations → X/Y devices (issue 8)
        self.runner = BenchRunner(bench, self.link, trace, self.mlc, on_cycle=self._on_cycle)
        self.x = self.mlc.link.x
        self.records: dict[str, DriveRecord] = {}
        self.watchers: list[Callable[["Machine"], None]] = []
        self._mpg_count = 0
        self._stopping = False  # a signal ended the script: the stop's own cycles run on (B96)
        self.alarms: list[Alarm] = []
        self.cleared: dict[int, float] = {}  # id(alarm) -> simulated time of the reset that cleared it (B59)

    # ---- life cycle ----------------------------------------------------------------------------
    def power_up(self) -> None:
        r = self.runner
        for name in self._names():
            self.records[name] = DriveRecord()
        if not r.power_up():
            raise ScriptError("; ".join(str(a) for a in r.result.alarms) or "drives did not enable")
        start = dict(zip(r.axes, r.actual.tolist()))
        r.channel = Channel(Planner(self.bench.motion_config(), start, spindle_rpm=lambda: self.mlc.spindle.rpm))
        # the bench's soft limits hold for the manual modes too (App. A 0x0A01-0x0A04, nc.softlimits)
        r.channel.soft_limits = SoftLimits.for_bench(self.bench, make_profile(self.bench.profile, r.axes, self.bench.params))
        self.mlc.manual.position[:] = r.actual
        self.mlc.manual.take_over(r.actual.copy())
        self.mlc.manual.home_input = r.home_input  # NC-side homing on the drive's home switch (issue 5)
        self.mlc.manual.shift_origin = r.shift_origin
        self._record(first=True)

    def close(self) -> None:
        self.runner._shutdown()

    def _names(self) -> list[str]:
        return list(self.runner.axes) + [s.name for s in self.bench.spindles]

    def _on_cycle(self, runner: BenchRunner) -> None:
        self.panel(runner)
        self._record()
        for w in self.watchers:
            w(self)

    def _record(self, first: bool = False) -> None:
        r = self.runner
        n = len(r.axes)
        for i, name in enumerate(self._names()):
            rec, tx, sc = self.records[name], r.tx[i], r.scales[i]
            pos = sc.to_units(tx.position_actual)
            if first:
                rec.start = pos
            rec.end = pos
            rec.min, rec.max = min(rec.min, pos), max(rec.max, pos)
            rec.peak_velocity = max(rec.peak_velocity, abs(sc.drive_to_velocity(tx.velocity_actual)))
            if i >= n:
                rec.peak_rpm = max(rec.peak_rpm, abs(sc.drive_to_rpm(tx.velocity_actual)))
            mode = getattr(tx, "mode_display", 0)
            if not rec.modes or rec.modes[-1] != mode:
                rec.modes.append(mode)

    # ---- time ------------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.runner.time

    def cycle(self, n: int = 1) -> None:
        r = self.runner
        for _ in range(arg.whole("machine.cycle", "n", n, 0)):
            r._exchange()
            if r.stop_request is not None and not self._stopping:  # a signal (hil/stop_signals.py): the script
                raise SignalStop(r.stop_request)  # ends at this cycle; its command stops the machine (B96)

    def stop_under_control(self) -> None:
        """What the operator does when a script must end now (B96): every jog key let go, then RESET — the
        program and the manual motion stop jerk-limited, the spindle ramps down (NC5 §3.8). The shutdown
        (close) then waits for standstill and disables the drives."""
        self._stopping = True
        for i in range(len(self.runner.axes)):
            self.mlc.mem.set_bit(m2(self.x, 384 + i), False)
            self.mlc.mem.set_bit(m2(self.x, 400 + i), False)
        self.reset()

    def wait(self, s: float) -> None:
        self.cycle(max(1, int(round(arg.seconds(f"machine.wait({s!r})", s) / self.bench.cycle))))

    def wait_until(self, predicate: Callable[[], bool], timeout: float = 10.0, what: str = "condition") -> float:
        """Cycle until `predicate()` is true; returns the simulated time it took."""
        if not callable(predicate):
            raise ScriptError(f"machine.wait_until: {predicate!r} is not a function to call")
        t0 = self.time
        limit = int(round(arg.seconds(f"machine.wait_until(…, timeout={timeout!r})", timeout, positive=True) / self.bench.cycle))
        for _ in range(max(1, limit)):
            if predicate():
                return self.time - t0
            self.cycle()
        raise ScriptError(f"{what} not reached within {timeout:g} s simulated")

    # ---- devices ---------------------------------------------------------------------------------
    def get(self, address: str) -> int | float:
        """A device's value; an App. B register pair as its width says (f32: the float, u32: both words), decision
        B129."""
        from mlc.memory import DeviceError

        try:
            sig = self._pair(arg.text("machine.get", "address", address))
            if sig is not None:
                mem = self.mlc.mem
                return mem.f32(sig.number) if sig.width == "f32" else mem.u32(sig.number)
            return self.mlc.get(address)
        except DeviceError as exc:
            raise ScriptError(f"machine.get({address!r}): {exc}") from None

    def _pair(self, address: str):  # -> mlc.signals.Signal | None
        """The D device's signal where App. B makes it a two-word f32 or u32 (D2x256 MLC axis target, …), else None."""
        from mlc.signals import resolve

        if not address.strip().upper().startswith("D"):
            return None
        sig = resolve(address, self.x)
        return sig if sig.width in ("f32", "u32") else None

    def set(self, address: str, value: int | bool = True) -> None:
        from mlc.memory import DeviceError

        if not isinstance(value, bool):  # a relay's True/False, or a number for a D device
            value = arg.number(f"machine.set({address!r}, …)", "value", value)
        try:
            sig = self._pair(arg.text("machine.set", "address", address))
            if sig is not None and sig.width == "f32":  # as `hil run --at set`: the float, both words (B129)
                self.mlc.mem.set_f32(sig.number, float(value))
                return
            if value != int(value):  # int() dropped the fraction: D21256 = 30.5 became 30 in one word (B129)
                raise ScriptError(f"machine.set({address!r}, {value!r}): the device holds an integer "
                                  f"({sig.width if sig is not None else 'u16'})")
            if sig is not None:
                self.mlc.mem.set_u32(sig.number, int(value))
                return
            self.mlc.put(address, int(value))
        except DeviceError as exc:
            raise ScriptError(f"machine.set({address!r}, …): {exc}") from None

    def pulse(self, relay: int, cycles: int = 2) -> None:
        """Press a button relay for a few cycles (edge-triggered commands)."""
        from mlc.memory import M_SIZE

        arg.whole("machine.pulse", "relay", relay, 0, M_SIZE - 1)
        cycles = arg.whole("machine.pulse", "cycles", cycles, 1)
        self.mlc.mem.set_bit(relay, True)
        self.cycle(cycles)
        self.mlc.mem.set_bit(relay, False)
        self.cycle(1)

    # ---- remote I/O terminals of the simulated stations (bench [[io]], mlc/remote_io.py) ------------
    def _terminal(self, device: str, kind: str) -> tuple[Any, int]:
        """(simulated station, point) behind X<n> / Y<n>, by the bench's [[io]] mapping."""
        from mlc.memory import DeviceError, parse_address

        try:
            k, n = parse_address(device)
        except DeviceError as exc:
            raise ScriptError(str(exc)) from None
        if k != kind:
            raise ScriptError(f"{device}: expected an {'input X' if kind == 'X' else 'output Y'}<n>")
        try:
            hit = io_terminal(self.bench, self.link, kind, n)
        except IoNotSimulated as exc:
            raise ScriptError(str(exc)) from None
        if hit is None:
            raise ScriptError(f"{device} belongs to no [[io]] station of the bench")
        return hit

    def set_input(self, device: str, on: bool = True) -> None:
        """Switch the terminal behind remote input X<n> on its simulated station (seen from the next scan)."""
        station, point = self._terminal(device, "X")
        station.set_input(point, bool(on))

    def get_output(self, device: str) -> bool:
        """What the terminal behind remote output Y<n> drives on its simulated station now."""
        station, point = self._terminal(device, "Y")
        return bool(station.output(point))

    def axis_index(self, axis: str) -> int:
        try:
            return self.runner.axes.index(axis.upper())
        except ValueError:
            raise ScriptError(f"axis {axis!r} is not on the bench (axes: {', '.join(self.runner.axes)})") from None

    def position(self, axis: str) -> float:
        return float(self.runner.actual[self.axis_index(axis)])

    def command(self, axis: str) -> float:
        return float(self.runner._commands[self.axis_index(axis)])

    # ---- operator actions through the special relays -------------------------------------------------
    def mode(self, name: str) -> None:
        name = arg.text("machine.mode", "mode", name).upper()
        if name not in MODE_NAMES:
            raise ScriptError(f"unknown mode {name!r}; choose one of {', '.join(MODE_NAMES)}")
        k = MODE_NAMES.index(name)
        self.mlc.mem.set_u16(d2(self.x, 0), k)
        self.wait_until(lambda: self.mlc.mem.bit(m3(self.x, k)), 1.0, f"mode {name}")

    def mpg(self, axis: str, pulses: int, ratio: int = 1, rate: float = 100.0) -> None:
        """Turn the handwheel `pulses` detents (negative: backwards) at `rate` detents/s on `axis`."""
        i = self.axis_index(axis)
        # detents: a fraction would never be reached, the handwheel would turn on
        pulses = arg.whole("machine.mpg", "pulses", pulses, -(1 << 31), (1 << 31) - 1, "of detents (+ or -)")
        if not isinstance(ratio, Integral) or isinstance(ratio, bool) or not 0 <= ratio <= 0xFFFF:
            # D2x009 is a word: the manual's 1/10/100 are usual, not the limit
            raise ScriptError(f"MPG ratio {ratio!r}: D2x009 holds 0-65535 (usually 1, 10 or 100)")
        if not isinstance(rate, Real) or not 0.0 < rate < math.inf:  # no detents would ever come
            raise ScriptError(f"MPG rate {rate:g}: detents per second must be > 0")
        mem = self.mlc.mem
        mem.set_u16(d2(self.x, 8), i)
        mem.set_u16(d2(self.x, 9), ratio)
        if not mem.bit(m3(self.x, 3)):
            self.mode("MPG")
        per_cycle = rate * self.bench.cycle
        done, acc = 0, 0.0
        step = 1 if pulses >= 0 else -1
        while done != pulses:
            acc += per_cycle
            while acc >= 1.0 and done != pulses:
                acc -= 1.0
                done += step
                self._mpg_count = (self._mpg_count + step) & 0xFFFF
            mem.set_u16(d3(0, 4), self._mpg_count)
            self.cycle()
        self.settle(axis)

    def settle(self, axis: str | None = None, timeout: float = 10.0) -> None:
        mm = self.mlc.manual
        arg.seconds(f"machine.settle(timeout={timeout!r})", timeout, positive=True)
        self.wait_until(lambda: not mm.busy, timeout, "manual motion to finish")
        self.cycle(int(0.05 / self.bench.cycle))

    def jog(self, axis: str, direction: int, seconds: float, percent: int = 100) -> None:
        i = self.axis_index(axis)
        if direction not in (1, -1) or isinstance(direction, bool):
            raise ScriptError(f"machine.jog: direction {direction!r} must be 1 (+) or -1 (-)")
        arg.seconds(f"machine.jog({axis!r}, {direction}, {seconds!r})", seconds)
        percent = arg.whole("machine.jog", "percent", percent, 0, 100)  # D2x006 in percentage mode: 0-100 %
        if not self.mlc.mem.bit(m3(self.x, 4)):
            self.mode("JOG")
        self.mlc.mem.set_u16(d2(self.x, 6), percent)
        relay = m2(self.x, (384 if direction > 0 else 400) + i)
        self.mlc.mem.set_bit(relay, True)
        self.wait(seconds)
        self.mlc.mem.set_bit(relay, False)
        self.settle(axis)

    def inc(self, axis: str, steps: int, units: int = 1000) -> None:
        """`steps` presses of the INC key, each `units` × N9.013 (default 1000 × 0.001 = 1 mm)."""
        i = self.axis_index(axis)
        steps = arg.whole("machine.inc", "steps", steps, -(1 << 31), (1 << 31) - 1, "of presses (+ or -)")
        units = arg.whole("machine.inc", "units", units, 0, 0xFFFF_FFFF)  # D2x014 is a double word
        if not self.mlc.mem.bit(m3(self.x, 6)):
            self.mode("INC")
        self.mlc.mem.set_u32(d2(self.x, 14), units)
        relay = m2(self.x, (384 if steps > 0 else 400) + i)
        for _ in range(abs(steps)):
            self.pulse(relay)
            self.settle(axis)

    def home(self, axis: str, timeout: float = 60.0) -> float:
        i = self.axis_index(axis)
        arg.seconds(f"machine.home({axis!r}, timeout={timeout!r})", timeout, positive=True)
        if not self.mlc.mem.bit(m3(self.x, 7)):
            self.mode("HOME")
        self.pulse(m2(self.x, 320 + i))
        return self.wait_until(lambda: self.mlc.mem.bit(m3(self.x, 336 + i)), timeout, f"{axis} homing")

    def mdi(self, text: str, timeout: float = 60.0) -> float:
        """Run program text (MDI/AUTO) through cycle start and the M/S/T handshakes; returns its time."""
        return self.run_program(text, name="MDI", timeout=timeout)

    def start_program(self, text: str, name: str = "program") -> Channel:
        """Load program text in AUTO and press Cycle Start; returns at once (the channel runs on as the
        script cycles), so a script can feed-hold, reset or E-stop it mid-way."""
        r = self.runner
        text = arg.text("machine.start_program", "program text", text)
        self.mlc.mem.set_u16(d2(self.x, 0), 0)
        self.wait_until(lambda: self.mlc.link.mode == 0 and not self.mlc.manual.busy, 5.0, "AUTO mode")
        try:
            store = ProgramStore()  # O programs after the main one are its subprograms (M98, M96 P_)
            program = store.add_text(text, name)[0]
            program.store = store
        except NcAlarm as exc:
            raise ScriptError(str(exc.alarm)) from None
        here = dict(zip(r.axes, r.channel.planner.position.tolist()))
        interp = Interpreter(make_profile(self.bench.profile, r.axes, self.bench.params), here)
        self.mlc.attach_interpreter(interp)  # #25000–#25511 and the block skip switch M2x010
        ch = Channel(Planner(self.bench.motion_config(), here, spindle_rpm=lambda: self.mlc.spindle.rpm))
        if r.channel is not None:  # the tapping interrupt status outlives the program (N§3.13.2 note (6), M26-2)
            ch.tap = r.channel.tap
        ch.on_retracted = lambda pos: interp.position.update({a: v for a, v in pos.items() if a in interp.position})
        ch.param_groups = {**self.bench.motion_configs(), 0: ch.planner.cfg}  # G05 (decision language L25-1)
        r.channel = ch
        ch.soft_limits = SoftLimits.for_bench(self.bench, interp.profile)  # bench + this program's G10 L21
        ch.m96 = m96_link(interp)  # the MLC's M2x019 interrupts it (machine.interrupt())
        ch.load(interp.run(program))
        self.pulse(m2(self.x, OPERATOR_BUTTONS["cycle-start"]))
        return ch

    def run_program(self, text: str, name: str = "program", timeout: float = 600.0) -> float:
        """Run program text to its end through cycle start and the handshakes; returns its time."""
        arg.seconds(f"machine.run_program(…, timeout={timeout!r})", timeout, positive=True)
        prev_mode = self.mlc.link.mode
        t0 = self.time
        ch = self.start_program(text, name)
        limit = int(round(timeout / self.bench.cycle))
        for _ in range(limit):
            if not ch.busy:
                break
            self.cycle()
        else:
            raise ScriptError(f"{name} did not finish within {timeout:g} s simulated")
        self.alarms += [a for a in ch.alarms if a not in self.alarms]
        if prev_mode != 0:
            self.mlc.mem.set_u16(d2(self.x, 0), prev_mode)
            self.cycle(2)
        return self.time - t0

    def spindle(self, rpm: float, direction: int = 1, wait: bool = True) -> float:
        """Start (M03/M04 S…) or stop (rpm 0: M05) the spindle through MDI and the handshake."""
        arg.number("machine.spindle", "rpm", rpm)
        if rpm == 0 or direction == 0:
            return self.mdi("M05")
        return self.mdi(f"{'M03' if direction > 0 else 'M04'} S{abs(rpm):g}")

    def spindle_override(self, percent: int) -> None:
        """The operator's spindle override D2x026 (%): the NC applies it under G97 and G96 alike,
        within G50/G92 S and the spindle maximum, and holds 100 % during threads (motion decisions 32)."""
        percent = arg.whole("machine.spindle_override", "percent", percent, 0, 65535)  # D2x026's range
        self.mlc.mem.set_u16(d2(self.x, 26), percent)
        self.cycle()

    def get_rpm(self, spindle: int = 0) -> float:
        """Actual speed of a spindle drive (0x606C), rpm."""
        i = len(self.runner.axes) + spindle
        return self.runner.scales[i].drive_to_rpm(self.runner.tx[i].velocity_actual)

    def estop(self, on: bool = True) -> None:
        self.mlc.mem.set_bit(m2(self.x, ESTOP_RELAY), on)
        self.cycle()

    def interrupt(self) -> None:
        """Raise M2x019 (M96 program interruption) for a few cycles; M3x031 shows it running."""
        self.pulse(m2(self.x, OPERATOR_BUTTONS["interrupt"]))

    def feed_hold(self) -> None:
        self.pulse(m2(self.x, OPERATOR_BUTTONS["feed-hold"]))

    def cycle_start(self) -> None:
        self.pulse(m2(self.x, OPERATOR_BUTTONS["cycle-start"]))

    def reset(self) -> None:
        """The RESET button. The alarms standing before it are cleared when it takes (NC5: reset clears an alarm
        whose cause is gone): the channel is out of alarm and no E-stop is held (decision B59)."""
        ch = self.runner.channel
        before = self.active_alarms()
        self.pulse(m2(self.x, OPERATOR_BUTTONS["reset"]))
        if ch is not None and not ch.emergency and ch.state is not RunState.ALARM:
            for a in before:
                self.cleared.setdefault(id(a), self.time)

    def all_alarms(self) -> list[Alarm]:
        """Every alarm the script met, cleared ones included, in order."""
        ch = self.runner.channel
        return self.alarms + [a for a in (ch.alarms if ch is not None else []) if a not in self.alarms]

    def active_alarms(self) -> list[Alarm]:
        """The alarms no reset has cleared: what makes `hil script` exit 1."""
        return [a for a in self.all_alarms() if id(a) not in self.cleared]

    # ---- what the drives did -----------------------------------------------------------------------
    def summary(self) -> list[str]:
        lines = []
        n = len(self.runner.axes)
        for i, (name, rec) in enumerate(self.records.items()):
            if i < n:
                lines.append(f"{name:<4} {rec.start:10.4f} → {rec.end:10.4f}  (moved {rec.end - rec.start:+.4f}, "
                             f"range {rec.min:.4f}…{rec.max:.4f}, peak {rec.peak_velocity:.3f}/s)  "
                             f"modes {'/'.join(_mode_name(m) for m in rec.modes)}")
            else:
                lines.append(f"{name:<4} peak {rec.peak_rpm:8.1f} rpm, now "
                             f"{self.runner.scales[i].drive_to_rpm(self.runner.tx[i].velocity_actual):8.1f} rpm  "
                             f"modes {'/'.join(_mode_name(m) for m in rec.modes)}")
        alarms = [str(a) + (f" (cleared by reset at t={self.cleared[id(a)]:.3f} s)" if id(a) in self.cleared else "")
                  for a in self.all_alarms()]
        lines.append("alarms  " + ("; ".join(alarms) if alarms else "none"))
        return lines

    def report(self) -> None:
        for line in self.summary():
            print(line)


def _mode_name(mode: int) -> str:
    return {8: "CSP", 9: "CSV", 10: "CST", 6: "HM", 1: "PP", 3: "PV"}.get(mode, str(mode))


def run_script(path: str, machine: Machine, args: list[str] | None = None) -> Any:
    """Execute a script file against `machine`: its `main(machine, *args)` or its top-level code."""
    p = Path(path)
    if not p.is_file():
        raise ScriptError(f"script {path} does not exist")
    ns = runpy.run_path(str(p), init_globals={"machine": machine, "args": args or []}, run_name="__hil_script__")
    main = ns.get("main")
    if callable(main):
        return main(machine, *(args or [])) if args else main(machine)
    return None


__all__ = ["Machine", "OperatorPanel", "ScriptError", "run_script", "NcAlarm"]


# ---- `hil run --mlc MODULE --trace-signals LIST --m00-resume S` --------------------------------------
def build_mlc(bench: Bench, spec: str | None) -> Any:
    """The bench's MLC: "basic" → the foundation's BasicMlc; "lathe" / "default" → the Delta MLC with the
    default lathe program (mlc.lathe); anything else → the Delta MLC running that user module."""
    from mlc.basic import BasicMlc

    spec = spec or bench.mlc_program
    max_rpm = min((s.max_rpm for s in bench.spindles), default=6000.0)
    if spec == "basic":
        return BasicMlc(max_rpm=max_rpm, cycle_time=bench.cycle)
    program = None if spec in ("lathe", "default") else load_mlc_program(spec)
    mlc = Mlc(program, axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config(), max_rpm=max_rpm)
    if "N0.1025" in bench.params:  # 1st spindle positioning check time, ms (App. A 0x0C01)
        mlc.caxis.check_time = bench.params["N0.1025"] / 1000.0
    return mlc


def load_mlc_program(spec: str) -> Any:
    from mlc.machine import load_program

    module_spec = spec.split(":")[0] if not spec.endswith(".py") else spec
    return load_program(module_spec)


def mlc_setup(bench: Bench, mlc_spec: str | None, signals: str | None, m00_resume: float | None,
              devices: bool = False):
    """(mlc, on_cycle, trace sources) for `hil run`; raises InputError naming a bad module or device.
    `devices`: the run writes M/D devices (`--at`), so it needs the Delta MLC like `signals` does."""
    from hil.session import InputError
    from mlc.machine import MlcLoadError
    from mlc.memory import DeviceError
    from mlc.tracing import SignalSource, parse_signal_list

    if (signals or devices or getattr(bench, "io", None)) and not mlc_spec and bench.mlc_program == "basic":
        mlc_spec = "lathe"  # device columns and remote I/O (X/Y) need the Delta MLC
    try:
        mlc = build_mlc(bench, mlc_spec)
    except MlcLoadError as exc:
        raise InputError(str(exc)) from None
    if not isinstance(mlc, Mlc):
        mlc.m00_resume = m00_resume  # the basic MLC's M00 hold: its operator is built in (decision B78)
        return mlc, None, []
    sources = []
    if signals:
        try:
            sources.append(SignalSource(mlc.mem, parse_signal_list(signals, mlc.link.x)))
        except DeviceError as exc:
            raise InputError(f"--trace-signals: {exc}") from None
    return mlc, OperatorPanel(mlc, m00_resume), sources
