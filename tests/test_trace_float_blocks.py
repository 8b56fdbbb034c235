"""A Parquet trace part's float columns joined from the stretches' float64 blocks without lists (bench decision B85):
the same values `_column` makes of the joined list, and the list way wherever the blocks or rows are anything else."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest

from hil.trace_parquet import ParquetTrace, _by_column, _column, _float_blocks


def _listed(chunks: list, i: int) -> list:
    values: list = []
    for is_rows, ch in chunks:
        values.extend([r[i] for r in ch] if is_rows else (ch[i].tolist() if isinstance(ch[i], np.ndarray) else ch[i]))
    return values


def _chunks(row_values: list) -> list:
    """Rows (one column, column 0) between two float64 blocks, with -0.0, NaN and a subnormal among them."""
    return [(False, [np.array([0.1, -0.0, np.nan])]), (True, [(v,) for v in row_values]),
            (False, [np.array([5e-324, 1e300, 2.5])])]


@pytest.mark.parametrize("rows", [[0.25, 1 / 3], [7, 2**53 + 1, -(2**62)], [1.5, 3], [True, 2.0], []])
def test_float_blocks_hold_what_the_list_way_holds_bit_for_bit(rows):
    chunks = _chunks(rows)
    got = _float_blocks(_by_column(chunks, 1), 0)  # (the writer's rows transposed first, as _write_part does)
    want = _column(_listed(chunks, 0), pa.float64())
    assert got is not None and got.tobytes() == want.buffers()[1].to_pybytes()[:got.nbytes]
    assert len(got) == len(want) == 6 + len(rows)


@pytest.mark.parametrize("chunks", [
    _chunks([True, False]),  # bools alone: numpy's array of the rows is not numbers
    _chunks([None, 2.0]),  # a None: pa.array's null, the list way
    _chunks([2**70]),  # beyond 64 bits: numpy's object array, the list way
    [(True, [(1,), (2,)])],  # rows alone: the all-int column's ±2⁵³ check stays the list way's
    [(False, [[0.5, 1.5]]), (False, [np.array([2.5])])],  # a list block
    [(False, [np.array([1, 2])])],  # an int64 block
])
def test_anything_else_takes_the_list_way(chunks):
    assert _float_blocks(_by_column(chunks, 1), 0) is None


def test_a_trace_of_rows_and_float_blocks_reads_back_as_pyarrow_converts_it(tmp_path):
    path = tmp_path / "t.parquet"
    w = ParquetTrace(path, ["t", "X_cmd", "line"])
    w.write([0.0, 1.0, 0])  # the first row sets the column types (X_cmd float64)
    ks = np.arange(1, 200)
    w.write_columns([ks * 0.001, ks * 0.5, (ks // 10).tolist()], len(ks))
    w.write([0.2, 2**53 + 1, 20])  # an int among the float column's rows: the nearest double, as pyarrow's list way
    w.close({"reason": "completed"})
    import pyarrow.parquet as pq

    t = pq.read_table(path)
    want = pa.array([1.0, *(ks * 0.5).tolist(), float(2**53 + 1)], type=pa.float64())
    assert t.column("X_cmd").combine_chunks().equals(want)
    assert t.column("t").to_pylist() == [0.0, *(ks * 0.001).tolist(), 0.2]
