"""A Parquet trace is written by pyarrow's writer class itself, without importing pyarrow.parquet's module and its
file systems (bench decision B92): the file must be the one `pq.write_table(..., compression="zstd")` writes with the
trace's encodings (a dictionary for strings and statuswords, delta for int64, plain floats: B139), byte for byte,
with this pyarrow; a pyarrow whose writer is missing or takes other arguments writes through pq."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import hil.trace_parquet as tp

ROOT = Path(__file__).resolve().parents[1]


def _table() -> pa.Table:
    """A trace's column types: float64 (NaN, -0.0), int64, uint16 statuswords, strings with nulls; units in the field
    metadata and the run's provenance in the schema's."""
    n = 3000
    cols = {
        "t": pa.array([k * 0.001 for k in range(n)]),
        "line": pa.array([k // 7 for k in range(n)], pa.int64()),
        "alarm": pa.array([None if k % 11 else "0x0401" for k in range(n)], pa.string()),
        "X_cmd": pa.array([(-0.0 if k == 5 else float("nan") if k == 9 else k * 0.25) for k in range(n)]),
        "X_sw": pa.array([0x1637 if k % 3 else 0x0237 for k in range(n)], pa.uint16()),
    }
    fields = [pa.field(name, arr.type, metadata={"unit": "mm"} if name == "X_cmd" else None)
              for name, arr in cols.items()]
    return pa.Table.from_arrays(list(cols.values()), schema=pa.schema(fields, metadata={b"deltahil": b'{"a": 1}'}))


def _pq_bytes(table: pa.Table, tmp_path: Path) -> bytes:
    ref = tmp_path / "ref.parquet"
    names = table.column_names
    pq.write_table(table, ref, compression="zstd",
                   use_dictionary=[c for c in names if c in ("alarm", "X_sw")],
                   column_encoding={c: "DELTA_BINARY_PACKED" for c in names if c == "line"} or None)
    return ref.read_bytes()


def test_the_file_is_pq_write_tables_byte_for_byte(tmp_path):
    table = _table()
    assert tp._Writer is not None  # this pyarrow has it: the way a run takes
    out = tmp_path / "t.parquet"
    tp.write_table(table, out)
    assert out.read_bytes() == _pq_bytes(table, tmp_path)
    tp.write_table(table, str(out))
    assert out.read_bytes() == _pq_bytes(table, tmp_path)
    buf = pa.BufferOutputStream()
    tp.write_table(table, buf)
    assert buf.getvalue().to_pybytes() == _pq_bytes(table, tmp_path)
    back = pq.ParquetFile(out).read()
    assert back.drop_columns(["X_cmd"]).equals(table.drop_columns(["X_cmd"]))  # (X_cmd holds a NaN: not equal)
    assert back.column("X_cmd").to_pylist()[:5] == [0.0, 0.25, 0.5, 0.75, 1.0] and back.num_rows == 3000
    assert back.schema.metadata[b"deltahil"] == b'{"a": 1}' and back.schema.field("X_cmd").metadata == {b"unit": b"mm"}


class _OtherSignature:
    def __init__(self, *args, **kwargs):
        raise TypeError("__cinit__() got an unexpected keyword argument 'writer_engine_version'")


@pytest.mark.parametrize("writer", [None, _OtherSignature], ids=["no private writer", "another signature"])
def test_another_pyarrow_writes_through_pq(tmp_path, monkeypatch, writer):
    monkeypatch.setattr(tp, "_Writer", writer)
    out = tmp_path / "t.parquet"
    tp.write_table(_table(), out)
    assert out.read_bytes() == _pq_bytes(_table(), tmp_path)


def test_a_failed_write_leaves_no_file(tmp_path):
    """As pq.write_table: a table Parquet cannot hold (a union column) raises and leaves nothing behind."""
    union = pa.UnionArray.from_sparse(pa.array([0, 1], pa.int8()), [pa.array([1, 2]), pa.array(["a", "b"])])
    table = pa.table({"u": union})
    out = tmp_path / "u.parquet"
    with pytest.raises(pa.ArrowException):
        tp.write_table(table, out)
    assert not out.exists()


def test_a_run_does_not_import_pyarrow_parquet_and_its_trace_reads_back(tmp_path):
    trace = tmp_path / "t.parquet"
    # (FLUSH_S raised: a run slower than 2 s of wall time, on a loaded machine, writes its trace in parts and joins
    # them, a second row group; the one-group check is about the run's rows, not the machine's speed)
    code = ("import sys; import hil.trace_parquet as tp; tp.FLUSH_S = 1e9; from hil.cli import main; "
            f"rc = main(['run', 'examples/lathe_demo.nc', '--trace', {str(trace)!r}]); "
            "print('RC', rc, *(m in sys.modules for m in ('pyarrow.parquet', 'pyarrow.fs', 'ssl')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-4:] == ["0", "False", "False", "False"]
    f = pq.ParquetFile(trace)
    assert f.metadata.num_rows == 14396 and f.metadata.num_row_groups == 1
    assert f.schema_arrow.field("X_sw").type == pa.uint16() and b"deltahil" in f.schema_arrow.metadata


def test_a_part_without_alarms_has_the_all_null_column_the_list_way_made(tmp_path):
    """A part whose alarm column is all "" (no alarm: null) is made at once; it is the column pa.array makes of
    the nulls, and the file the same bytes as pq's of that column."""
    n = 1000
    fast = tp._column([""] * (n - 1) + [None], pa.string())
    want = pa.array([None] * n, pa.string())
    assert fast.equals(want) and fast.null_count == n and fast.type == pa.string()
    mixed = tp._column([""] * (n - 1) + ["0x0401"], pa.string())  # the general way, one alarm
    assert mixed.null_count == n - 1 and mixed[n - 1].as_py() == "0x0401"
    out = tmp_path / "a.parquet"
    tp.write_table(pa.table({"alarm": fast}), out)
    assert out.read_bytes() == _pq_bytes(pa.table({"alarm": want}), tmp_path)
    assert tp._column([], pa.string()).equals(pa.array([], pa.string()))


