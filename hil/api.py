"""deltahil as a library: `hil.run`, `hil.path`, `hil.load_trace`.

The `hil run` command is a thin printer over `run`, so a user's script, the pytest plugin and
a campaign worker wire a bench exactly as the command line does (the same MLC, remote I/O,
events, trace and checks):

    import hil
    r = hil.run("examples/lathe_demo.nc", bench="benches/lathe-2axis.toml", trace="out/demo.parquet")
    assert r.ok, r.alarms
    print(r.program_time, r.max_following_error, r.final_position)
    table = r.trace.load()          # a pyarrow Table; .to_pandas() is one call away

Bad input (a bench file, an option, an event) raises `hil.session.InputError` naming what is
wrong; a program that cannot be read or parsed is a result with its Delta alarm, as on the NC.
"""

from __future__ import annotations

import functools
import gc
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hil.bench import Bench


@dataclass
class TraceRef:
    path: Path

    def load(self, columns: Sequence[str] | None = None):
        """The trace as a pyarrow Table (Parquet or CSV alike)."""
        from hil.trace_read import TraceFile

        return TraceFile(self.path).table(columns)


@dataclass
class Result:
    """What one run did. `ok`: it completed, raised no alarm and passed every check it ran."""

    program: str
    bench: Bench
    run: Any  # hil.runner.RunResult
    checks: list[Any] = field(default_factory=list)  # hil.checks.CheckResult, empty when none ran
    events: list[Any] = field(default_factory=list)  # hil.run_events.RunEvent, with fired_* filled in
    trace: TraceRef | None = None
    runner: Any = None  # the BenchRunner, for a caller that wants more than the summary

    @property
    def alarms(self) -> list[Any]:
        return list(self.run.alarms)

    @property
    def warnings(self) -> list[Any]:
        """hil.aux_watch.AuxWarning: M/S/T codes the MLC did not answer in time."""
        return list(getattr(self.runner, "warnings", ()))

    @property
    def completed(self) -> bool:
        return bool(self.run.ok)

    @property
    def checks_ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def ok(self) -> bool:
        return self.completed and self.checks_ok

    @property
    def program_time(self) -> float:
        return self.run.program_time

    @property
    def sim_time(self) -> float:
        return self.run.sim_time

    @property
    def cycles(self) -> int:
        return self.run.cycles

    @property
    def max_following_error(self) -> dict[str, float]:
        return dict(self.run.max_ferr)

    @property
    def final_position(self) -> dict[str, float]:
        return dict(self.run.final)

    def figures(self) -> dict[str, Any]:
        """The report's plots of this run's trace as matplotlib Figures, by name ("path",
        "following_error", "velocity_torque", "jitter", "signals"): a notebook shows them inline."""
        if self.trace is None:
            raise ValueError("this run kept no trace: give trace=… to hil.run")
        from hil.report import trace_figures

        moves = None
        if self.runner is not None:
            from hil.checks import offline_moves, program_start
            from hil.session import load_program
            from hil.trace_read import TraceFile

            start = program_start(TraceFile(str(self.trace.path)), self.bench.axis_names)
            moves, _ = offline_moves(load_program(self.program), self.bench, start)
        return {name.removesuffix(".png"): fig for name, _, fig in trace_figures(self.trace.path, self.bench, moves)}

    @property
    def unfired(self) -> list[Any]:
        return [e for e in self.events if e.fired_cycle is None]


def _bench(bench: str | Path | Bench | None, profile: str | None, bus: str | None) -> Bench:
    from hil.session import load_bench, override_bench

    if isinstance(bench, Bench):
        return override_bench(bench, profile, bus)
    return load_bench(str(bench) if bench is not None else None, profile, bus)


def _percent(name: str, value: float, high: float) -> float:
    from hil.session import InputError

    if not (isinstance(value, (int, float)) and 0 <= value <= high):
        raise InputError(f"{name} {value!r}: a percentage from 0 to {high:g}")
    return float(value)


_PAUSED: ContextVar[list[bool] | None] = ContextVar("hil_api_gc_paused", default=None)  # [frozen] while paused


