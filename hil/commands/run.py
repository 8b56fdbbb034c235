"""`hil run PROGRAM`: execute a program on the bench (virtual bus by default) and summarise."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from hil.bench import Bench
from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from hil.clock import make_clock
from hil.progress import Progress, wants_progress
from hil.remote_io import attach_remote_io
from hil.run_events import EventPlayer, EventSpecError, parse_events
from hil.runner import BenchRunner, RunResult
from hil.scripting import mlc_setup
from hil.session import InputError, load_bench, load_program, make_link, print_alarm
from hil.trace import open_trace
from nc.alarms import NcAlarm


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a G-code program on the bench and print a summary")
    p.add_argument("program", help="G-code program file")
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--bus", help="sim | ethercat:IFACE | canopen:INTERFACE[:CHANNEL] (overrides the bench)")
    p.add_argument("--profile", help="controller profile (overrides the bench)")
    p.add_argument("--lib", action="append", default=[], metavar="DIR|FILE",
                   help="where subprograms and macros (O numbers) are found, as for `hil path --lib`")
    p.add_argument("--trace", metavar="FILE", help="write every cycle to this file: .parquet/.pq → Parquet, else CSV")
    p.add_argument("--realtime", action="store_true",
                   help="pace cycles in real time (SCHED_FIFO, CPU pinning, DC alignment where allowed)")
    p.add_argument("--overrun", choices=("warn", "alarm"), help="what a cycle overrun does (overrides the bench)")
    p.add_argument("--check", action=argparse.BooleanOptionalAction, default=None,
                   help="judge the run by the bench's [checks] (default: on when the bench has checks)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr (default: only when stderr is a terminal)")
    p.add_argument("--mlc", metavar="MODULE",
                   help="MLC program: lathe (Delta's lathe MLC, the default on a lathe) | basic (the default on a "
                        "mill) | module name | path.py (overrides the bench's mlc)")
    p.add_argument("--trace-signals", metavar="DEVICES",
                   help="extra trace columns, one per MLC device: M31064,M21016,D31048 or App. B names")
    p.add_argument("--at", action="append", default=[], metavar="TRIGGER:ACTION",
                   help="poke an MLC device during the run, e.g. \"t=1.1:pulse M21019\", \"line=12:set D21002=50\", "
                        "\"Z<-10:set X5=1\", \"t=3:feed-hold\" (repeatable; grammar in docs/guide/mlc.md)")
    p.add_argument("--events", action="append", default=[], metavar="FILE",
                   help="events file: one TRIGGER:ACTION per line, # comments (after any --at)")
    p.add_argument("--m00-resume", metavar="SECONDS", type=float, default=0.5,
                   help="the simulated operator presses Cycle Start this long after an M00/M01 hold (default 0.5)")
    p.add_argument("--servo-modbus", metavar="DEVICE",
                   help="G10 L40/L41 servo parameters go over this RS-485 port (Modbus RTU, station = I) "
                        "instead of SDO on the bench's bus")
    p.add_argument("--servo-baud", type=int, default=38400, help="baud rate of --servo-modbus (default 38400)")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    if not 0.0 <= args.m00_resume < float("inf"):
        print(f"hil run: --m00-resume {args.m00_resume:g}: seconds must be >= 0", file=sys.stderr)
        return EXIT_USAGE
    try:
        bench = load_bench(args.bench, args.profile, args.bus)
    except InputError as exc:
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        program = load_program(args.program, args.lib)
    except NcAlarm as exc:
        print_alarm(exc.alarm)
        return EXIT_ALARM
    except InputError as exc:  # a --lib that is neither file nor folder
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        link = make_link(bench)
    except InputError as exc:
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if args.overrun:
        bench.realtime.overrun = args.overrun
    clock = make_clock(bench.cycle, args.realtime, bench.realtime)
    progress = None
    if wants_progress(args.progress):
        progress = Progress(max((b.line for b in program.blocks), default=1))
    wants_events = bool(args.at or args.events)
    try:  # the MLC, its operator panel and --trace-signals columns (issue 8)
        mlc, panel, signal_sources = mlc_setup(bench, args.mlc, args.trace_signals, args.m00_resume, wants_events)
    except InputError as exc:
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    attach_remote_io(bench, mlc, link)  # [[io]] stations → X/Y devices (issue 8)
    player = None
    if wants_events:  # --at / --events: timed pokes at MLC devices (hil/run_events.py)
        try:
            player = make_player(args, bench, mlc, link, panel, signal_sources)
        except EventSpecError as exc:
            print(f"hil run: {exc}", file=sys.stderr)
            return EXIT_USAGE
    runner = BenchRunner(bench, link, None, mlc, player or panel, clock=clock, progress=progress)
    runner.trace_sources += signal_sources
    if player is not None:
        runner.trace_sources.append(player)
    # Extra trace columns (e.g. the MLC's --trace-signals) are TraceSources appended here,
    # before the trace is opened with the runner's columns.
    trace_path = args.trace
    want_checks = bench.checks.any and args.check is not False
    if want_checks and not trace_path:
        trace_path = _temp_trace()  # checks read a trace; keep it only if asked for
    if trace_path:
        try:
            runner.trace = open_trace(trace_path, runner.trace_columns())
        except OSError as exc:
            print(f"hil run: cannot write trace {trace_path}: {exc.strerror}", file=sys.stderr)
            return EXIT_USAGE
    if args.servo_modbus:  # G10 L40/L41 over the drives' RS-485 port (issue 8)
        import serial

        from fieldbus.modbus import ModbusRtuMaster
        try:
            runner.servo_modbus = ModbusRtuMaster.open(args.servo_modbus, baudrate=args.servo_baud)
        except (serial.SerialException, OSError) as exc:
            print(f"hil run: cannot open {args.servo_modbus}: {exc}", file=sys.stderr)
            return EXIT_USAGE
    try:
        result = runner.run_program(program)
    finally:
        if args.servo_modbus:
            runner.servo_modbus.close()
    print_summary(args.program, bench, result)
    waits = [(ln, w) for ln, w in runner.channel.planner.thread_waits if w] if runner.channel is not None else []
    if waits:  # threads armed only once the spindle settled at its command (motion decisions 33)
        print("spindle settle " + "  ".join(f"line {ln} {w * bench.cycle * 1000:g} ms" for ln, w in waits)
              + " before the thread", file=sys.stdout)
    if player is not None:
        print("\n".join(player.summary()), file=sys.stdout)
    print_timing(result)
    code = EXIT_OK if result.ok else EXIT_ALARM
    if trace_path and want_checks:
        checks_ok = run_bench_checks(trace_path, bench, program)
        if not checks_ok:
            code = EXIT_ALARM
    if trace_path and trace_path != args.trace:
        Path(trace_path).unlink(missing_ok=True)
    return code


def make_player(args: argparse.Namespace, bench: Bench, mlc, link, panel, signal_sources) -> EventPlayer:
    """The --at / --events player, wrapping the operator panel; EventSpecError for a bad event."""
    if not hasattr(mlc, "mem"):
        raise EventSpecError("--at/--events write MLC devices: they need a Delta MLC, not --mlc basic")
    events = parse_events(args.at, args.events, bench.axis_names, mlc.link.x)
    traced = [c for src in signal_sources for c in src.columns]
    return EventPlayer(events, mlc, bench, link, panel, traced)


def _temp_trace() -> str:
    fd, name = tempfile.mkstemp(prefix="hil-run-", suffix=".parquet")
    os.close(fd)
    return name


def run_bench_checks(trace_path: str, bench: Bench, program) -> bool:
    """Judge the run's trace by the bench's [checks]; print one line per check."""
    from hil.checks import program_moves, run_checks
    from hil.trace_read import TraceFile

    try:
        moves = program_moves(program, bench)
    except NcAlarm:
        moves = None
    results = run_checks(TraceFile(trace_path), bench.checks, bench, moves)
    print("checks", file=sys.stdout)
    for r in results:
        print(f"  {r}", file=sys.stdout)
    return all(r.ok for r in results)


def print_timing(r: RunResult) -> None:
    out = sys.stdout
    if r.realtime:
        j = r.timing.get("jitter", {})
        print(f"real time      {r.granted}", file=out)
        print("cycle jitter   " + "  ".join(f"{k} {j.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")),
              file=out)
        lat = r.timing.get("latency", {})
        if lat:
            print("wake latency   " + "  ".join(f"{k} {lat.get(k, 0.0) * 1e6:.1f} µs"
                                            for k in ("p50", "p99", "p99.9", "max")), file=out)
    e = r.timing.get("exec", {})
    if e:
        print("cycle work     " + "  ".join(f"{k} {e.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "max"))
              + ("  (wall clock, lock-step)" if not r.realtime else ""), file=out)
    if r.overruns:
        print(f"overruns       {r.overruns} cycles ran past their deadline", file=sys.stderr if not r.alarms else out)


def print_summary(program: str, bench: Bench, r: RunResult) -> None:
    out = sys.stdout
    print(f"program        {program}  (profile {bench.profile}, bench {bench.name}, bus {bench.bus})", file=out)
    print(f"cycles         {r.cycles}  ({bench.cycle * 1000:g} ms cycle, {r.sim_time:.3f} s simulated)", file=out)
    print(f"drives enabled after {r.enable_cycles} cycles", file=out)
    print(f"program time   {r.program_time:.3f} s simulated", file=out)
    units = {a.name: "deg" if a.units == "deg" else "mm" for a in bench.axes}
    ferr = "  ".join(f"{a} {v:.4f} {units.get(a, 'mm')}" for a, v in r.max_ferr.items())
    print(f"max following error  {ferr}", file=out)
    final = "  ".join(f"{a} {v:.4f}" for a, v in r.final.items())
    print(f"final machine position  {final}", file=out)
    if r.alarms:
        print(f"alarms         {len(r.alarms)}", file=out)
        for a in r.alarms:
            print(f"  {a}", file=out)
    else:
        print("alarms         none", file=out)
    print(f"result         {'completed' if r.ok else 'STOPPED'}", file=out)