def test_rows_are_read_by_column_as_before(tmp_path):
    """The writer transposes a chunk of rows once (B92): a row with an extra value has it left out, a short row
    is the trace's failure at close, as when each column was read row by row."""
    w = tp.ParquetTrace(tmp_path / "x.parquet", ["t", "line"])
    w.write([0.0, 1, "extra"])
    w.write([0.001, 2])
    w.close()
    t = pq.ParquetFile(tmp_path / "x.parquet").read()
    assert t.column_names == ["t", "line"] and t.column("line").to_pylist() == [1, 2]
    w = tp.ParquetTrace(tmp_path / "short.parquet", ["t", "line"])
    w.write([0.0, 1])
    w.write([0.001])
    with pytest.raises(IndexError):
        w.close()
    assert not (tmp_path / "short.parquet").exists()


def test_a_long_chunk_of_rows_is_transposed_a_slice_at_a_time():
    """A real-time run's part can hold thousands of rows: one zip holds the GIL for its whole slice, so slices stay TRANSPOSE rows
    (the cycle thread takes the GIL back within the writer's switch interval); a short row deep in it still fails."""
    rows = [(k * 0.001, k) for k in range(600)]
    sliced = tp._by_column([(True, rows)], 2)
    assert [len(cols[0]) for _, cols in sliced] == [tp.TRANSPOSE, tp.TRANSPOSE, 600 - 2 * tp.TRANSPOSE]
    assert [v for _, cols in sliced for v in cols[1]] == list(range(600))
    with pytest.raises(IndexError):
        tp._by_column([(True, rows[:500] + [(0.5,)] + rows[500:])], 2)