def _collector_paused(fn: Callable[..., Result]) -> Callable[..., Result]:
    """The cyclic garbage collector off from the call to the run's cycles (bench decision B47): the ≈ 450 modules a
    first run imports and what it builds set off ≈ 90 collections, ≈ 20 ms of a `hil run`. `_resume_collector`
    freezes what was built (as B42 does after the planner: a first collection of all of it would cost what the 90
    did) and turns the collector back on just before `BenchRunner.run_program`, whose end unfreezes it (B42); on every
    way out the collector is as the caller had it, nothing left frozen by the run."""

    @functools.wraps(fn)
    def paused(*args: Any, **kwargs: Any) -> Result:
        if not gc.isenabled():  # the caller turned it off: left to the caller
            return fn(*args, **kwargs)
        gc.disable()
        state: list[bool] = [False]
        token = _PAUSED.set(state)
        try:
            return fn(*args, **kwargs)
        finally:
            _PAUSED.reset(token)
            if state[0]:
                gc.unfreeze()  # (run_program's own end has done it already, unless it failed before its try)
            gc.enable()

    return paused


def _resume_collector() -> None:
    state = _PAUSED.get()
    if state is not None and not state[0]:
        state[0] = True
        gc.freeze()
        gc.enable()


@_collector_paused
def run(program: str | Path, bench: str | Path | Bench | None = None, *, bus: str | None = None,
        profile: str | None = None, libs: Sequence[str] = (), trace: str | Path | None = None,
        mlc: str | None = None, events: Sequence[str] = (), event_files: Sequence[str] = (),
        feed_override: float = 100.0, rapid_override: float = 100.0, spindle_override: float = 100.0,
        check: bool | None = None, trace_signals: str | None = None, m00_resume: float = 0.5,
        realtime: bool = False, overrun: str | None = None, progress: Any = None,
        servo_modbus: str | None = None, servo_baud: int = 38400, capture: str | Path | None = None,
        scope: Any = None, aux_timeout: float = 5.0, home: bool = True, retain: str | Path | None = None,
        max_time: float | None = None) -> Result:
    """Run `program` on a bench in lock-step virtual time (or `realtime`); see the module doc.

    `bench`: a bench file, a `Bench`, or None for the built-in 2-axis lathe. `events`: `--at`
    strings; `event_files`: `--events` files. Overrides are the panel's switch positions at power-on
    (D2x002 feed 0–150 %, D2x004 rapid 0–100 %, D2x026 spindle 50–120 %); the MLC may change them.
    `check`: judge the run by the bench's [checks] (default: when it has any). `capture`: record the
    bus's frames (EtherCAT .pcapng, CAN .asc/.blf/.log; fieldbus/capture.py). `scope`: a started
    `hil.scope.Scope` that streams this run's rows to its page. `aux_timeout`: simulated seconds an
    M/S/T code may wait for the MLC's finish before a warning (0: never). `home`: False skips the drive
    homing of axes with a bench `homing` table (hil/drive_homing.py; the drives keep their last origin). `retain`: a
    JSON file holding the retentive # variables from run to run (hil/retentive.py). `max_time`: simulated seconds
    after which the run stops under control with alarm 0xDE03, in place of the bench's max_time (decision B57)."""
    from hil.clock import make_clock
    from hil.placement import lockstep_clock
    from hil.progress import Progress
    from hil.remote_io import attach_remote_io
    from hil.runner import BenchRunner, RunResult
    from hil.scripting import mlc_setup
    from hil.session import InputError, load_program, make_link
    from hil.trace import open_trace
    from nc.alarms import NcAlarm

    if not 0.0 <= m00_resume < float("inf"):
        raise InputError(f"--m00-resume {m00_resume:g}: seconds must be >= 0")
    if not 0.0 <= aux_timeout < float("inf"):
        raise InputError(f"--aux-timeout {aux_timeout:g}: seconds must be >= 0 (0: no warning)")
    if max_time is not None and not 0.0 < max_time < float("inf"):
        raise InputError(f"--max-time {max_time:g}: simulated seconds must be > 0")
    if retain:  # a store the run could not write back: refused before anything moves (hil/retentive.py)
        from hil.retentive import unusable

        why = unusable(retain)
        if why is not None:
            raise InputError(f"--retain {retain}: {why}")
    feed = _percent("feed override", feed_override, 150.0)
    rapid = _percent("rapid override", rapid_override, 100.0)
    spindle = _percent("spindle override", spindle_override, 120.0)
    if spindle < 50.0:
        raise InputError(f"spindle override {spindle_override!r}: a percentage from 50 to 120")
    b = _bench(bench, profile, bus)
    # axes that need homing but were not homed have no origin: G28/G30/G53 on them raise 0x0A08 (A42)
    unreferenced = frozenset(a.name for a in b.axes if a.homing) if not home else frozenset()
    if unreferenced:
        from dataclasses import replace

        b = replace(b, axes=[replace(a, homing=None) for a in b.axes])
    try:
        prog = load_program(str(program), list(libs))
    except NcAlarm as exc:
        return Result(str(program), b, RunResult(alarms=[exc.alarm]))
    if overrun:
        b.realtime.overrun = overrun
    if max_time is not None:  # the bench's own guard, given for this run (0xDE03; decision B57)
        from dataclasses import replace as _with

        b = _with(b, max_time=max_time)  # (a copy: a caller's Bench keeps its own)
    if capture:  # refuse a sim bus or a wrong suffix before anything starts
        _capture_suffix(str(capture), b)
    link = make_link(b)
    # lock-step: placed on one CPU under SCHED_FIFO when the bench's [realtime] lockstep says so (decisions E21)
    clock = make_clock(b.cycle, realtime, b.realtime) if realtime else lockstep_clock(b.cycle, b.realtime)
    if progress is True:
        progress = Progress(max((blk.line for blk in prog.blocks), default=1))
    if aux_timeout:  # warn when an M/S/T code waits longer for the MLC's finish (decision T7)
        from hil.aux_watch import AuxWatch

        progress = AuxWatch(aux_timeout, progress)
    wants_events = bool(events or event_files)
    overridden = (feed, rapid, spindle) != (100.0, 100.0, 100.0)
    m, panel, signal_sources = mlc_setup(b, mlc, trace_signals, m00_resume, wants_events)
    _set_overrides(m, feed, rapid, spindle)
    attach_remote_io(b, m, link)
    player = None
    if wants_events:
        from hil.run_events import EventPlayer, EventSpecError, parse_events  # here: a run without events needs none

        if not hasattr(m, "mem"):
            raise InputError("--at/--events write MLC devices: they need a Delta MLC, not --mlc basic")
        try:
            parsed = parse_events(list(events), list(event_files), b.axis_names, m.link.x, b.cycle)
        except EventSpecError as exc:
            raise InputError(str(exc)) from None
        traced = [c for src in signal_sources for c in src.columns]
        player = EventPlayer(parsed, m, b, link, panel, traced)
    runner = BenchRunner(b, link, None, m, player or panel, clock=clock, progress=progress)
    runner.unreferenced = unreferenced
    runner.retain = str(retain) if retain else None
    if max_time is not None:
        runner.max_time_name = "--max-time"
    runner.trace_sources += signal_sources
    if player is not None:
        runner.trace_sources.append(player)
    del overridden
    trace_path = str(trace) if trace else None
    want_checks = b.checks.any and check is not False
    temporary = want_checks and not trace_path
    if temporary:  # checks read a trace; keep it only if asked for
        fd, trace_path = tempfile.mkstemp(prefix="hil-run-", suffix=".parquet")
        os.close(fd)
    cap = None
    from hil.stop_signals import stop_on_signals

    try:
        # Signals are taken from before the trace is opened: opening it warms pyarrow up (≈ 0.5 s,
        # longer on a loaded machine), and a Ctrl-C then must still end through the stop path.
        with stop_on_signals(runner):
            if capture:
                cap = _open_capture(str(capture), link, b)
            if trace_path:
                from hil.trace_meta import column_units, run_meta

                columns = runner.trace_columns()
                try:
                    runner.trace = open_trace(trace_path, columns, run_meta(b, str(program), libs), column_units(columns, b))
                except OSError as exc:
                    raise InputError(f"cannot write trace {trace_path}: {exc.strerror}") from None
            if scope is not None:  # the live scope reads the rows the trace is written from
                try:
                    runner.trace = scope.attach(runner.trace, runner.trace_columns())
                except ValueError as exc:
                    if runner.trace is not None:
                        runner.trace.discard()
                    raise InputError(str(exc)) from None
                if getattr(scope, "wait", False):  # --scope-wait: every input is checked by now, nothing moved yet
                    try:
                        scope.wait_for_browser(sys.stderr, lambda: runner.stop_request)
                    except BaseException:  # Ctrl-C while waiting: no trace left behind
                        runner.trace.discard()
                        raise
            if servo_modbus:  # G10 L40/L41 over the drives' RS-485 port (issue 8)
                import serial

                from fieldbus.modbus import ModbusRtuMaster

                try:
                    runner.servo_modbus = ModbusRtuMaster.open(servo_modbus, baudrate=servo_baud)
                except (serial.SerialException, OSError) as exc:
                    if runner.trace is not None:
                        runner.trace.discard()
                    raise InputError(f"cannot open {servo_modbus}: {exc}") from None
            _resume_collector()
            try:
                result = runner.run_program(prog)
            finally:
                if servo_modbus:
                    runner.servo_modbus.close()
        from nc.alarm_table import TRACE_WRITE

        lost = any(a.code == TRACE_WRITE for a in result.alarms)  # the trace was removed: nothing to judge (B97)
        checks = _checks(trace_path, b, prog) if trace_path and want_checks and not lost else []
    finally:
        if temporary and trace_path:
            Path(trace_path).unlink(missing_ok=True)
        if cap is not None:
            cap.close()
    return Result(str(program), b, result, checks, list(player.events) if player is not None else [],
                  TraceRef(Path(trace_path)) if trace_path and not temporary and not lost else None, runner)


