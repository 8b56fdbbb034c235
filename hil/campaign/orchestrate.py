"""One campaign from file to results: expand the cases, skip those already done (by input hash),
run the rest, journal each row as it lands, then write results.parquet, the per-run traces and
reports, and summary.html."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hil.campaign.engine import Engine, Progress, SchedulerLost, run_cases
from hil.campaign.inputs import gather
from hil.campaign.matrix_html import matrix_page
from hil.campaign.results import RESULTS, Journal, report_dir, to_table, trace_dir, write_atomic
from hil.campaign.spec import load_campaign


@dataclass
class CampaignOutcome:
    rows: list[dict[str, Any]] = field(default_factory=list)
    skipped: int = 0  # cases whose result was already there (resume)
    interrupted: bool = False
    signal: str = "SIGINT"  # what interrupted it: Ctrl-C, or the signal that stopped a serial case's run (B107)
    lost: str = ""  # why the cluster went away mid-campaign (SchedulerLost), else ""
    unrun: int = 0  # cases to run that never finished (an interrupted or lost campaign)
    results: Path | None = None

    @property
    def ok(self) -> bool:
        return not self.interrupted and all(r["status"] == "completed" for r in self.rows)

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for r in self.rows:
            out[r["status"]] = out.get(r["status"], 0) + 1
        return out


@contextmanager
def _sigint_taken() -> Iterator[None]:
    """B114: SIGINT is the campaign's even when it was ignored at start (a non-interactive shell's background job
    `hil campaign … &`), as it is a run's (B94). Ignored, it was taken only inside each case's run (stop_on_signals)
    and lost between runs: `kill -INT` then let the campaign run on to its end. Here it raises KeyboardInterrupt as
    Ctrl-C from a terminal does, for the whole campaign; the local cluster's workers still start ignoring it (B55)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_campaign(path: str | Path, out: str | Path, engine: Engine | None = None, *, rerun: bool = False,
                 quiet: bool = True, reports: bool = True,
                 report_html: bool = True) -> CampaignOutcome:
    """Raises CampaignFileError (an InputError) for a bad campaign file, naming the field."""
    with _sigint_taken():
        return _run_campaign(path, out, engine, rerun=rerun, quiet=quiet, reports=reports, report_html=report_html)


def _run_campaign(path: str | Path, out: str | Path, engine: Engine | None, *, rerun: bool, quiet: bool,
                  reports: bool, report_html: bool) -> CampaignOutcome:
    campaign = load_campaign(path)
    engine = engine or Engine()
    engine.retries = campaign.retries
    cases = gather(campaign)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    journal = Journal(out)
    previous = {} if rerun else journal.previous()
    wanted = {c.input_hash for c in cases}
    outcome = CampaignOutcome()
    kept = [previous[h] for h in wanted if h in previous and previous[h]["status"] != "worker_lost"]
    todo = [c for c in cases if c.input_hash not in {r["input_hash"] for r in kept}]
    outcome.skipped = len(kept)
    outcome.rows = list(kept)
    progress = Progress(len(todo), quiet)
    ran = 0
    try:
        for row in run_cases(todo, engine):
            trace_bytes = row.pop("_trace_bytes", None)
            if trace_bytes is not None:
                folder = trace_dir(out, row)
                folder.mkdir(parents=True, exist_ok=True)
                (folder / "trace.parquet").write_bytes(trace_bytes)
                row["trace"] = (folder / "trace.parquet").relative_to(out).as_posix()
            journal.append(row)
            outcome.rows.append(row)
            progress.update(row)
            ran += 1
    except KeyboardInterrupt as exc:
        outcome.interrupted = True
        outcome.signal = getattr(exc, "signal_name", "SIGINT")
    except SchedulerLost as exc:  # what finished is written and the journal kept: the same command resumes (B76)
        outcome.interrupted = True
        outcome.lost = str(exc)
    finally:
        progress.close()
        outcome.unrun = len(todo) - ran
    outcome.rows = [r for r in outcome.rows if r["input_hash"] in wanted]
    outcome.results = out / RESULTS
    write_atomic(to_table(outcome.rows), outcome.results)
    journal.close(remove=not outcome.interrupted)
    if reports:
        _reports(out, outcome.rows, report_html)
    page = matrix_page(f"campaign {campaign.name}", outcome.rows, out)
    _write_text(out / "summary.html", page)
    return outcome


def _reports(out: Path, rows: list[dict[str, Any]], interactive: bool = True) -> None:
    """A report for each kept trace, in DIR/reports/<input hash>/ (not beside the trace: the traces
    folder is a Parquet dataset and must hold nothing else), for the matrix to link to."""
    from hil.report import write_report

    for r in rows:
        if not r.get("trace"):
            continue
        trace = out / r["trace"]
        target = out / report_dir(r)
        if trace.exists() and not (target / "index.html").exists():
            try:
                write_report(trace, target, title=f"{r['program']} on {r['bench']}", interactive=interactive)
            except Exception as exc:  # a report is a convenience: the row and trace stand without it
                _write_text(target / "index.html", f"<p>report failed: {exc}</p>")


def _write_text(path: Path, text: str) -> None:
    import os

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)
