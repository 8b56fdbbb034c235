"""`hil campaign FILE --out DIR`: a matrix of lock-step runs on Dask, one Parquet row per case;
`hil campaign diff BASE NEW`: what changed between two campaigns (exit 1 on a regression)."""

from __future__ import annotations

import argparse
import signal
import sys

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2
EXIT_CLUSTER = 3  # the cluster's scheduler went away mid-campaign: resumable, nothing judged for the rest (B76)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("campaign", help="run a matrix of lock-step runs (programs × benches × variants) on Dask; "
                                        "`hil campaign diff BASE NEW` compares two results",
                       description="hil campaign FILE --out DIR [--scheduler tcp://HOST:PORT] [--workers N] "
                                   "[--rerun]  |  hil campaign diff BASE NEW [--html FILE]")
    p.add_argument("args", nargs="+", metavar="FILE | diff BASE NEW")
    p.add_argument("--out", metavar="DIR", help="results folder (results.parquet, traces/, summary.html)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="an existing Dask scheduler (default: a local "
                                                                  "cluster of one worker per core)")
    p.add_argument("--workers", type=int, metavar="N", help="local cluster size; 0 runs the cases serially here")
    p.add_argument("--rerun", action="store_true", help="run every case again, even those with a result")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.add_argument("--no-reports", action="store_true", help="no per-run report next to kept traces")
    p.add_argument("--no-report-html", action="store_true",
                   help="per-run reports without report.html (PNG report only: faster and ~5 MB less per run)")
    p.add_argument("--time-tol", type=float, default=0.01, metavar="FRACTION",
                   help="diff: relative change of program time that counts (default 0.01)")
    p.add_argument("--error-tol", type=float, default=0.005, metavar="MM",
                   help="diff: change of a following or contour error that counts (default 0.005 mm)")
    p.add_argument("--share-tol", type=float, default=0.02, metavar="FRACTION",
                   help="diff: change of a peak v/a/j share of its limit that counts (default 0.02)")
    p.add_argument("--html", metavar="FILE", help="diff: write the new matrix with the changed cases marked")
    p.set_defaults(func=cmd_campaign)


def cmd_campaign(args: argparse.Namespace) -> int:
    if args.args[0] == "diff":
        if len(args.args) != 3:
            print("hil campaign diff: give BASE and NEW (results.parquet files or campaign folders)", file=sys.stderr)
            return EXIT_USAGE
        return cmd_diff(args, *args.args[1:])
    if len(args.args) != 1:
        print("hil campaign: give one campaign file (or `diff BASE NEW`)", file=sys.stderr)
        return EXIT_USAGE
    if not args.out:
        print("hil campaign: --out DIR is required", file=sys.stderr)
        return EXIT_USAGE
    if args.workers is not None and args.workers < 0:
        print(f"hil campaign: --workers {args.workers}: must be 0 (serial) or more", file=sys.stderr)
        return EXIT_USAGE
    if args.scheduler and not args.scheduler.startswith(("tcp://", "tls://", "inproc://", "ucx://")):
        print(f"hil campaign: --scheduler {args.scheduler!r}: give an address like tcp://HOST:8786", file=sys.stderr)
        return EXIT_USAGE
    from hil.campaign import Engine, run_campaign
    from hil.session import InputError

    engine = Engine(scheduler=args.scheduler, workers=args.workers)
    try:
        outcome = run_campaign(args.args[0], args.out, engine, rerun=args.rerun, quiet=args.quiet,
                               reports=not args.no_reports, report_html=not args.no_report_html)
    except InputError as exc:
        print(f"hil campaign: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:
        if "connect" in str(exc).lower() or isinstance(exc, (ConnectionError, TimeoutError)):
            print(f"hil campaign: cannot reach the scheduler {args.scheduler}: {exc}", file=sys.stderr)
            return EXIT_USAGE
        raise
    counts = outcome.counts()
    total = len(outcome.rows)
    print(f"campaign       {args.args[0]}")
    print(f"cases          {total}  ({outcome.skipped} already done, {total - outcome.skipped} run)")
    print("status         " + "  ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    bad = [r for r in outcome.rows if r["status"] != "completed"]
    for r in bad[:20]:
        why = r.get("alarm") or r.get("checks_failed") or ""
        line = f" line {r['alarm_line']}" if r.get("alarm_line") else ""
        print(f"  {r['status']:<12} {r['program']} on {r['bench']} ({_variant(r)}) {why}{line}".rstrip())
    if len(bad) > 20:
        print(f"  … and {len(bad) - 20} more (see results.parquet)")
    print(f"results        {outcome.results}")
    print(f"summary        {outcome.results.parent / 'summary.html'}")
    if outcome.lost:
        done = total - outcome.skipped
        print(f"hil campaign: {outcome.lost} after {done} of {done + outcome.unrun} cases; what finished is written: "
              "run the same command again (with a scheduler) to resume", file=sys.stderr)
        return EXIT_CLUSTER
    if outcome.interrupted:
        how = "interrupted" if outcome.signal == "SIGINT" else f"stopped by {outcome.signal}"
        print(f"hil campaign: {how}; run the same command again to resume", file=sys.stderr)
        return 128 + int(getattr(signal, outcome.signal, signal.SIGINT))  # 130, 143 ... as README "Exit codes"
    return EXIT_OK if outcome.ok else EXIT_FAIL


def _variant(r: dict) -> str:
    from hil.campaign.matrix_html import variant

    return variant(r)


def cmd_diff(args: argparse.Namespace, base: str, new: str) -> int:
    from pathlib import Path

    from hil.campaign.diff import Tolerances, _key, diff, load_rows

    rows = []
    for p in (base, new):
        try:
            rows.append(load_rows(p))
        except (OSError, ValueError) as exc:
            print(f"hil campaign diff: {p}: not a campaign result ({exc})", file=sys.stderr)
            return EXIT_USAGE
    d = diff(rows[0], rows[1], Tolerances(args.time_tol, args.error_tol, args.share_tol))
    print(f"compared       {d.compared} cases  ({len(d.added)} new, {len(d.missing)} gone)")
    for c in d.changes:
        print(c.line())
    for r in d.added:
        print(f"new           {r['program']} on {r['bench']} ({_variant(r)}): {r['status']}")
    for r in d.missing:
        print(f"gone          {r['program']} on {r['bench']} ({_variant(r)})")
    print(f"regressions    {len(d.regressions)}")
    if args.html:
        from hil.campaign.matrix_html import matrix_page

        page = matrix_page(f"campaign diff {base} → {new}", rows[1], Path(new) if Path(new).is_dir()
                           else Path(new).parent, changed={tuple(c.key.values()) for c in d.changes}, key=_key)
        Path(args.html).write_text(page, encoding="utf-8")
        print(f"html           {args.html}")
    return EXIT_FAIL if d.regressions else EXIT_OK
