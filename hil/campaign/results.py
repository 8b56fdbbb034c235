"""The campaign's results: one row per case in `DIR/results.parquet`, a journal that makes an
interrupted campaign resumable, and per-run traces as a Hive-partitioned Parquet dataset
(`DIR/traces/program=…/bench=…/case=…/trace.parquet`) that pandas, polars and duckdb read directly.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any, Iterable

import pyarrow as pa
import pyarrow.parquet as pq

from hil import strict_json

STATUSES = ("completed", "alarm", "check_failed", "not_triggered", "worker_lost", "timeout")
KEY_COLUMNS = ("program", "bench", "bus", "override", "rapid_override", "spindle_override", "params", "fault")
# Fixed columns and their types; per-axis metrics (max_ferr_X, peak_v_share_X …) are float64 and
# follow, in name order. A value that does not apply (no alarm, an axis a bench lacks) is null.
SCHEMA = pa.schema([
    ("program", pa.string()), ("bench", pa.string()), ("bus", pa.string()), ("override", pa.float64()),
    ("rapid_override", pa.float64()), ("spindle_override", pa.float64()), ("params", pa.string()),
    ("fault", pa.string()), ("status", pa.string()), ("alarm", pa.string()), ("alarm_line", pa.int64()),
    ("message", pa.string()), ("checks_failed", pa.string()), ("program_time_s", pa.float64()),
    ("sim_time_s", pa.float64()), ("cycles", pa.int64()), ("max_contour_error", pa.float64()),
    ("wall_s", pa.float64()), ("attempts", pa.int64()), ("worker", pa.string()), ("trace", pa.string()),
    ("deltahil_version", pa.string()), ("input_hash", pa.string()),
])
# Columns that depend on where and when a case ran, not on what it computed.
RUN_COLUMNS = ("wall_s", "attempts", "worker", "trace")
JOURNAL = "journal.jsonl"
RESULTS = "results.parquet"


def to_table(rows: Iterable[dict[str, Any]]) -> pa.Table:
    rows = sorted(rows, key=lambda r: tuple(str(r.get(k)) for k in KEY_COLUMNS))
    extra = sorted({k for r in rows for k in r} - set(SCHEMA.names))
    schema = pa.schema(list(SCHEMA) + [(k, pa.float64()) for k in extra])
    return pa.Table.from_pylist([{k: r.get(k) for k in schema.names} for r in rows], schema=schema)


def write_atomic(table: pa.Table, path: Path) -> None:
    """Readers see the previous complete file or the new one, never half of one."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


class Journal:
    """One JSON line per finished case, flushed as it lands: what a resumed campaign skips."""

    def __init__(self, out: Path) -> None:
        self.path = out / JOURNAL
        self._f = None

    def previous(self) -> dict[str, dict[str, Any]]:
        """Rows already there, by input hash: from results.parquet and from the journal."""
        rows: dict[str, dict[str, Any]] = {}
        res = self.path.parent / RESULTS
        if res.exists():
            for r in pq.read_table(res).to_pylist():
                rows[r["input_hash"]] = r
        if self.path.exists():
            for line in self.path.read_text(encoding="utf-8").splitlines():
                try:
                    r = json.loads(line)
                except json.JSONDecodeError:  # a line cut by a crash mid-write
                    continue
                rows[r["input_hash"]] = r
        return rows

    def append(self, row: dict[str, Any]) -> None:
        if self._f is None:
            self._f = self.path.open("a", encoding="utf-8")
        self._f.write(strict_json.dumps(row) + "\n")  # a NaN figure is null, never a crash
        self._f.flush()
        os.fsync(self._f.fileno())

    def close(self, remove: bool) -> None:
        if self._f is not None:
            self._f.close()
            self._f = None
        if remove:
            self.path.unlink(missing_ok=True)


def trace_dir(out: Path, row: dict[str, Any]) -> Path:
    """Hive partitions by program and bench, one folder per case."""
    return (out / "traces" / f"program={_safe(row['program'])}" / f"bench={_safe(row['bench'])}"
            / f"case={row['input_hash']}")


def report_dir(row: dict[str, Any]) -> Path:
    """Relative to DIR: where a traced case's report goes."""
    return Path("reports") / row["input_hash"]


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", Path(name).name)
