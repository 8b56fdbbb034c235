"""`hil run PROGRAM`: execute a program on the bench (virtual bus by default) and summarise."""

from __future__ import annotations

import argparse
import sys

from typing import TYPE_CHECKING

from hil.cli import EXIT_ALARM, EXIT_USAGE

if TYPE_CHECKING:  # the runner and the bench load when a run starts, not at `hil` start-up
    from hil.bench import Bench
    from hil.runner import RunResult


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
    p.add_argument("--feed-override", type=float, default=100.0, metavar="PERCENT",
                   help="feed override switch at power-on, 0–150 %% (D2x002; default 100)")
    p.add_argument("--rapid-override", type=float, default=100.0, metavar="PERCENT",
                   help="rapid override switch at power-on, 0–100 %% (D2x004; default 100)")
    p.add_argument("--spindle-override", type=float, default=100.0, metavar="PERCENT",
                   help="spindle override switch at power-on, 50–120 %% (D2x026; default 100)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (result, alarms, checks, events, times, errors, trace) on stdout; "
                        "the text summary goes to stderr")
    p.add_argument("--junit", metavar="FILE", help="write JUnit XML: a test case for the run and one per check")
    p.add_argument("--capture", metavar="FILE",
                   help="record the bus's frames: EtherCAT as .pcapng (Wireshark/tshark), CAN as .asc/.blf/.log")
    p.add_argument("--aux-timeout", metavar="SECONDS", type=float, default=5.0,
                   help="warn when an M/S/T code waits longer than this (simulated) for the MLC's finish "
                        "M2x016; the run keeps waiting as the NC does (default 5, 0: never)")
    p.add_argument("--scope", action="store_true",
                   help="live scope: serve a page on 127.0.0.1 (free port, printed) that streams trace columns "
                        "while the run goes")
    p.add_argument("--scope-columns", metavar="COLS",
                   help="columns for --scope, e.g. X_cmd,X_act,Z_ferr,S1_rpm_act "
                        "(default: every axis's cmd/act/ferr and every spindle's rpm_cmd/rpm_act)")
    p.add_argument("--scope-linger", metavar="SECONDS", type=float, default=30.0,
                   help="after the run, keep the scope page up this long unless the browser already "
                        "has the last rows (default 30)")
    p.add_argument("--scope-wait", action="store_true",
                   help="hold the run until a browser has the scope page open")
    p.add_argument("--scope-port", metavar="PORT", type=int, default=0, help=argparse.SUPPRESS)
    p.add_argument("--retain", metavar="FILE",
                   help="keep the retentive # variables (#2000-#11999; lathe-2018 #1601-#1800, #10001-#10450) in this "
                        "JSON file from run to run: read before the program, written when the run ends")
    p.add_argument("--home", action=argparse.BooleanOptionalAction, default=True,
                   help="home the axes whose bench entry has a `homing` table by their drives before the program "
                        "(default); --no-home: the drives keep the origin of their last homing")
    p.add_argument("--max-time", metavar="SECONDS", type=float,
                   help="stop the run after this much simulated time (from power-up) as the bench's max_time does: "
                        "axes stopped along the path, drives disabled at standstill, alarm 0xDE03, exit 1 "
                        "(default: the bench's max_time, 3600 s)")
    p.add_argument("--allow-unfired", action="store_true",
                   help="an --at/--events event that never fired does not fail the run")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    """`hil run` prints what `hil.run` returns; the run itself is the library's (hil/api.py)."""
    if (args.scope_columns or args.scope_wait) and not args.scope:
        print("hil run: --scope-columns and --scope-wait need --scope", file=sys.stderr)
        return EXIT_USAGE
    try:
        scope = _start_scope(args)
    except OSError as exc:
        print(f"hil run: --scope cannot listen on 127.0.0.1:{args.scope_port}: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return _run_and_print(args, scope)
    finally:
        if scope is not None:
            scope.close()


def _start_scope(args: argparse.Namespace):
    if not args.scope:
        return None
    from hil.scope import Scope

    scope = Scope(args.scope_columns, linger_s=max(0.0, args.scope_linger), port=args.scope_port)
    print(f"scope: {scope.start()} (127.0.0.1 only)", file=sys.stderr, flush=True)
    scope.wait = args.scope_wait  # hil.run waits once the inputs are checked, before the drives are enabled
    return scope


def _run_and_print(args: argparse.Namespace, scope) -> int:
    from hil.api import run
    from hil.progress import wants_progress
    from hil.session import InputError, print_alarm

    try:
        r = run(args.program, args.bench, bus=args.bus, profile=args.profile, libs=args.lib, trace=args.trace,
                mlc=args.mlc, events=args.at, event_files=args.events, feed_override=args.feed_override,
                rapid_override=args.rapid_override, spindle_override=args.spindle_override, check=args.check,
                trace_signals=args.trace_signals, m00_resume=args.m00_resume, realtime=args.realtime,
                overrun=args.overrun, progress=True if wants_progress(args.progress) else None,
                servo_modbus=args.servo_modbus, servo_baud=args.servo_baud,
                capture=args.capture, scope=scope, aux_timeout=args.aux_timeout, home=args.home,
                retain=args.retain, max_time=args.max_time)
    except InputError as exc:
        if exc.alarm is not None:
            print_alarm(exc.alarm)
            return EXIT_ALARM
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    from hil.run_output import junit_xml, to_json, verdict, write_atomic

    text = sys.stderr if args.json else sys.stdout
    if r.runner is None:  # the program could not be read or parsed: its alarm, no run
        print_alarm(r.alarms[0])
    else:
        print_run(args.program, r, text)
    _, code = verdict(r, args.allow_unfired)
    if r.unfired and not args.allow_unfired:
        player = r.runner.on_cycle if r.runner is not None else None
        why = player.why_unfired() if hasattr(player, "why_unfired") else ""  # an E-stop ended the run (B58)
        print(f"hil run: {len(r.unfired)} event(s) never fired (--allow-unfired to accept): "
              + "; ".join(e.spec for e in r.unfired) + why, file=sys.stderr)
    if args.junit:
        try:
            write_atomic(args.junit, junit_xml(r, args.allow_unfired))
        except OSError as exc:
            print(f"hil run: cannot write {args.junit}: {exc.strerror}", file=sys.stderr)
            return EXIT_USAGE
    if args.json:
        print(to_json(r, args.allow_unfired), file=sys.stdout)
    if scope is not None:
        scope.linger(sys.stderr)
    return code


def print_run(program: str, r, out) -> None:
    """The text summary of a run, as `hil run` prints it."""
    print_summary(program, r.bench, r.run, out)
    for w in r.warnings:  # M/S/T codes the MLC left waiting (hil/aux_watch.py)
        print(w.text, file=out)
    runner = r.runner
    waits = [(ln, w) for ln, w in runner.channel.planner.thread_waits if w] if runner.channel is not None else []
    if waits:  # threads armed only once the spindle settled at its command (motion decisions 33)
        print("spindle settle " + "  ".join(f"line {ln} {w * r.bench.cycle * 1000:g} ms" for ln, w in waits)
              + " before the thread", file=out)
    # an EventPlayer exists only if hil.api.run imported hil.run_events, for --at/--events (not imported otherwise)
    events = sys.modules.get("hil.run_events")
    player = runner.on_cycle if events is not None and isinstance(runner.on_cycle, events.EventPlayer) else None
    if player is not None:
        print("\n".join(player.summary()), file=out)
    print_timing(r.run, out)
    if r.checks:
        print("checks", file=out)
        for c in r.checks:
            print(f"  {c}", file=out)


def print_timing(r: RunResult, out=None) -> None:
    from hil.placement import PREFIX as PLACEMENT

    out = out or sys.stdout
    if r.realtime:
        j = r.timing.get("jitter", {})
        print(f"real time      {r.granted}", file=out)
        print("cycle jitter   " + "  ".join(f"{k} {j.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")),
              file=out)
        lat = r.timing.get("latency", {})
        if lat:
            print("wake latency   " + "  ".join(f"{k} {lat.get(k, 0.0) * 1e6:.1f} µs"
                                            for k in ("p50", "p99", "p99.9", "max")), file=out)
    elif r.granted.startswith(PLACEMENT):  # [realtime] lockstep = "fifo": what the system granted (decisions E21)
        print(f"placement      {r.granted[len(PLACEMENT):]}", file=out)
    e = r.timing.get("exec", {})
    if e:
        print("cycle work     " + "  ".join(f"{k} {e.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "max"))
              + ("  (wall clock, lock-step)" if not r.realtime else ""), file=out)
    for key, label in (("bus_wait", "bus wait       "), ("master", "master work    ")):  # a field bus (E25)
        w = r.timing.get(key, {})
        if w:
            print(label + "  ".join(f"{k} {w.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "max")), file=out)
    b = r.timing.get("between", {})
    if r.realtime and b:  # the work done in the periods' slack (decision B21): with cycle work, what a tick waits for
        print("between cycles " + "  ".join(f"{k} {b.get(k, 0.0) * 1e6:.1f} µs" for k in ("p50", "p99", "max")),
              file=out)
    if r.fits_ahead is not None and sum(r.fits_ahead):  # B86
        ahead, here = r.fits_ahead
        print(f"fitted windows {ahead} worked out ahead by a second process, {here} in the cycle", file=out)
    if r.overruns:
        print(f"overruns       {r.overruns} cycles ran past their deadline", file=sys.stderr if not r.alarms else out)


def print_summary(program: str, bench: Bench, r: RunResult, out=None) -> None:
    out = out or sys.stdout
    print(f"program        {program}  (profile {bench.profile}, bench {bench.name}, bus {bench.bus})", file=out)
    print(f"cycles         {r.cycles}  ({bench.cycle * 1000:g} ms cycle, {r.sim_time:.3f} s simulated)", file=out)
    resets = getattr(r, "power_up_resets", ())
    reset = ("  (fault reset at power-up: " + ", ".join(f"{a} 0x{c:04X}" for a, c in resets) + ")") if resets else ""
    print(f"drives enabled after {r.enable_cycles} cycles{reset}", file=out)
    print(f"program time   {r.program_time:.3f} s simulated", file=out)
    units = {a.name: "deg" if a.units == "deg" else "mm" for a in bench.axes}
    ferr = "  ".join(f"{a} {v:.4f} {units.get(a, 'mm')}" for a, v in r.max_ferr.items())
    print(f"max following error  {ferr}", file=out)
    final = "  ".join(f"{a} {v:.4f}" for a, v in r.final.items())
    print(f"final machine position  {final}", file=out)
    groups = getattr(r, "param_groups", ())
    if groups:  # G05 (decision language L25-1): which parameter group the motion used from where
        print("parameter groups  " + ", ".join(f"G05 P{n} at line {line}" for line, n in groups), file=out)
    if r.alarms:
        print(f"alarms         {len(r.alarms)}", file=out)
        for a in r.alarms:
            print(f"  {a}", file=out)
    else:
        print("alarms         none", file=out)
    why = f" by {r.stopped_by}: axes stopped along the path, drives disabled at standstill" if r.stopped_by else ""
    if r.stopped_by and r.ok:
        why = f" ({r.stopped_by} came after the program's end)"
    elif not r.ok and not r.alarms and not r.stopped_by:
        why = ": the program was aborted before its end (a reset flushes it)"
    print(f"result         {'completed' if r.ok else 'STOPPED'}{why}", file=out)
