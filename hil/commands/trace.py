"""`hil trace FILE`: summarise a trace, slice it by time or program line, export CSV/Parquet."""

from __future__ import annotations

import argparse
import sys

from hil.cli import EXIT_OK, EXIT_USAGE


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("trace", help="summarise, slice or export a run's trace (CSV or Parquet)")
    p.add_argument("file", help="trace written by hil run --trace")
    p.add_argument("--from", dest="lo", metavar="T|Ln", help="start: time in s (1.5) or program line (L12)")
    p.add_argument("--to", dest="hi", metavar="T|Ln", help="end: time in s or program line (inclusive)")
    p.add_argument("--columns", help="comma-separated columns to export (t and line are always kept first)")
    p.add_argument("--out", metavar="FILE", help="export the slice by its suffix: .parquet/.pq, .csv, "
                   ".feather/.arrow (Arrow IPC), .mf4 (MDF4 with units, needs deltahil[mdf])")
    p.set_defaults(func=cmd_trace)


def cmd_trace(args: argparse.Namespace) -> int:
    from hil.trace_read import TraceFile, TraceReadError  # pyarrow: only when a trace is read
    from hil.trace_summary import Bound, check_bounds, empty_slice, export, format_summary, summarise

    try:
        lo = Bound.parse(args.lo) if args.lo else None
        hi = Bound.parse(args.hi) if args.hi else None
        tf = TraceFile(args.file)
        if args.out:
            cols = [c.strip() for c in args.columns.split(",") if c.strip()] if args.columns else None
            if cols:
                cols = list(dict.fromkeys(["t", "line"] + cols))
            rows = export(tf, args.out, lo, hi, cols)
            print(f"wrote {rows} rows to {args.out}")
            return EXIT_OK
        check_bounds(lo, hi)
        s = summarise(tf, lo, hi)
        if s.rows == 0 and (lo is not None or hi is not None):
            raise empty_slice(tf, lo, hi)  # "rows 0" read as a trace with nothing in it (decisions B53)
        print(format_summary(tf, s))
    except BrokenPipeError:  # `hil trace … | head`: hil.cli ends quietly
        raise
    except OSError as exc:
        print(f"hil trace: {exc.filename or args.out}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    except (ValueError, TraceReadError) as exc:
        print(f"hil trace: {exc}", file=sys.stderr)
        return EXIT_USAGE
    return EXIT_OK
