"""Reading traces back (Parquet or CSV) as pyarrow tables or numpy columns, in batches when the
trace is too long to hold."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from hil.trace import INT_COLUMNS, is_parquet


FLOAT_COLUMNS = ("t", "period", "late")
FLOAT_SUFFIXES = ("_cmd", "_act", "_vel", "_torque", "_ferr", "_angle")  # _rpm_cmd / _rpm_act included


class TraceReadError(Exception):
    """A file that is not a trace this bench wrote (missing, unreadable, wrong columns)."""


def _csv_types(path: Path) -> dict[str, pa.DataType]:
    with open(path, newline="") as fh:
        header = fh.readline().strip().split(",")
    types: dict[str, pa.DataType] = {}
    for c in header:
        if c in INT_COLUMNS or c.endswith("_sw"):
            types[c] = pa.int64()
        elif c in ("alarm", "event"):  # event: `hil run --at` actions (hil/run_events.py)
            types[c] = pa.string()
        elif c in FLOAT_COLUMNS or c.endswith(FLOAT_SUFFIXES):  # text there is damage, not data
            types[c] = pa.float64()
    return types


class TraceFile:
    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise TraceReadError(f"{path}: no such trace file")
        self.parquet = is_parquet(self.path)
        try:
            if self.parquet:
                self._pf = pq.ParquetFile(self.path)
                self.columns = list(self._pf.schema_arrow.names)
                self.num_rows = self._pf.metadata.num_rows
            else:
                self._types = _csv_types(self.path)
                self.columns = list(self._types_header())
                self.num_rows = -1
        except (pa.ArrowInvalid, OSError, UnicodeDecodeError) as exc:
            raise TraceReadError(f"{path}: not a readable trace ({exc})") from None
        if "t" not in self.columns or "line" not in self.columns:
            raise TraceReadError(f"{path}: not a bench trace (no 't' and 'line' columns)")

    def _types_header(self) -> list[str]:
        with open(self.path, newline="") as fh:
            return fh.readline().strip().split(",")

    def _convert(self, columns: Sequence[str] | None) -> pacsv.ConvertOptions:
        return pacsv.ConvertOptions(column_types=self._types, include_columns=list(columns) if columns else None,
                                    strings_can_be_null=False)

    def batches(self, columns: Sequence[str] | None = None, batch_rows: int = 65_536) -> Iterator[pa.RecordBatch]:
        try:
            if self.parquet:
                yield from self._pf.iter_batches(batch_size=batch_rows, columns=list(columns) if columns else None)
            else:
                reader = pacsv.open_csv(self.path, read_options=pacsv.ReadOptions(block_size=1 << 22),
                                        convert_options=self._convert(columns))
                yield from reader
        except pa.ArrowInvalid as exc:
            raise TraceReadError(f"{self.path}: damaged trace ({exc})") from None

    def table(self, columns: Sequence[str] | None = None) -> pa.Table:
        try:
            if self.parquet:
                return self._pf.read(columns=list(columns) if columns else None)
            return pacsv.read_csv(self.path, convert_options=self._convert(columns))
        except pa.ArrowInvalid as exc:
            raise TraceReadError(f"{self.path}: damaged trace ({exc})") from None

    def arrays(self, columns: Sequence[str] | None = None) -> dict[str, np.ndarray]:
        """The named columns (all when None) as numpy arrays (strings as object arrays)."""
        tab = self.table([c for c in columns if c in self.columns] if columns else None)
        out: dict[str, np.ndarray] = {}
        for name in tab.column_names:
            col = tab.column(name)
            if pa.types.is_string(col.type) or pa.types.is_large_string(col.type):
                out[name] = np.array(col.to_pylist(), dtype=object)
            else:
                out[name] = col.to_numpy()
        return out


def write_table(tab: pa.Table, path: str | Path) -> None:
    """Export: Parquet or CSV by the file's extension."""
    if is_parquet(path):
        pq.write_table(tab, path, compression="zstd")
    else:
        pacsv.write_csv(tab, path, write_options=pacsv.WriteOptions(quoting_style="needed"))
