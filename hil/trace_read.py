"""Reading traces back (Parquet or CSV) as pyarrow tables or numpy columns, in batches when the
trace is too long to hold."""

from __future__ import annotations

import json

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
    header = _header(path)
    types: dict[str, pa.DataType] = {}
    for c in header:
        if c in INT_COLUMNS or c.endswith("_sw"):
            types[c] = pa.int64()
        elif c in ("alarm", "event"):  # event: `hil run --at` actions (hil/run_events.py)
            types[c] = pa.string()
        elif c in FLOAT_COLUMNS or c.endswith(FLOAT_SUFFIXES):  # text there is damage, not data
            types[c] = pa.float64()
    return types


def _header(path: Path) -> list[str]:
    """A CSV trace's column names (quoted or not: pyarrow's CSV writer quotes them)."""
    import csv

    with open(path, newline="") as fh:
        return next(csv.reader([fh.readline()]), [])


def _check_types(path: str | Path, schema: pa.Schema) -> None:
    """Numbers where the bench writes numbers: a string `t` would otherwise surface as an internal error
    deep inside a check (decisions inputs.md I5)."""
    for f in schema:  # integer columns may be stored as doubles (a header-only trace writes them so)
        c = f.name
        numeric = c in INT_COLUMNS or c.endswith("_sw") or c in FLOAT_COLUMNS or c.endswith(FLOAT_SUFFIXES)
        if numeric and not (pa.types.is_floating(f.type) or pa.types.is_integer(f.type) or pa.types.is_null(f.type)):
            raise TraceReadError(f"{path}: column {c!r} must hold numbers, got {f.type}")


def _missing(path: Path) -> str:
    """Why there is no trace to read: a run killed hard leaves `<trace>.part` (bench decisions, B73)."""
    from hil.trace_parquet import FLUSH_S  # (only on this error path)

    part = path if path.name.endswith(".part") else path.with_name(path.name + ".part")
    if part.is_dir() and part != path and any(part.glob("*.parquet")):
        return (f"no such trace file; {part.name} is what a run killed before it finished left: give that (its "
                "rows up to its last flush), or rerun")
    if part.is_dir():  # a Parquet trace's parts, with none in it
        why = f"a run killed before its first flush ({FLUSH_S:g} s of wall time) left it with no rows"
        return f"{why}; rerun" if part == path else f"no such trace file; {part.name}: {why}; rerun"
    if part.is_file() and part != path:
        return f"no such trace file; {part.name} is what a run killed before it finished left: give that, or rerun"
    return "no such trace file"


