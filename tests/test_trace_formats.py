"""Traces every data tool reads alike (issue 22): nulls for "no value", unsigned statuswords, the
unit of every column and the run's provenance and end record in the metadata, a trace readable
after SIGKILL, and `hil trace --out` formats."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import hil
from hil.cli import main
from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
TURN = ROOT / "tests" / "data" / "campaign" / "short_turn.nc"


@pytest.fixture(scope="module")
def trace(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("t") / "run.parquet"
    r = hil.run(TURN, bench=LATHE, trace=out, events=["t=0.3:estop"], check=False)
    assert r.alarms and r.alarms[0].code == 0x0401
    return out


def test_types_nulls_units_and_provenance(trace):
    schema = pq.read_schema(trace)
    assert schema.field("X_sw").type == pa.uint16() and schema.field("S1_sw").type == pa.uint16()
    assert schema.field("cycle").type == pa.int64() and schema.field("alarm").type == pa.string()
    tf = TraceFile(trace)
    units = tf.units()
    assert units["t"] == "s" and units["X_cmd"] == "mm" and units["Z_vel"] == "mm/s"
    assert units["S1_rpm_act"] == "rpm" and units["X_torque"] == "% rated torque"
    meta = tf.meta
    assert meta["bench"]["name"] == "lathe-2axis" and meta["bench"]["axes"]["X"]["jerk"] == 150000.0
    assert meta["program"].endswith("short_turn.nc") and meta["deltahil_version"]
    end = meta["end"]
    assert end == {"reason": "alarm", "alarm": "0x0401", "alarm_line": end["alarm_line"],
                   "cycle": tf.num_rows, "t": pytest.approx(tf.num_rows * 0.001), "complete": True,
                   "bus": "closed"}
    alarm = pq.read_table(trace, columns=["alarm"]).column("alarm")
    assert alarm.null_count == alarm.length() - 1  # one row names the E-stop, the rest are null


def test_pyarrow_pandas_polars_duckdb_read_the_same_types_and_nulls(trace):
    pd = pytest.importorskip("pandas")
    pl = pytest.importorskip("polars")
    duckdb = pytest.importorskip("duckdb")
    t = pq.read_table(trace)
    df = pd.read_parquet(trace)
    lf = pl.read_parquet(trace)
    con = duckdb.connect()
    n_alarm = con.execute(f"SELECT count(alarm), count(*) FROM '{trace}'").fetchone()
    assert n_alarm == (1, t.num_rows)  # count(alarm) counts alarms, not empty strings
    assert int(df["alarm"].notna().sum()) == 1 and lf["alarm"].null_count() == t.num_rows - 1
    assert str(df["X_sw"].dtype) == "uint16" and lf["X_sw"].dtype == pl.UInt16
    sw_type = con.execute(f"SELECT typeof(X_sw) FROM '{trace}' LIMIT 1").fetchone()[0]
    assert sw_type == "USMALLINT"
    assert df["X_cmd"].tolist() == lf["X_cmd"].to_list() == t.column("X_cmd").to_pylist()


def test_a_run_killed_hard_leaves_a_trace_readable_up_to_its_last_flush(tmp_path):
    """Killed once a part was flushed (FLUSH_S of wall time in: a run that takes longer than that; a run that
    ends sooner writes its one part as the trace itself at its end, hil/trace_parquet.py)."""
    out = tmp_path / "killed.parquet"
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", str(ROOT / "examples" / "lathe_part_g71_g70_g76.nc"),
                          "--trace", str(out), "--no-check", "--no-progress"],
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    parts = out.with_name(out.name + ".part")
    deadline = time.monotonic() + 120
    while not list(parts.glob("*.parquet")) and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert not out.exists() and parts.is_dir()
    tf = TraceFile(parts)
    assert tf.partial and tf.num_rows >= 1000 and "X_cmd" in tf.columns
    t = tf.arrays(["t"])["t"]
    assert t[0] == pytest.approx(0.001) and all(t[1:] > t[:-1])
    assert pq.read_table(parts).num_rows == tf.num_rows  # a plain Parquet dataset to other tools
    assert main(["trace", str(parts)]) == 0


@pytest.mark.parametrize("suffix", [".parquet", ".csv", ".feather", ".arrow"])
def test_trace_out_writes_the_format_its_suffix_names(trace, tmp_path, suffix):
    out = tmp_path / f"x{suffix}"
    assert main(["trace", str(trace), "--out", str(out)]) == 0
    back = TraceFile(out).table() if suffix in (".parquet", ".csv") else \
        pa.ipc.open_file(out).read_all()
    assert back.num_rows == pq.read_metadata(trace).num_rows
    assert back.column("X_cmd").to_pylist() == pq.read_table(trace, columns=["X_cmd"]).column(0).to_pylist()


def test_trace_out_mf4_has_units_and_other_suffixes_are_refused(trace, tmp_path, capsys):
    asammdf = pytest.importorskip("asammdf")
    out = tmp_path / "x.mf4"
    assert main(["trace", str(trace), "--out", str(out)]) == 0
    mdf = asammdf.MDF(str(out))
    sig = mdf.get("X_cmd")
    assert sig.unit == "mm" and len(sig.samples) == pq.read_metadata(trace).num_rows
    assert mdf.get("Z_vel").unit == "mm/s"
    assert sig.timestamps[0] == pytest.approx(0.001)
    mdf.close()
    capsys.readouterr()
    assert main(["trace", str(trace), "--out", str(tmp_path / "x.xlsx")]) == 2
    assert ".xlsx" in capsys.readouterr().err and not (tmp_path / "x.xlsx").exists()


@pytest.mark.parametrize("suffix", [".feather", ".arrow"])
def test_an_arrow_ipc_export_is_read_back_by_trace_check_and_report(trace, tmp_path, capsys, suffix):
    """bench B54: `hil trace --out x.feather` wrote a file `hil trace x.feather` refused with a utf-8 codec error."""
    out = tmp_path / f"x{suffix}"
    assert main(["trace", str(trace), "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["trace", str(out)]) == 0
    text = capsys.readouterr().out
    rows = pq.read_metadata(trace).num_rows
    assert f"(Arrow IPC, " in text and f"rows           {rows}  (t 0.001 … " in text
    assert "0x0401 at cycle 300 (t=0.300 s)" in text  # the E-stop's alarm row, as from the Parquet trace
    assert main(["check", str(out), "--max-ferr", "1"]) == 0
    assert "ok    following error X" in capsys.readouterr().out
    back = tmp_path / "back.csv"
    assert main(["trace", str(out), "--from", "0.1", "--to", "0.2", "--out", str(back)]) == 0
    assert len(back.read_text().splitlines()) == 1 + 101


def test_an_mdf4_export_given_as_a_trace_says_what_it_is(trace, tmp_path, capsys):
    pytest.importorskip("asammdf")
    out = tmp_path / "x.mf4"
    assert main(["trace", str(trace), "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["trace", str(out)]) == 2
    err = capsys.readouterr().err
    assert "x.mf4: an MDF4 file: hil reads traces as CSV, Parquet or Arrow IPC" in err and "codec" not in err


def test_a_trace_a_killed_run_left_unfinished_is_pointed_at(tmp_path, capsys):
    """`hil trace t.parquet` after a run writing it was killed hard: the message names the `.part` it left,
    or says that one holds no rows (killed before its first flush), not just 'no such trace file' (B73)."""
    empty = tmp_path / "a.parquet.part"
    empty.mkdir()
    assert main(["trace", str(tmp_path / "a.parquet")]) == 2
    err = capsys.readouterr().err
    assert "no such trace file; a.parquet.part: a run killed before its first flush (2 s of wall time) left it" \
           " with no rows; rerun" in err
    assert main(["trace", str(empty)]) == 2
    assert "a.parquet.part: a run killed before its first flush" in capsys.readouterr().err
    (tmp_path / "b.csv.part").write_text("t,line\n0.001,1\n")
    assert main(["check", str(tmp_path / "b.csv")]) == 2
    assert "b.csv.part is what a run killed before it finished left: give that, or rerun" in capsys.readouterr().err
    assert main(["trace", str(tmp_path / "c.csv")]) == 2
    assert capsys.readouterr().err.strip().endswith("c.csv: no such trace file")


def test_an_export_keeps_the_runs_bench_program_end_and_units(trace, tmp_path, capsys):
    """bench B81: `hil trace --out x.csv` of a Parquet trace (and the other way) dropped the run's record: the
    converted trace no longer knew its bench (`hil check x.csv --limits` asked for --bench), its end or units."""
    from hil.trace_parquet import read_meta

    meta = TraceFile(trace).meta
    assert meta["end"]["alarm"] == "0x0401" and meta["bench"]["name"] == "lathe-2axis"
    csv_out, back, arrow = tmp_path / "x.csv", tmp_path / "back.parquet", tmp_path / "x.arrow"
    assert main(["trace", str(trace), "--out", str(csv_out)]) == 0
    assert {k: v for k, v in TraceFile(csv_out).meta.items() if k != "units"} == meta
    assert TraceFile(csv_out).meta["units"]["X_cmd"] == "mm"
    capsys.readouterr()
    assert main(["check", str(csv_out), "--max-ferr", "1"]) == 0
    assert "bench lathe-2axis (recorded in the trace" in capsys.readouterr().out
    for out in (back, arrow):  # CSV → Parquet / Arrow IPC: the side file's record goes into the schema again
        assert main(["trace", str(csv_out), "--out", str(out)]) == 0
        schema = pq.read_schema(out) if out.suffix == ".parquet" else pa.ipc.open_file(out).schema
        assert read_meta(schema) == meta and schema.field("Z_vel").metadata == {b"unit": b"mm/s"}
    mf4 = pytest.importorskip("asammdf").MDF
    assert main(["trace", str(csv_out), "--out", str(tmp_path / "x.mf4")]) == 0
    assert mf4(str(tmp_path / "x.mf4")).get("X_cmd").unit == "mm"  # the CSV's units reach MDF4 too
    # an export of a trace without a record leaves none, not an older file's, beside its CSV
    bare = tmp_path / "bare.csv"
    bare.write_text("t,line,X_cmd\n0.001,0,1.0\n")
    (tmp_path / "y.csv.meta.json").write_text('{"program": "older.nc"}')
    assert main(["trace", str(bare), "--out", str(tmp_path / "y.csv")]) == 0
    assert not (tmp_path / "y.csv.meta.json").exists()
