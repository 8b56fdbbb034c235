"""A Parquet trace's encodings, column by column (bench decision B139): a dictionary only where few values repeat
(alarm codes, statuswords), delta for the int64 columns (cycle, line), the float64 quantities plain; the values are
the run's bit for bit, in a one-part trace and in one joined from its parts, and a trace written before B139 (a
dictionary for every column) still reads and summarises the same."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import hil
import hil.trace_parquet as tp
from hil.trace import trace_columns
from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
TURN = ROOT / "tests" / "data" / "campaign" / "short_turn.nc"
WALL = ("period", "late")  # the cycle's wall-clock timing: not the same from one run to the next


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> tuple[Path, Path]:
    """The same lock-step run (an E-stop at 0.3 s: alarm 0x0401 in the alarm column) traced as Parquet and CSV."""
    d = tmp_path_factory.mktemp("enc")
    out = []
    for name in ("run.parquet", "run.csv"):
        r = hil.run(TURN, bench=LATHE, trace=d / name, events=["t=0.3:estop"], check=False)
        assert r.alarms and r.alarms[0].code == 0x0401
        out.append(d / name)
    return out[0], out[1]


def _encodings(path: Path) -> list[dict[str, tuple[str, ...]]]:
    """Each row group's encodings by column, as pq's metadata names them."""
    md = pq.ParquetFile(path).metadata
    return [{md.row_group(g).column(i).path_in_schema: md.row_group(g).column(i).encodings
             for i in range(md.num_columns)} for g in range(md.num_row_groups)]


def _assert_chosen(path: Path) -> None:
    ints = {f.name for f in pq.read_schema(path) if f.type == pa.int64()}  # cycle, line, the MLC's bits and words
    assert {"cycle", "line"} <= ints
    for group in _encodings(path):
        for col, enc in group.items():
            if col in ("alarm", "event") or col.endswith("_sw"):  # alarm codes, `--at` actions, statuswords
                assert "RLE_DICTIONARY" in enc, (col, enc)
            elif col in ints:
                assert "DELTA_BINARY_PACKED" in enc and "RLE_DICTIONARY" not in enc, (col, enc)
            else:  # t, period, late, positions, speeds, torques, following errors
                assert "PLAIN" in enc and "RLE_DICTIONARY" not in enc, (col, enc)


def _bits(values: list) -> list:
    """Floats as their IEEE bits (NaN and -0.0 compared exactly), the rest as it is."""
    return [np.float64(v).view(np.int64).item() if isinstance(v, float) else v for v in values]


def test_a_runs_parquet_trace_holds_the_values_of_its_csv_trace_bit_for_bit(runs):
    """CSV writes each float's repr (the shortest text of that very double): the Parquet trace of the same lock-step
    run holds the same numbers, bit for bit, the alarm as null where there is none; pandas reads them alike."""
    parquet, csv = runs
    _assert_chosen(parquet)
    got, want = TraceFile(parquet).table(), TraceFile(csv).table()
    assert got.num_rows == want.num_rows > 300 and got.column_names == want.column_names
    for name in got.column_names:
        if name in WALL:
            continue
        g, w = got.column(name).to_pylist(), want.column(name).to_pylist()
        if name == "alarm":
            assert g.count("0x0401") > 0 and g.count(None) > 0
            w = [v or None for v in w]
        assert _bits(g) == _bits(w), name
    df = pd_frame(parquet)
    assert df["cycle"].tolist() == got.column("cycle").to_pylist()
    assert _bits(df["X_act"].tolist()) == _bits(got.column("X_act").to_pylist())
    assert df["X_sw"].dtype == np.uint16 and df["alarm"].isna().sum() == got.column("alarm").null_count


def pd_frame(path: Path):
    pd = pytest.importorskip("pandas")
    return pd.read_parquet(path)


def test_a_trace_joined_from_its_parts_has_the_same_encodings_and_values(tmp_path):
    """A run longer than a row group (or FLUSH_S of wall time) writes parts and joins them at its end: each row
    group of the trace has the encodings of a one-part trace, and the rows written, bit for bit."""
    cols = trace_columns(["X"], []) + ["M21013"]
    rows = []
    for k in range(2500):
        alarm = "0x0401" if 1800 <= k < 1900 else ""
        sw = 0x1637 if k % 400 else 0x0237
        x = math.sin(k / 300) * 25.0 + (-0.0 if k == 7 else 0.0)
        rows.append((k * 0.001, 10 + k // 13, k, 0.001, 0.0, alarm, x, x - 1e-4 * math.cos(k / 9), 12.5 * k % 7,
                     0.25 * (k % 5), 1e-4 * math.cos(k / 9), sw, k // 500 % 2))
    for row_group, groups in ((1000, 3), (10_000, 1)):
        path = tmp_path / f"t{row_group}.parquet"
        w = tp.ParquetTrace(path, cols, row_group=row_group)
        for row in rows:
            w.write(row)
        w.close({"reason": "completed"})
        assert pq.ParquetFile(path).metadata.num_row_groups == groups
        _assert_chosen(path)
        table = pq.read_table(path)
        for i, name in enumerate(cols):
            want = [r[i] for r in rows]
            if name == "alarm":
                want = [v or None for v in want]
            assert _bits(table.column(name).to_pylist()) == _bits(want), name
        assert table.schema.field("X_sw").type == pa.uint16() and table.schema.field("M21013").type == pa.int64()
        assert tp.read_meta(table.schema)["end"] == {"reason": "completed"}


def test_a_trace_written_before_b139_reads_checks_and_summarises_the_same(runs, tmp_path, hil):
    """A trace from before B139 (pq's default: a dictionary for every column) is read by hil as before: the same
    table, and `hil trace` and `hil check` print the same as for the trace written now."""
    parquet, _ = runs
    old = tmp_path / "old.parquet"
    pq.write_table(pq.read_table(parquet), old, compression="zstd")  # what a run wrote before B139
    assert all("RLE_DICTIONARY" in enc for enc in _encodings(old)[0].values())
    new = tmp_path / "new.parquet"
    new.write_bytes(parquet.read_bytes())
    assert TraceFile(old).table().equals(TraceFile(new).table())
    for args in (("trace",), ("trace", "--from", "0.1", "--to", "0.2"),
                 ("check", "--bench", LATHE, "--program", TURN, "--max-ferr", "0.5", "--limits")):
        a, b = hil(*args[:1], old, *args[1:]), hil(*args[:1], new, *args[1:])
        assert a.code == b.code and a.out.replace("old.parquet", "T") == b.out.replace("new.parquet", "T"), args
        assert "0x0401" in a.out or args[0] == "check"


@pytest.mark.parametrize("private", [True, False], ids=["pyarrow's writer and reader classes", "through pq"])
def test_a_joined_trace_is_the_same_through_pq(tmp_path, monkeypatch, private):
    """The parts are read and joined through pyarrow's reader and writer classes, or through pq's module for a
    pyarrow without them: the same file either way."""
    if not private:
        monkeypatch.setattr(tp, "_Reader", None)
        monkeypatch.setattr(tp, "_Writer", None)
    cols = ["t", "line", "cycle", "alarm", "X_act", "X_sw"]
    w = tp.ParquetTrace(tmp_path / "j.parquet", cols, row_group=400, meta={"program": "j.nc"})
    for k in range(1000):
        w.write((k * 0.001, k // 9, k, "" if k % 250 else "0x0401", math.cos(k / 40), 0x1637))
    w.close({"reason": "completed"})
    _assert_chosen(tmp_path / "j.parquet")
    t = pq.read_table(tmp_path / "j.parquet")
    assert t.column("alarm").to_pylist()[::250] == ["0x0401"] * 4 and t.column("alarm").null_count == 996
    assert _bits(t.column("X_act").to_pylist()) == _bits([math.cos(k / 40) for k in range(1000)])
    assert pq.ParquetFile(tmp_path / "j.parquet").metadata.num_row_groups == 3


def test_joining_the_parts_does_not_import_pyarrow_parquet(tmp_path):
    """pq's module imports pyarrow.fs and ssl (≈ 10 ms of CPU, B92): a run of several parts joins them without it."""
    import subprocess
    import sys

    code = ("import sys, hil.trace_parquet as tp; "
            f"w = tp.ParquetTrace({str(tmp_path / 'p.parquet')!r}, ['t', 'cycle'], row_group=100); "
            "[w.write((k * 0.001, k)) for k in range(350)]; w.close(); "
            "print(*(m in sys.modules for m in ('pyarrow.parquet', 'pyarrow.fs')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "False"]
    assert pq.read_table(tmp_path / "p.parquet").column("cycle").to_pylist() == list(range(350))
