"""What a Dask worker (or the serial loop) does with one case: lay out its inputs in a scratch
folder, run it in lock-step, and turn the outcome into a result row. Every outcome is a row —
an alarm, a failed check, a bad input — so one case never aborts the campaign."""

from __future__ import annotations

import math
import os
import socket
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from hil.campaign.inputs import CaseInputs, materialise
from hil.version import version


class CaseStopped(KeyboardInterrupt):
    """A signal stopped the case's run under control (a serial campaign's run holds the signal handlers): the case
    did not finish, so it is no row and the campaign is interrupted as by Ctrl-C between cases (B107)."""

    def __init__(self, signal_name: str):
        super().__init__(signal_name)
        self.signal_name = signal_name


def base_row(case: CaseInputs) -> dict[str, Any]:
    return {**case.key, "input_hash": case.input_hash, "deltahil_version": version(),
            "worker": f"{socket.gethostname()}:{os.getpid()}", "attempts": 1}


def lost_row(case: CaseInputs, why: str, attempts: int) -> dict[str, Any]:
    """A case whose worker died `attempts` times (Dask's KilledWorker)."""
    row = base_row(case)
    row.update(status="worker_lost", message=why[:500], attempts=attempts, worker=None)
    return row


def run_case(case: CaseInputs) -> dict[str, Any]:
    t0 = time.perf_counter()
    row = base_row(case)
    with tempfile.TemporaryDirectory(prefix="hil-case-") as tmp:
        try:
            row.update(_execute(case, Path(tmp)))
        except Exception as exc:  # never lose a row: an unexpected error is the NC's internal alarm
            from nc.alarms import internal_error

            alarm = internal_error(exc)
            row.update(status="alarm", alarm=alarm.code_text, message=alarm.message[:500])
    row["wall_s"] = time.perf_counter() - t0
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}


def _execute(case: CaseInputs, scratch: Path) -> dict[str, Any]:
    from hil.api import run as hil_run
    from hil.bench_file import BenchFileError
    from hil.campaign.variant import apply_variant

    where = materialise(case, scratch)
    bench_path = where[case.bench]
    try:
        bench = apply_variant(Path(bench_path).read_text(encoding="utf-8"), bench_path, case, case.checks,
                              case.max_time)
    except BenchFileError as exc:
        return {"status": "alarm", "message": str(exc)[:500]}
    trace = scratch / "trace.parquet"
    mlc = where.get(case.mlc, case.mlc) if case.mlc else None
    result = hil_run(where[case.program], bench=bench, trace=str(trace), mlc=mlc, events=case.events,
                     libs=[where[x] for x in case.libs], feed_override=case.override,
                     rapid_override=case.rapid_override, spindle_override=case.spindle_override)
    stopped_by = getattr(result.run, "stopped_by", None)
    if stopped_by:  # a cut run is no `completed` row (B107)
        raise CaseStopped(stopped_by)
    if result.runner is None:  # the program could not be read or parsed
        a = result.alarms[0]
        return {"status": "alarm", "alarm": a.code_text, "alarm_line": a.line, "message": a.message[:500]}
    out: dict[str, Any] = {"program_time_s": result.program_time, "sim_time_s": result.sim_time,
                           "cycles": result.cycles}
    for axis, v in result.max_following_error.items():
        out[f"max_ferr_{axis}"] = v
    failed = [c for c in result.checks if not c.ok and not c.skipped]
    if result.alarms:
        a = result.alarms[0]
        out.update(status="timeout" if _is_timeout(a) else "alarm", alarm=a.code_text, alarm_line=a.line,
                   message=a.message[:500])
    elif failed:
        out.update(status="check_failed", checks_failed="; ".join(c.name for c in failed))
    elif result.unfired:  # B88: the case's fault never happened, so the case tested nothing of it (hil run: exit 3)
        never = "; ".join(e.spec for e in result.unfired)
        out.update(status="not_triggered", message=f"never triggered: {never}"[:500])
    else:
        out["status"] = "completed"
    if trace.exists():
        out.update(_trace_metrics(trace, bench, result))
        if case.want_trace:
            out["_trace_bytes"] = trace.read_bytes()
    return out


def _is_timeout(alarm: Any) -> bool:
    """The run outlived the campaign's (or bench's) max_time: the runner's own guard alarm."""
    from hil.runner import MAX_TIME_ALARM

    return alarm.code == MAX_TIME_ALARM


def _trace_metrics(trace: Path, bench: Any, result: Any) -> dict[str, Any]:
    """Peak setpoint v/a/j of each axis as a share of its limit (backward differences per cycle,
    as `hil check --limits` takes them) and the largest contour error the checks found."""
    from hil.trace_read import TraceFile

    tf = TraceFile(str(trace))
    out: dict[str, Any] = {}
    names = [f"{a.name}_cmd" for a in bench.axes if f"{a.name}_cmd" in tf.columns]
    cols = tf.arrays(["t", *names]) if names else {}
    t = cols.get("t")
    dt = float(np.median(np.diff(t))) if t is not None and len(t) > 1 else bench.cycle
    for ax in bench.axes:
        x = cols.get(f"{ax.name}_cmd")
        if x is None:
            continue
        for order, (tag, lim) in enumerate((("v", ax.limits.max_velocity), ("a", ax.limits.max_acceleration),
                                            ("j", ax.limits.max_jerk)), start=1):
            d = np.abs(np.diff(np.asarray(x, dtype=float), n=order)) / dt ** order
            out[f"peak_{tag}_share_{ax.name}"] = float(d.max()) / lim if d.size and lim > 0 else 0.0
    contour = [c.value for c in result.checks if c.name == "contour error" and not c.skipped]
    if contour:
        out["max_contour_error"] = max(contour)
    return out