def _capture_suffix(path: str, b: Bench) -> None:
    from fieldbus.capture import check_suffix
    from fieldbus.factory import parse_bus
    from hil.session import InputError

    try:
        check_suffix(path, parse_bus(b.bus).kind)
    except ValueError as exc:
        raise InputError(str(exc)) from None


def _open_capture(path: str, link: Any, b: Bench) -> Any:
    from fieldbus.capture import open_capture
    from fieldbus.factory import parse_bus
    from hil.session import InputError

    spec = parse_bus(b.bus)
    try:
        return open_capture(path, link, spec.kind, spec.interface)
    except (ValueError, OSError) as exc:
        raise InputError(f"cannot capture to {path}: {exc}") from None


def _set_overrides(mlc: Any, feed: float, rapid: float, spindle: float) -> None:
    """The panel's override switches at power-on: the Delta MLC's D2x002/D2x004/D2x026, or the
    basic MLC's fixed values (it has no panel)."""
    if hasattr(mlc, "mem"):
        from mlc.signals import d2

        x = mlc.link.x
        for reg, value in ((2, feed), (4, rapid), (26, spindle)):
            mlc.mem.set_u16(d2(x, reg), int(round(value)))
    else:
        mlc.overrides = (feed / 100.0, rapid / 100.0, spindle / 100.0)


