"""Per-cycle trace, written row by row so memory stays flat on long runs.

One row per bench cycle: time and cycle number, the executing program line, the cycle's timing
(period and lateness), any alarm raised in it, each axis's setpoint and feedback, each spindle's
commanded and actual speed and angle, then any extra columns added by `TraceSource`s (the MLC
adds its signals of interest this way). `open_trace` picks the format from the file name:
`.parquet`/`.pq` → Parquet (columnar, written in row groups), anything else → CSV.
"""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path
from typing import IO, Any, Protocol, Sequence

INT_COLUMNS = ("cycle", "line")  # plus every *_sw statusword column


class TraceWriter(Protocol):
    columns: list[str]

    def write(self, row: Sequence[float | int | str]) -> None: ...

    def close(self, end: dict[str, Any] | None = None) -> None: ...

    def discard(self) -> None: ...


class TraceSource(Protocol):
    """Extra trace columns: `columns` names them, `values(runner)` gives this cycle's values
    (ints for bits and words, floats for quantities; the same type every cycle)."""

    columns: list[str]

    def values(self, runner: Any) -> Sequence[float | int | str]: ...


def trace_columns(axes: Sequence[str], spindles: Sequence[str], extra: Sequence[str] = ()) -> list[str]:
    cols = ["t", "line", "cycle", "period", "late", "alarm"]
    for a in axes:
        cols += [f"{a}_cmd", f"{a}_act", f"{a}_vel", f"{a}_torque", f"{a}_ferr", f"{a}_sw"]
    for s in spindles:
        cols += [f"{s}_rpm_cmd", f"{s}_rpm_act", f"{s}_angle", f"{s}_torque", f"{s}_sw"]
    return cols + list(extra)


def axes_of(columns: Sequence[str]) -> list[str]:
    return [c[:-4] for c in columns if c.endswith("_cmd") and not c.endswith("_rpm_cmd")]


def spindles_of(columns: Sequence[str]) -> list[str]:
    return [c[:-8] for c in columns if c.endswith("_rpm_cmd")]


def _csv_value(v: float | int | str) -> float | int | str:
    # repr of a float is the shortest text that reads back to the same double: CSV round-trips exactly.
    return repr(v) if isinstance(v, float) else v


def csv_meta_path(path: str | Path) -> Path:
    """A CSV trace's provenance and end record live beside it: CSV has no place for them."""
    p = Path(path)
    return p.with_name(p.name + ".meta.json")


class CsvTrace:
    def __init__(self, path: str | Path, columns: list[str], meta: dict[str, Any] | None = None,
                 units: dict[str, str] | None = None) -> None:
        self.path = Path(path)
        self.columns = columns
        self._meta = {**(meta or {}), **({"units": units} if units else {})}
        csv_meta_path(self.path).unlink(missing_ok=True)  # never leave an older run's record beside this trace
        # Written to a side file and renamed on close, so a failed run never leaves half a trace
        # that looks complete.
        self._tmp = self.path.with_name(self.path.name + ".part")
        import csv  # (a CSV trace's alone, not a Parquet one's)

        self._fh: IO[str] = open(self._tmp, "w", newline="")
        self._w = csv.writer(self._fh)
        self._w.writerow(columns)

    def write(self, row: Sequence[float | int | str]) -> None:
        self._w.writerow([_csv_value(v) for v in row])

    def close(self, end: dict[str, Any] | None = None) -> None:
        """The trace, then its side file with the provenance and the end-of-run record (a Parquet
        trace keeps both in its metadata)."""
        if not self._fh.closed:
            self._fh.close()
            self._tmp.replace(self.path)
            if self._meta:
                side = csv_meta_path(self.path)
                tmp = side.with_name(side.name + ".part")
                tmp.write_text(json.dumps({**self._meta, **({"end": end} if end else {})}, default=str))
                tmp.replace(side)

    def discard(self) -> None:
        """A run refused after its trace was opened leaves nothing."""
        if not self._fh.closed:
            self._fh.close()
        self._tmp.unlink(missing_ok=True)


def is_parquet(path: str | Path) -> bool:
    return Path(path).suffix.lower() in (".parquet", ".pq")


def check_target(path: str | Path) -> None:
    """Refuse an output path that is a folder now, not at the rename after the whole run."""
    if Path(path).is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))


def open_trace(path: str | Path, columns: list[str], meta: dict[str, Any] | None = None,
               units: dict[str, str] | None = None) -> TraceWriter:
    """`meta` (run provenance) and `units` (per column) go into a Parquet trace's metadata; a CSV
    trace is plain CSV."""
    check_target(path)
    Path(path).parent.mkdir(parents=True, exist_ok=True)  # `--trace out/run.csv` on a fresh clone
    if is_parquet(path):
        from hil.trace_parquet import ParquetTrace

        return ParquetTrace(path, columns, meta=meta, units=units)
    return CsvTrace(path, columns, meta=meta, units=units)
