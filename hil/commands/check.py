"""`hil check TRACE`: judge a trace by the bench's [checks] and/or limits given on the command line.
Exit 0 when every check passes, 1 when one fails (naming its cycle and line), 2 on bad input."""

from __future__ import annotations

import argparse
import sys

from typing import TYPE_CHECKING

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE

if TYPE_CHECKING:  # the bench, traces and pyarrow load when the command runs, not at start-up
    from hil.bench import Bench, ChecksConfig
    from hil.trace_read import TraceFile


def add_check_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--bench", help="bench file: axes, limits and its [checks]")
    p.add_argument("--program", help="the G-code program the trace ran (for contour and thread checks)")
    p.add_argument("--max-ferr", type=float, metavar="MM", help="max following error on every axis, mm")
    p.add_argument("--contour", type=float, metavar="MM", help="max distance from the programmed path, mm")
    p.add_argument("--limits", action="store_true", help="setpoint velocity/acceleration/jerk within axis limits")
    p.add_argument("--thread-phase", type=float, metavar="DEG", help="max phase spread of thread passes, degrees")
    p.add_argument("--jitter-p99", type=float, metavar="US", help="p99 of |period - cycle|, µs")
    p.add_argument("--jitter-max", type=float, metavar="US", help="max |period - cycle|, µs")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="check a trace: following/contour error, v/a/j limits, thread phase, jitter")
    p.add_argument("trace", help="trace file (CSV or Parquet) from hil run --trace")
    add_check_options(p)
    p.add_argument("--against", metavar="REF", help="a reference trace of the same program (a run kept as good): "
                   "the commanded path, the program's time, how the run ended and the recorded MLC signals compared")
    p.add_argument("--path-tol", type=float, default=0.001, metavar="MM",
                   help="with --against: the paths' largest distance from each other, mm (default 0.001)")
    p.add_argument("--time-tol", type=float, metavar="S",
                   help="with --against: the program times' largest difference, s (default 1 %% of the reference's)")
    p.add_argument("--json", action="store_true", help="one JSON object per check")
    p.set_defaults(func=cmd_check)


CHECK_FLAGS = ("max_ferr", "contour", "limits", "thread_phase", "jitter_p99", "jitter_max")


def checks_from_args(args: argparse.Namespace, bench: Bench | None, axes: list[str],
                     recorded: bool = False) -> ChecksConfig:
    """The bench's [checks] with the command line's limits over them. A bench only recorded in
    the trace lends its [checks] when no check is asked for: then the trace is judged as its run
    was; with flags, only what they ask."""
    from hil.bench import ChecksConfig
    from hil.session import InputError

    asked = any(getattr(args, k) not in (None, False) for k in CHECK_FLAGS)
    c = bench.checks if bench is not None and not (recorded and asked) else ChecksConfig()
    for opt in ("max_ferr", "contour", "thread_phase", "jitter_p99", "jitter_max"):
        v = getattr(args, opt)
        if v is not None and not 0.0 <= v < float("inf"):  # a negative limit fails every trace
            raise InputError(f"--{opt.replace('_', '-')} {v:g}: a limit must be >= 0")
    if args.max_ferr is not None:
        c.max_following_error = {a: args.max_ferr for a in (bench.axis_names if bench is not None else axes)}
    if args.contour is not None:
        c.contour_error = args.contour
    if args.limits:
        c.limits = True
    if args.thread_phase is not None:
        c.thread_phase = args.thread_phase
    if args.jitter_p99 is not None:
        c.jitter_p99 = args.jitter_p99 / 1e6
    if args.jitter_max is not None:
        c.jitter_max = args.jitter_max / 1e6
    return c


def trace_bench(args: argparse.Namespace, tf: TraceFile) -> tuple[Bench | None, str]:
    """The bench to judge the trace against, and how it was found: --bench, else the bench the
    trace's metadata records (Parquet traces from `hil run`), else none (decision R4)."""
    from hil.session import load_bench
    from hil.trace_meta import bench_from_meta

    recorded = bench_from_meta(tf.meta)
    if args.bench:
        bench = load_bench(args.bench)
        if recorded is not None and recorded.name != bench.name:
            print(f"hil: note: {args.trace} was recorded on bench {recorded.name}; checking against "
                  f"{bench.name} ({args.bench}) as asked", file=sys.stderr)
        return bench, f"{bench.name} ({args.bench})"
    if recorded is not None:
        src = f", {recorded.source}" if recorded.source else ""
        return recorded, f"{recorded.name} (recorded in the trace{src})"
    return None, ""