def _checks(trace_path: str, bench: Bench, program: Any) -> list[Any]:
    from hil.checks import offline_moves, program_start, run_checks
    from hil.trace_read import TraceFile

    tf = TraceFile(trace_path)
    if (tf.num_rows if tf.num_rows >= 0 else tf.table(["t"]).num_rows) == 0:
        return []  # no cycle ran (a bus that never opened): the run's alarm is the result; nothing to judge
    moves, why = offline_moves(program, bench, program_start(tf, bench.axis_names))
    return run_checks(tf, bench.checks, bench, moves, why)


def path(program: str | Path, bench: str | Path | Bench | None = None, *, profile: str | None = None,
         libs: Sequence[str] = (), params: dict[str, float] | None = None) -> list[Any]:
    """The canonical moves and aux events of a program in machine coordinates, without motion —
    what `hil path --json` prints; with a bench, from its axes' power-on positions. Raises nc.alarms.NcAlarm where the NC would alarm, InputError for
    a bad bench or library."""
    from hil.session import InputError
    from nc.interp import Interpreter
    from nc.profiles import make_profile
    from nc.store import ProgramStore

    b = _bench(bench, profile, None)
    rotary = tuple(a.name for a in b.axes if a.units == "deg") if bench is not None else ()
    prof = make_profile(b.profile, b.axis_names if bench is not None else None, {**b.params, **(params or {})},
                        rotary)
    store = ProgramStore(usb_first=bool(prof.param("N8.22 Bit5")))
    try:
        store.add_libs(list(libs))
    except ValueError as exc:
        raise InputError(str(exc)) from None
    start = {a.name: a.start for a in b.axes} if bench is not None else None  # the bench's power-on position
    return list(Interpreter(prof, start, store=store).run(store.load_main(str(program))))


def load_trace(path_: str | Path):
    """A trace file (Parquet or CSV) as a pyarrow Table."""
    return TraceRef(Path(path_)).load()
