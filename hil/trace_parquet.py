"""Parquet traces through pyarrow, safe against a hard kill.

While the run goes, rows are buffered and each row group is written as a complete Parquet file of
its own in `<trace>.part/` (written aside and renamed, so every file there is whole). A run killed
with SIGKILL or a power loss leaves that folder: a Parquet dataset that pyarrow, pandas, polars,
duckdb and `hil trace` read up to the last flush. At the end the parts are joined into the trace
file (one row group each), its end-of-run record is stored in the metadata, and the folder goes.

A row group is converted and written by a writer thread, not in the cycle that filled it (≈ 6 ms of CPU per
2 s of a real-time run, which made the next tick late: issue 17). pyarrow releases the GIL while it encodes
and writes; the conversion of the rows holds it, in short calls, and the switch interval is lowered while a
writer works so the cycle thread waking for its deadline takes the GIL back within ≈ 0.2 ms.

Types read the same in every tool: "no alarm" is null (not ""), statuswords are uint16, cycle and
line int64, quantities float64. Every column carries its unit in its field metadata (`unit`), and
the schema metadata `deltahil` holds the run's provenance (hil/trace_meta.py).
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import sys
import threading
import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pyarrow as pa

from hil.trace import INT_COLUMNS

try:  # pyarrow's Parquet writer itself: pyarrow.parquet's module imports pyarrow.fs (ssl, S3, GCS...) with it (B92)
    from pyarrow._parquet import ParquetWriter as _Writer
except ImportError:  # a pyarrow without it: pyarrow.parquet's public writer
    _Writer = None
try:  # and its reader, for the parts joined at the end of a run (B139)
    from pyarrow._parquet import ParquetReader as _Reader
except ImportError:
    _Reader = None

ROW_GROUP = 50_000  # rows per row group: ~50 s at 1 ms, a few MB in memory
FLUSH_S = 2.0  # …or sooner, once this much wall time has passed (real-time runs lose at most this)
META_KEY = b"deltahil"
SWITCH_S = 0.0002  # the GIL switch interval while a writer converts (CPython's default 5 ms: a whole period)
TRANSPOSE = 256  # rows transposed by one zip (_by_column: ≈ 30 µs for a trace's 23 columns, within SWITCH_S)
# what pq.write_table(table, where, compression="zstd") gives pyarrow's writer (pyarrow.parquet.core.ParquetWriter's
# defaults), so the file is the one pq writes with these options (tests/test_trace_parquet_writer.py compares the
# bytes); which columns are dictionary-encoded and which delta-encoded is writer_options' (B139)
_OPTIONS = dict(version="2.6", use_dictionary=True, compression="zstd", write_statistics=True,
                writer_engine_version="V2", data_page_version="1.0", use_compliant_nested_type=True, store_schema=True)
_DICTIONARY_TYPES = (pa.string(), pa.uint16())  # alarm codes, statuswords: a handful of values, repeated


def writer_options(schema: pa.Schema) -> dict[str, Any]:
    """The writer's options for a trace of this schema, column by column (bench decision B139): a dictionary only
    for the columns of a few repeated values (alarm codes, statuswords); the int64 columns (cycle, line, the MLC's
    bits and words) delta-encoded (cycle counts up by one, line by small steps); the float64 quantities plain, as
    zstd takes them. pyarrow's default, a dictionary for every column, hashed each of a CAM trace's ≈ 6,000 distinct
    positions per column and made the file larger: 52 M instructions to write the CAM run's trace, 29 M this way
    (benchmarks/trace_ab.py --writer). Every encoding here is in Parquet's format 2.6 and read by pyarrow, pandas,
    polars and duckdb; the values read back are the same, bit for bit."""
    delta = {f.name: "DELTA_BINARY_PACKED" for f in schema if f.type == pa.int64()}
    return dict(_OPTIONS, use_dictionary=[f.name for f in schema if f.type in _DICTIONARY_TYPES],
                column_encoding=delta or None)


def _type_of(name: str, value: float | int | str | None) -> pa.DataType:
    if name.endswith("_sw"):
        return pa.uint16()  # CiA 402 statusword 0x6041 is UNSIGNED16
    if name in INT_COLUMNS:
        return pa.int64()
    if isinstance(value, str) or value is None:
        return pa.string()
    if isinstance(value, (bool, int)):
        return pa.int64()
    return pa.float64()


_NUMPY = {pa.float64(): ("fiu", np.float64), pa.int64(): ("iu", np.int64), pa.uint16(): ("iu", np.uint16)}


def _column(values: list, typ: pa.DataType) -> pa.Array:
    """One trace column as an Arrow array, built from numpy buffers (bench decision B48): `pa.array` imports pandas
    on its first call, to ask whether the values are a pandas array (≈ 0.17 s of every `hil run --trace`, issue 17),
    and costs ≈ 5 µs a call. The array holds what `pa.array(values, type=typ)` holds, so the file is the same;
    values it does not take this way (a None among numbers, a float in an integer column, a statusword out of
    range, not a str in a string column) go to `pa.array`, which converts or refuses them as before (one
    difference: a bool in an integer column is stored as 0/1, where pa.array refused it)."""
    n = len(values)
    try:
        if typ == pa.string():
            if n and not any(values):  # no alarm in the whole part (the common case): the same buffers, made at once
                return pa.Array.from_buffers(typ, n, [pa.py_buffer(np.zeros((n + 7) // 8, np.uint8)),
                                                      pa.py_buffer(np.zeros(n + 1, np.int32)), pa.py_buffer(b"")], n)
            data = [v.encode() if v else b"" for v in values]  # "" and None: null, as every reader means it
            valid = np.fromiter(map(bool, data), bool, n)
            offsets = np.zeros(n + 1, np.int32)
            np.cumsum(np.fromiter(map(len, data), np.int32, n), out=offsets[1:])
            nulls = n - int(np.count_nonzero(valid))
            bitmap = pa.py_buffer(np.packbits(valid, bitorder="little")) if nulls else None
            return pa.Array.from_buffers(typ, n, [bitmap, pa.py_buffer(offsets), pa.py_buffer(b"".join(data))], nulls)
        kinds, dtype = _NUMPY[typ]
        arr = np.array(values)
        if n and arr.dtype.kind not in kinds:
            raise TypeError(f"{arr.dtype} for {typ}")
        if n and arr.dtype.kind in "iu" and dtype is not np.int64:  # pyarrow's range checks
            low, high = (0, 0xFFFF) if dtype is np.uint16 else (-(2**53), 2**53)  # 16 bits; an int exact as a float
            if arr.min() < low or arr.max() > high:
                raise OverflowError(f"{typ} out of range")
        return pa.Array.from_buffers(typ, n, [None, pa.py_buffer(np.ascontiguousarray(arr, dtype=dtype))], 0)
    except (TypeError, ValueError, AttributeError, OverflowError, KeyError):
        return pa.array([v or None for v in values] if typ == pa.string() else values, type=typ)


def _float_blocks(chunks: list, i: int) -> np.ndarray | None:
    """Column i of a part as one float64 array when the part has column blocks and each holds the column as a
    float64 array (a stretch's setpoints and feedback: 13 of the lathe demo's 23 columns, 14,148 of its 14,396 rows)
    and the stepped rows' values are numbers: the blocks are joined as they are, not through lists (B85). The
    values are those `_column` makes of the joined list: a block's floats unchanged, the rows' ints converted to the
    nearest double as numpy's array of the list converts them. None (the list way) for anything else: a list
    block, a bool, a None, an int beyond 64 bits, a part of rows alone (an all-int column's ±2⁵³ check)."""
    pieces: list[np.ndarray | int] = []  # a block's array, or how many rows come next
    rows: list = []
    for is_rows, ch in chunks:
        if is_rows:  # (rows transposed: a tuple per column, _by_column)
            rows.extend(ch[i])
            pieces.append(len(ch[i]))
        else:
            col = ch[i]
            if type(col) is not np.ndarray or col.dtype != np.float64:
                return None
            pieces.append(col)
    if len(pieces) == len([p for p in pieces if type(p) is int]):
        return None
    values = np.array(rows) if rows else np.empty(0)
    if values.dtype.kind not in "fiu":
        return None
    values, at = values.astype(np.float64, copy=False), 0
    for k, p in enumerate(pieces):
        if type(p) is int:
            pieces[k], at = values[at:at + p], at + p
    return np.concatenate(pieces)


def _by_column(chunks: list, width: int) -> list:
    """The chunks with each chunk of rows transposed, once, into a tuple per column, TRANSPOSE rows at a time (a
    chunk of rows is mostly one stepped cycle's row between two stretches: 223 of the lathe demo's 478 chunks), so
    that a column is read from every chunk alike (≈ 1.5 ms of the lathe demo's part, B92). In slices: one zip holds
    the GIL for its whole slice, and a real-time run's cycle thread must get it back within the switch interval
    (`SWITCH_S`; a real-time part can hold thousands of rows). A row shorter than the schema is refused, as reading its columns one
    by one refused it (an IndexError: the run's trace failure); a longer one's extra values are left out, as they
    were."""
    out = []
    for is_rows, ch in chunks:
        if not is_rows:
            out.append((False, ch))
            continue
        for k in range(0, len(ch), TRANSPOSE):
            cols = list(zip(*ch[k:k + TRANSPOSE]))  # as long as the shortest row
            if len(cols) < width:
                raise IndexError(f"a trace row of {len(cols)} values for {width} columns")
            out.append((True, cols))
    return out


def write_table(table: pa.Table, where: str | Path | pa.NativeFile) -> None:
    """`pq.write_table(table, where, compression="zstd")`: the same file, through pyarrow's writer class itself
    (`pyarrow._parquet.ParquetWriter`, what pq's writer wraps), so that a run does not import pyarrow.parquet's
    module: it imports pyarrow.fs, and with it ssl and the S3/GCS/Azure/HDFS file systems, ≈ 10 ms of CPU in every
    `hil run --trace` (issue 17, bench decision B92). A pyarrow whose writer is missing or takes other arguments
    writes through pq.write_table; as pq does, a file left by a failed write is removed. The options are
    writer_options' (B139): the file is the one pq.write_table writes with them."""
    if _Writer is not None:
        sink = str(where) if isinstance(where, (str, Path)) else where
        try:
            writer = _Writer(sink, table.schema, **writer_options(table.schema))
        except TypeError:  # another pyarrow's signature (its arguments are bound before a file is opened)
            writer = None
        except Exception:
            _remove(sink)
            raise
        if writer is not None:
            try:
                try:
                    writer.write_table(table, row_group_size=None)
                finally:
                    writer.close()
            except Exception:
                _remove(sink)
                raise
            return
    import pyarrow.parquet as pq

    pq.write_table(table, where, **writer_options(table.schema))


def _open_writer(path: Path, schema: pa.Schema) -> Any:
    """The writer of a run's parts joined into its trace: the parts' options (writer_options), through pyarrow's
    writer class itself as write_table (pq's module imported only for a pyarrow without it)."""
    if _Writer is not None:
        try:
            return _Writer(str(path), schema, **writer_options(schema))
        except TypeError:  # another pyarrow's signature
            pass
    import pyarrow.parquet as pq

    return pq.ParquetWriter(path, schema, **writer_options(schema))


def _read_part(path: Path) -> pa.Table:
    """A part as `pq.ParquetFile(path).read()` reads it (not pq.read_table: the dataset reader imports pandas, B48),
    through pyarrow's reader class itself: pq's module would import pyarrow.fs, ≈ 10 ms of CPU at the end of every
    run of more than one part (B92, B139)."""
    if _Reader is not None:
        try:
            reader = _Reader()
            reader.open(str(path))
            return reader.read_all()
        except TypeError:  # another pyarrow's signature
            pass
    import pyarrow.parquet as pq

    return pq.ParquetFile(path).read()


def _remove(sink: str | pa.NativeFile) -> None:
    if isinstance(sink, str):
        Path(sink).unlink(missing_ok=True)


def _warm_up() -> None:
    """pyarrow's first Parquet file (its zstd codec, the writer's set-up) costs lazy set-up; at the first row
    group's flush, inside the bus cycle, that stalled an EtherCAT line past its SM watchdog (AL 0x001B) two seconds
    into every run (then 0.3–0.5 s: pa.array's pandas import, B48); so it is done here, before cycling."""
    tab = pa.Table.from_arrays([_column([0.0], pa.float64()), _column([0], pa.int64()), _column([0], pa.uint16()),
                                _column([""], pa.string())], names=["f", "i", "u", "s"])
    write_table(tab, pa.BufferOutputStream())


class ParquetTrace:
    def __init__(self, path: str | Path, columns: list[str], row_group: int = ROW_GROUP,
                 meta: dict[str, Any] | None = None, units: dict[str, str] | None = None) -> None:
        self.path = Path(path)
        self.columns = columns
        self.row_group = row_group
        self.meta = dict(meta or {})
        self.units = units or {}
        self.parts = self.path.with_name(self.path.name + ".part")
        if self.parts.is_file():  # an old single-file partial trace
            self.parts.unlink()
        shutil.rmtree(self.parts, ignore_errors=True)  # a killed earlier run's parts
        self.parts.mkdir()  # fail now, not at the first flush, if the place is not writable
        self._rows: list[Sequence[float | int | str]] = []
        # what is buffered ahead of _rows, in order: (True, rows) of write(), (False, columns) of write_columns()
        self._chunks: list[tuple[bool, list]] = []
        self._pending = 0  # the rows in _chunks
        self._schema: pa.Schema | None = None
        self._n_parts = 0
        self._last_flush = time.monotonic()
        self._closed = False
        self._jobs: queue.Queue[tuple[list, Path] | None] = queue.Queue()
        self._error: BaseException | None = None  # the writer's failure, raised in the run's thread
        self._owner = threading.get_native_id()  # the run's thread, whose scheduling the writer takes
        _warm_up()
        # Started now, not at the first flush: once a real-time run holds its memory locked (mlockall, hil/clock.py),
        # a new thread's stack is faulted in by the thread that starts it, ≈ 4 ms in a cycle's slack
        self._writer: threading.Thread | None = threading.Thread(target=self._write_parts, name="parquet-trace",
                                                                 daemon=True)
        self._writer.start()

    def write(self, row: Sequence[float | int | str]) -> None:
        self._rows.append(tuple(row))
        n = len(self._rows) + self._pending
        if n >= self.row_group or (n & 1023 == 0 and time.monotonic() - self._last_flush >= FLUSH_S):
            self._flush()

    def write_columns(self, cols: Sequence[Sequence[Any]], n: int) -> None:
        """n rows handed over as columns (a stretch's cycles, hil/stretch_bulk.py): lists or float64 arrays, one
        per trace column, each n long. Kept as columns, not turned into rows (issue 17: ≈ 3 µs a cycle of the
        lathe demo went into the row tuples); the parts hold the same rows: the block is cut at the row
        counts where write() would flush (a full row group, or each 1,024th row once FLUSH_S passed)."""
        k = 0
        while k < n:
            have = self._pending + len(self._rows)
            # the next row count write() checks at: a multiple of 1,024, or the full row group
            stop = min(n, k + self.row_group - have, k + 1024 - (have & 1023))
            part = list(cols) if k == 0 and stop == n else [c[k:stop] for c in cols]
            self._block_rows()
            self._chunks.append((False, part))
            self._pending += stop - k
            k = stop
            have = self._pending
            if have >= self.row_group or (have & 1023 == 0 and time.monotonic() - self._last_flush >= FLUSH_S):
                self._flush()

    def _block_rows(self) -> None:
        """The rows write() buffered go ahead of a column block, as a chunk of their own."""
        if self._rows:
            self._pending += len(self._rows)
            self._chunks.append((True, self._rows))
            self._rows = []

    def _make_schema(self, first: Sequence[Any]) -> pa.Schema:
        fields = []
        for c, v in zip(self.columns, first):
            unit = self.units.get(c)
            fields.append(pa.field(c, _type_of(c, v), metadata={"unit": unit} if unit else None))
        return pa.schema(fields, metadata=self._metadata())

    def _metadata(self) -> dict[bytes, bytes]:
        return {META_KEY: json.dumps(self.meta, allow_nan=False, default=str).encode()}

    def _flush(self) -> None:
        """Hand the buffered rows to the writer thread as the next part (started at the first flush)."""
        self._last_flush = time.monotonic()
        if self._error is not None:
            self._raise()
        self._block_rows()
        if not self._chunks:
            return
        if self._schema is None:
            is_rows, first = self._chunks[0]
            self._schema = self._make_schema(first[0] if is_rows else [c[0] for c in first])
        self._jobs.put((self._chunks, self.parts / f"{self._n_parts:06d}.parquet"))
        self._n_parts += 1
        self._chunks, self._pending = [], 0

    def _write_parts(self) -> None:
        """The writer thread: each part in turn, until close() or discard() hands it None."""
        while (job := self._jobs.get()) is not None:
            if self._error is None:  # after a failure the rest is dropped: the run's thread raises it
                try:
                    _sched_like(self._owner)
                    with _short_switches():
                        self._write_part(*job)
                except BaseException as e:  # noqa: BLE001 - handed to the run's thread
                    self._error = e

    def _write_part(self, chunks: list, part: Path) -> None:
        """One part from its chunks: row lists (write) and column blocks (write_columns)."""
        assert self._schema is not None
        chunks = _by_column(chunks, len(self._schema))
        arrays = []
        for i, f in enumerate(self._schema):  # column by column: short GIL holds
            floats = _float_blocks(chunks, i) if f.type == pa.float64() else None
            if floats is not None:
                arrays.append(pa.Array.from_buffers(f.type, len(floats), [None, pa.py_buffer(floats)], 0))
                continue
            values: list = []  # the chunks' pieces joined first: one conversion a column, not one a chunk (B48)
            for _, ch in chunks:
                values.extend(ch[i].tolist() if isinstance(ch[i], np.ndarray) else ch[i])
            arrays.append(_column(values, f.type))
        tmp = self.parts / f".{part.name}.tmp"
        write_table(pa.Table.from_arrays(arrays, schema=self._schema), tmp)
        os.replace(tmp, part)

    def _drain(self) -> None:
        """Wait for the writer to finish every part handed to it; its failure is raised here."""
        if self._writer is not None:
            self._jobs.put(None)
            self._writer.join()
            self._writer = None
        if self._error is not None:
            self._raise()

    def _raise(self) -> None:
        err, self._error = self._error, None
        assert err is not None
        raise err

    def close(self, end: dict[str, Any] | None = None) -> None:
        """Join the parts into the trace, with the end-of-run record (reason, alarm, cycle)."""
        if self._closed:
            return
        self._closed = True
        if end is not None:
            self.meta["end"] = end
        self._block_rows()
        if self._n_parts == 0 and self._chunks:
            # the whole run in one part (a run shorter than FLUSH_S of wall time and ROW_GROUP rows): the writer
            # writes it as the trace itself, with the end record, instead of a part read back and written again
            is_rows, first = self._chunks[0]
            self._schema = self._make_schema(first[0] if is_rows else [c[0] for c in first])
            self._jobs.put((self._chunks, self.path))
            self._chunks, self._pending = [], 0
            self._drain()
            shutil.rmtree(self.parts, ignore_errors=True)
            return
        self._flush()
        self._drain()
        if self._schema is None:  # no rows at all: still a valid file with the columns
            self._schema = pa.schema([(c, pa.float64()) for c in self.columns])
        schema = self._schema.with_metadata(self._metadata())
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        try:
            writer = _open_writer(tmp, schema)  # (a run of more than one part: longer than FLUSH_S or ROW_GROUP rows)
            try:
                for part in sorted(self.parts.glob("*.parquet")):
                    writer.write_table(_read_part(part).replace_schema_metadata(schema.metadata), row_group_size=None)
            finally:
                writer.close()
            os.replace(tmp, self.path)
        finally:
            tmp.unlink(missing_ok=True)
        shutil.rmtree(self.parts, ignore_errors=True)

    def discard(self) -> None:
        """A run refused after its trace was opened leaves nothing."""
        self._closed = True
        self._rows, self._chunks = [], []
        try:
            self._drain()
        except Exception:  # noqa: BLE001 - nothing is kept of a refused run, its trace's failure included
            pass
        shutil.rmtree(self.parts, ignore_errors=True)


def _sched_like(tid: int) -> None:
    """The writer takes the run's thread's scheduling (SCHED_FIFO in a real-time run, granted after the trace
    opened): a writer preempted by the machine's other work while it holds the GIL would hold the cycle up."""
    try:
        policy, param = os.sched_getscheduler(tid), os.sched_getparam(tid)
        if (policy, param) != (os.sched_getscheduler(0), os.sched_getparam(0)):
            os.sched_setscheduler(0, policy, param)
    except (OSError, AttributeError):  # the run's thread gone, or no such call here: as it is
        pass


_switch_lock = threading.Lock()
_switch_users = 0
_switch_saved = 0.005


class _short_switches:
    """sys.setswitchinterval(SWITCH_S) while any writer converts rows, the interval as it was after."""

    def __enter__(self) -> None:
        global _switch_users, _switch_saved
        with _switch_lock:
            if _switch_users == 0:
                _switch_saved = sys.getswitchinterval()
                sys.setswitchinterval(min(_switch_saved, SWITCH_S))
            _switch_users += 1

    def __exit__(self, *exc: object) -> None:
        global _switch_users
        with _switch_lock:
            _switch_users -= 1
            if _switch_users == 0:
                sys.setswitchinterval(_switch_saved)


def read_meta(schema: pa.Schema) -> dict[str, Any]:
    """The `deltahil` run metadata of a trace's schema ({} for a trace without it)."""
    raw = (schema.metadata or {}).get(META_KEY)
    if not raw:
        return {}
    try:
        return json.loads(raw)
    except ValueError:
        return {}