class TraceFile:
    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        # A `<trace>.part` folder is what a run killed hard (SIGKILL, power loss) leaves: complete
        # row-group files up to its last flush, read here as one partial trace.
        self.partial = self.path.is_dir() and any(self.path.glob("*.parquet"))
        if not self.path.is_file() and not self.partial:
            raise TraceReadError(f"{path}: {_missing(self.path)}")
        head = _magic(self.path) if not self.partial else b""
        if head.startswith(b"MDF "):  # `hil trace --out x.mf4` writes it; asammdf or CANape read it
            raise TraceReadError(f"{path}: an MDF4 file: hil reads traces as CSV, Parquet or Arrow IPC "
                                 "(open MDF4 in asammdf or CANape)")
        # `hil trace --out x.feather/.arrow` exports Arrow IPC: read back as the Parquet path reads (bench B54)
        self.ipc = head.startswith(b"ARROW1")
        self.parquet = self.partial or self.ipc or is_parquet(self.path)
        self.kind = "Arrow IPC" if self.ipc else "Parquet" if self.parquet else "CSV"
        try:
            if self.ipc:
                import pyarrow.dataset as ds

                self._pf = _Parts(ds.dataset([str(self.path)], format="ipc"))
                self.columns = list(self._pf.schema_arrow.names)
                self.num_rows = self._pf.num_rows
            elif self.partial:
                import pyarrow.dataset as ds

                self._pf = _Parts(ds.dataset(sorted(str(p) for p in self.path.glob("*.parquet")), format="parquet"))
                self.columns = list(self._pf.schema_arrow.names)
                self.num_rows = self._pf.num_rows
            elif self.parquet:
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
        if self.parquet:
            _check_types(path, self._pf.schema_arrow)

    @property
    def meta(self) -> dict:
        """The run's provenance and end record (Parquet traces; {} for CSV)."""
        from hil.trace_parquet import read_meta

        if self.parquet:
            return read_meta(self._pf.schema_arrow)
        from hil.trace import csv_meta_path

        side = csv_meta_path(self.path)
        try:  # a CSV trace's provenance is its side file, if it still has one
            meta = json.loads(side.read_text()) if side.is_file() else {}
        except (OSError, ValueError):
            return {}
        return meta if isinstance(meta, dict) else {}

    def units(self) -> dict[str, str]:
        if not self.parquet:  # a CSV trace's units are in its side file, with the run's record (bench B81)
            units = self.meta.get("units")
            return {str(k): str(v) for k, v in units.items()} if isinstance(units, dict) else {}
        return {f.name: f.metadata[b"unit"].decode() for f in self._pf.schema_arrow
                if f.metadata and b"unit" in f.metadata}

    def _types_header(self) -> list[str]:
        return _header(self.path)

    def _convert(self, columns: Sequence[str] | None) -> pacsv.ConvertOptions:
        return pacsv.ConvertOptions(column_types=self._types, include_columns=list(columns) if columns else None,
                                    strings_can_be_null=True)  # "" in a CSV alarm column = null, as in Parquet

    def batches(self, columns: Sequence[str] | None = None, batch_rows: int = 65_536) -> Iterator[pa.RecordBatch]:
        try:
            if self.parquet:
                yield from self._pf.iter_batches(batch_size=batch_rows, columns=list(columns) if columns else None)
            else:
                reader = pacsv.open_csv(self.path, read_options=pacsv.ReadOptions(block_size=1 << 22),
                                        convert_options=self._convert(columns))
                yield from reader
        except (pa.ArrowInvalid, OSError) as exc:  # OSError: a corrupt page (decompression, checksum)
            raise TraceReadError(f"{self.path}: damaged trace ({exc})") from None

    def table(self, columns: Sequence[str] | None = None) -> pa.Table:
        try:
            if self.parquet:
                return self._pf.read(columns=list(columns) if columns else None)
            return pacsv.read_csv(self.path, convert_options=self._convert(columns))
        except (pa.ArrowInvalid, OSError) as exc:  # OSError: a corrupt page (decompression, checksum)
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
                out[name] = _numbers(col)
        return out


def _numbers(col: pa.ChunkedArray) -> np.ndarray:
    """col.to_numpy() without pyarrow's pandas probe (its first call imports pandas, ≈ 0.17 s of a `hil run` whose
    bench has checks: bench decision B48): a fixed-width column without nulls read off its buffers, a view of a
    single chunk (read-only, as to_numpy gives it) or the chunks joined; anything else through to_numpy."""
    typ = col.type
    if col.null_count == 0 and (pa.types.is_integer(typ) or pa.types.is_floating(typ)):
        dtype = np.dtype(typ.to_pandas_dtype())
        views = [np.frombuffer(ch.buffers()[1], dtype=dtype, count=len(ch), offset=ch.offset * dtype.itemsize)
                 for ch in col.chunks]
        if len(views) == 1:
            views[0].flags.writeable = False  # the table's own memory
            return views[0]
        return np.concatenate(views) if views else np.empty(0, dtype)
    return col.to_numpy()


def _magic(path: Path) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(8)
    except OSError:
        return b""  # the open below names the error


class _Parts:
    """The few ParquetFile calls TraceFile makes, over the row-group files of a partial trace (or an
    Arrow IPC export)."""

    def __init__(self, dataset) -> None:
        self._ds = dataset
        self.schema_arrow = dataset.schema
        self.num_rows = dataset.count_rows()

    def iter_batches(self, batch_size: int, columns: list[str] | None) -> Iterator[pa.RecordBatch]:
        yield from self._ds.to_batches(columns=columns, batch_size=batch_size)

    def read(self, columns: list[str] | None = None) -> pa.Table:
        return self._ds.to_table(columns=columns)


def write_table(tab: pa.Table, path: str | Path) -> None:
    """Export: Parquet or CSV by the file's extension."""
    if is_parquet(path):
        pq.write_table(tab, path, compression="zstd")
    else:
        pacsv.write_csv(tab, path, write_options=pacsv.WriteOptions(quoting_style="needed"))
