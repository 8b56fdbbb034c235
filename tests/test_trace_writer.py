"""A Parquet trace's row groups are converted and written by a writer thread (issue 17): the cycle that fills
a row group only hands it over, so the ≈ 6 ms of a flush does not land in a real-time period's slack. The
file stays whole and the same; a failure of the writer reaches the run's thread at close."""

from __future__ import annotations

import threading

import pyarrow.parquet as pq
import pytest

import hil.trace_parquet as tp
from hil.trace_parquet import ParquetTrace


def test_a_full_row_group_is_written_while_the_run_goes_on(tmp_path, monkeypatch):
    release = threading.Event()
    writing = threading.Event()
    real_write = tp.write_table
    callers: list[str] = []

    def held_write(*a, **k):  # the writer stays inside its first part until the test lets it go
        callers.append(threading.current_thread().name)
        writing.set()
        assert release.wait(10)
        return real_write(*a, **k)

    w = ParquetTrace(tmp_path / "w.parquet", ["t", "line", "alarm", "X_sw"], row_group=100)
    monkeypatch.setattr(tp, "write_table", held_write)
    for k in range(250):  # two row groups handed over, the writer still holding the first
        w.write([k * 0.001, k // 10, "" if k % 7 else "0x1001", k])
    assert writing.wait(10)
    assert not list(w.parts.glob("*.parquet"))  # nothing written yet, and write() returned all the same
    release.set()
    w.close({"reason": "completed"})
    assert callers and threading.main_thread().name not in callers
    t = pq.read_table(tmp_path / "w.parquet")
    assert pq.ParquetFile(tmp_path / "w.parquet").metadata.num_row_groups == 3
    assert t.column("t").to_pylist() == [k * 0.001 for k in range(250)]
    assert t.column("alarm").to_pylist() == [None if k % 7 else "0x1001" for k in range(250)]
    assert t.column("X_sw").to_pylist() == list(range(250)) and str(t.schema.field("X_sw").type) == "uint16"
    assert not w.parts.exists()


def test_a_writer_failure_reaches_the_run_at_close(tmp_path, monkeypatch):
    def full_disk(*a, **k):
        raise OSError(28, "No space left on device")

    w = ParquetTrace(tmp_path / "f.parquet", ["t", "x"], row_group=10)
    monkeypatch.setattr(tp, "write_table", full_disk)
    with pytest.raises(OSError, match="No space left"):  # at the next hand-over or at close, as it comes
        for k in range(25):
            w.write([k * 0.001, float(k)])
        w.close()
    assert not (tmp_path / "f.parquet").exists()


def test_the_switch_interval_is_put_back_after_the_writer(tmp_path):
    import sys

    before = sys.getswitchinterval()
    w = ParquetTrace(tmp_path / "s.parquet", ["t"], row_group=5)
    for k in range(12):
        w.write([k * 0.001])
    w.close()
    assert sys.getswitchinterval() == before
    assert pq.read_table(tmp_path / "s.parquet").num_rows == 12


def _rows(n: int) -> list[tuple]:
    return [(k * 0.001, k // 10, "" if k % 7 else "0x1001", 0x1637 + k % 3, k * 0.5) for k in range(n)]


@pytest.mark.parametrize("flush_s, row_group", [(1e9, 1000), (0.0, 50_000), (0.0, 1500)])
def test_rows_handed_over_as_columns_make_the_file_rows_make(tmp_path, monkeypatch, flush_s, row_group):
    """write_columns (a stretch's cycles, issue 17) between write() rows: the same table, and the same parts
    (cut where write() flushes: a full row group, or each 1,024th row once FLUSH_S passed: 0 s here)."""
    import numpy as np

    monkeypatch.setattr(tp, "FLUSH_S", flush_s)
    cols = ["t", "line", "alarm", "X_sw", "X_cmd"]
    rows = _rows(5000)
    one = ParquetTrace(tmp_path / "rows.parquet", cols, row_group=row_group)
    for r in rows:
        one.write(r)
    one.close({"reason": "completed"})
    two = ParquetTrace(tmp_path / "cols.parquet", cols, row_group=row_group)
    k, sizes = 0, [3, 700, 1, 2000, 17, 64, 1300]
    while k < len(rows):
        n = sizes[k % len(sizes)]
        block = rows[k:k + n]
        if k % 2:
            for r in block:
                two.write(r)
        else:
            c = [list(x) for x in zip(*block)]
            c[4] = np.array(c[4])  # floats as an array, as hil/stretch_bulk.py hands them
            two.write_columns(c, len(block))
        k += len(block)
    two.close({"reason": "completed"})
    a, b = pq.read_table(tmp_path / "rows.parquet"), pq.read_table(tmp_path / "cols.parquet")
    assert a.equals(b) and a.num_rows == 5000
    ma, mb = (pq.ParquetFile(tmp_path / f).metadata for f in ("rows.parquet", "cols.parquet"))
    assert [ma.row_group(i).num_rows for i in range(ma.num_row_groups)] == \
        [mb.row_group(i).num_rows for i in range(mb.num_row_groups)]
    assert [ma.row_group(i).num_rows for i in range(ma.num_row_groups)] == \
        ([1000] * 5 if row_group == 1000 else [1024] * 4 + [904])


def test_a_run_in_one_part_is_written_as_the_trace_with_its_end_record(tmp_path):
    """No part joined at the end when the whole run is one part: the file holds the rows and the end record."""
    w = ParquetTrace(tmp_path / "one.parquet", ["t", "line", "alarm", "X_sw", "X_cmd"])
    for r in _rows(300):
        w.write(r)
    w.close({"reason": "completed", "cycle": 300})
    f = pq.ParquetFile(tmp_path / "one.parquet")
    assert f.metadata.num_rows == 300 and f.metadata.num_row_groups == 1
    assert tp.read_meta(f.schema_arrow)["end"] == {"reason": "completed", "cycle": 300}
    assert f.schema_arrow.field("X_sw").type == "uint16" and not w.parts.exists()