def prepare(args: argparse.Namespace, cmd: str):
    """Bench, checks, trace, the programmed moves and where the bench came from; bad input raises
    InputError / TraceReadError / NcAlarm."""
    from hil.checks import NO_PROGRAM, program_moves, program_start
    from hil.session import InputError, load_program
    from hil.trace import axes_of, csv_meta_path
    from hil.trace_read import TraceFile

    tf = TraceFile(args.trace)
    bench, origin = trace_bench(args, tf)
    checks = checks_from_args(args, bench, axes_of(tf.columns), recorded=bench is not None and not args.bench)
    rows = tf.num_rows if tf.num_rows >= 0 else tf.table(["t"]).num_rows
    if rows == 0:  # e.g. a run whose bus never opened: passing its checks would judge nothing as good
        raise InputError(f"{args.trace} has no rows (its run stopped before the first cycle): nothing to check")
    if bench is None:
        needs = [n for n, on in (("--limits", checks.limits), ("--program", bool(args.program))) if on]
        if needs:  # never judge against limits or a path the trace did not run with
            raise InputError(f"{args.trace} does not say which bench it ran on (hil run records it in a Parquet "
                             f"trace, and beside a CSV trace as {csv_meta_path(args.trace).name}): "
                             f"give --bench FILE for {' and '.join(needs)}")
    else:
        missing = [a for a in bench.axis_names if f"{a}_cmd" not in tf.columns]
        if missing:
            raise InputError(f"{args.trace} has no columns for axis {', '.join(missing)} of bench {bench.name}")
    if args.program and bench is not None:
        # The program given here is the user's: an alarm offline is reported as the NC would (exit 1).
        return bench, checks, tf, program_moves(load_program(args.program), bench,
                                                program_start(tf, bench.axis_names)), origin, NO_PROGRAM
    moves, why = None, NO_PROGRAM
    if bench is not None:  # the program the run recorded, while its file is unchanged (B75)
        from hil.checks import offline_moves
        from hil.trace_meta import recorded_program

        program, libs, note = recorded_program(tf.meta)
        if program:
            # an offline alarm (a program reading what only a run answers) skips the path checks saying why,
            # as after `hil run`
            moves, why = offline_moves(load_program(program, libs), bench, program_start(tf, bench.axis_names))
            origin += f"\nprogram {program} (recorded in the trace)"
        elif note:
            print(f"hil {cmd}: note: {note}: give --program for the path checks", file=sys.stderr)
    return bench, checks, tf, moves, origin, why


def prepared(args: argparse.Namespace, cmd: str):
    """`prepare`, with a bad input reported for `hil CMD`: returns the tuple, or the exit code."""
    from hil.session import InputError, print_alarm
    from hil.trace_read import TraceReadError
    from nc.alarms import NcAlarm

    try:
        return prepare(args, cmd)
    except (InputError, TraceReadError) as exc:
        print(f"hil {cmd}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except NcAlarm as exc:
        print_alarm(exc.alarm)
        return EXIT_ALARM


def cmd_check(args: argparse.Namespace) -> int:
    from hil import strict_json
    from hil.checks import run_checks
    from hil.trace_read import TraceReadError

    ready = prepared(args, "check")
    if isinstance(ready, int):
        return ready
    bench, checks, tf, moves, origin, why = ready
    if not checks.any and not args.against:
        print("hil check: no checks to run: give a --bench with [checks], limits such as --max-ferr, or --against "
              "a reference trace", file=sys.stderr)
        return EXIT_USAGE
    try:  # the trace is read here: damage past its header shows now
        results = run_checks(tf, checks, bench, moves, why)
        if args.against:
            results += _against(args, tf)
    except TraceReadError as exc:
        print(f"hil check: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except ValueError as exc:  # a bad --against pairing or tolerance (_against)
        print(f"hil check: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if origin and not args.json:
        print(f"bench {origin}")
    from hil.trace_summary import end_note

    note = end_note(tf.meta)
    if note:  # B87: "12 passed" on a run its alarm ended is not a pass of the program
        print(f"{note}: the checks judge the cycles it ran", file=sys.stderr if args.json else sys.stdout)
    for r in results:
        print(strict_json.dumps(r.as_dict()) if args.json else str(r))
    failed = [r for r in results if not r.ok and not r.skipped]
    skipped = [r for r in results if r.skipped]
    passed = len(results) - len(failed) - len(skipped)
    if not args.json:
        print(f"{passed} passed, {len(failed)} failed" + (f", {len(skipped)} skipped" if skipped else ""))
    # A check that could not run for want of input (the program, the bench) is not a pass; one with
    # nothing to judge in this run (no thread in the program) is only reported.
    unjudged = [r for r in skipped if r.detail.startswith("needs")]
    if unjudged:
        print(f"hil check: {len(unjudged)} check(s) skipped ({'; '.join(r.detail for r in unjudged)}): "
              "nothing was judged there", file=sys.stderr)
    return EXIT_ALARM if failed or unjudged else EXIT_OK


def _against(args: argparse.Namespace, tf: TraceFile) -> list:
    """`--against REF` (decision B127): REF read as a trace; the two must have run on the same axes."""
    from hil.trace import axes_of
    from hil.trace_against import check_against
    from hil.trace_read import TraceFile

    for opt, v in (("--path-tol", args.path_tol), ("--time-tol", args.time_tol)):
        if v is not None and not 0.0 <= v < float("inf"):
            raise ValueError(f"{opt} {v:g}: a tolerance must be >= 0")
    ref = TraceFile(args.against)
    mine, theirs = axes_of(tf.columns), axes_of(ref.columns)
    if sorted(mine) != sorted(theirs):
        raise ValueError(f"{args.against} ran on axes {', '.join(theirs) or 'none'}, {args.trace} on "
                         f"{', '.join(mine) or 'none'}: a reference must be a run of the same bench's axes")
    return check_against(tf, ref, args.path_tol, args.time_tol)
