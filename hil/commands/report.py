"""`hil report TRACE --out DIR`: an HTML report with PNG plots (path, following error, velocity
and torque, jitter histogram, MLC signal timeline), plus the checks when a bench or limits are given."""

from __future__ import annotations

import argparse
import sys

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from hil.commands.check import add_check_options, prepared


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="write an HTML report with plots of a trace")
    p.add_argument("trace", help="trace file (CSV or Parquet) from hil run --trace")
    p.add_argument("--out", required=True, metavar="DIR", help="directory for index.html and the PNGs")
    p.add_argument("--title", help="report title")
    add_check_options(p)
    p.set_defaults(func=cmd_report)


def cmd_report(args: argparse.Namespace) -> int:
    from hil.checks import run_checks
    from hil.report import write_report
    from hil.trace_read import TraceReadError

    ready = prepared(args, "report")
    if isinstance(ready, int):
        return ready
    bench, checks, tf, moves, origin, why = ready
    try:  # the trace is read here: damage past its header shows now
        results = run_checks(tf, checks, bench, moves, why) if checks.any else None
        rep = write_report(args.trace, args.out, bench, moves, results, args.title)
    except TraceReadError as exc:
        print(f"hil report: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:
        print(f"hil report: cannot write {args.out}: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE
    if origin:
        print(f"bench {origin}")
    from hil.trace_summary import end_note

    note = end_note(tf.meta)
    if note:  # B87 (the report's summary says it too)
        print(note)
    print(f"wrote {rep.html}")
    if rep.interactive:
        print(f"  {rep.interactive} (interactive, opens offline)")
    for img in rep.images:
        print(f"  {img}")
    if results and not all(r.ok for r in results):
        print("checks failed: see the report", file=sys.stderr)
        return EXIT_ALARM
    return EXIT_OK
