"""A stop during a G04 dwell is at once (decision M24-1): the axes stand in a dwell, so an alarm, a reset or a
stop signal ends the dwell in the cycle it comes, not when the dwell's time has run out (before: the run went on
to the dwell's end, a 2 s dwell 1.2 s past an alarm, and a SIGTERM in a long dwell waited for the bench's
max_time). A feed hold in a dwell is taken at once and the dwell's time runs on (M24-1). Lathe bench, `hil run
--at`, read from the trace as a bench engineer would."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)


def _run(hil, tmp_path, program: str, *at: str, signals: str = "M31017"):
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    trace = tmp_path / "p.csv"
    args = [a for e in at for a in ("--at", e)]
    r = hil("run", str(prog), "--no-check", "--trace", str(trace), "--trace-signals", signals, *args)
    return r, list(csv.DictReader(trace.open()))


def _at_rest_and_disabled(rows, k: int) -> None:
    """No axis moves from row k on, and the run ends with every drive out of Operation Enabled."""
    for ax in ("X", "Z"):
        assert {row[f"{ax}_cmd"] for row in rows[k:]} == {rows[k][f"{ax}_cmd"]}
        assert int(rows[-1][f"{ax}_sw"]) & 0x6F != OP_ENABLED


@pytest.mark.parametrize("event, alarm", [("t=1.0:set A1=1", "A1"), ("t=1.0:reset", None)])
def test_an_alarm_or_a_reset_in_a_dwell_ends_the_run_at_once(hil, tmp_path, event, alarm):
    r, rows = _run(hil, tmp_path, "G04 X2.\nM30\n", event)
    assert r.code == 1, r.out + r.err
    k = next(i for i, row in enumerate(rows) if float(row["t"]) >= 1.0)
    if alarm is not None:
        assert rows[k]["alarm"] == alarm and not any(row["alarm"] for row in rows[:k])
    # the run ends within the drives' disable (a few cycles), not at the dwell's end at 2.0 s
    assert float(rows[-1]["t"]) < 1.05, rows[-1]["t"]
    _at_rest_and_disabled(rows, 0)
    assert "STOPPED" in r.out


def test_an_alarm_in_a_dwell_at_speed_ends_once_the_spindle_stands(hil, tmp_path):
    """M2x012 OFF at 1.0 s in a 2 s dwell at S1000 (M23-2's case): 0x0C06 at 1.0 s; the spindle ramps down on
    its drive's deceleration and the run ends when it stands, well before the dwell's 2 s."""
    r, rows = _run(hil, tmp_path, "M03 S1000\nG04 X2.\nM30\n", "t=1.0:set M21012=0", signals="M21012")
    assert r.code == 1 and "ALARM 0x0C06 axis S1 at line 2" in r.out, r.out + r.err
    k = next(i for i, row in enumerate(rows) if row["alarm"])
    assert float(rows[k]["t"]) == pytest.approx(1.0, abs=1e-9)
    assert float(rows[-1]["t"]) < 1.3 and abs(float(rows[-1]["S1_rpm_act"])) < 1.0
    _at_rest_and_disabled(rows, 0)
    assert int(rows[-1]["S1_sw"]) & 0x6F != OP_ENABLED


def test_a_feed_hold_in_a_dwell_is_at_once_and_the_dwell_time_runs_on(hil, tmp_path):
    """M2x001 in a dwell: M3x017 ON from that cycle; the dwell's time is not stopped by the hold (M24-1), so a
    cycle start at 1.5 s lets the program end when the 2 s dwell ends; one after the dwell's end ends it then."""
    r, rows = _run(hil, tmp_path, "G04 X2.\nM30\n", "t=1.0:feed-hold", "t=1.5:cycle-start")
    assert r.code == 0, r.out + r.err
    held = [float(row["t"]) for row in rows if row["M31017"] == "1"]
    assert held[0] == pytest.approx(1.0, abs=1e-9) and held[-1] == pytest.approx(1.499, abs=1e-9)
    assert 2.0 <= float(rows[-1]["t"]) < 2.05
    r, rows = _run(hil, tmp_path, "G04 X2.\nM30\n", "t=1.0:feed-hold", "t=2.5:cycle-start")
    assert r.code == 0, r.out + r.err
    assert 2.5 <= float(rows[-1]["t"]) < 2.55  # held past the dwell's end: the M30 waits for the cycle start
    _at_rest_and_disabled(rows, 0)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=lambda s: s.name)
def test_a_stop_signal_in_a_long_dwell_stops_the_run_at_once(tmp_path, sig):
    """A signal in a 100,000 s dwell: the run ends within seconds of wall time with 128 + the signal's number
    (before, the stop waited for the bench's max_time of 3600 s: ~6 min of wall time, then alarm 0xDE03)."""
    prog = tmp_path / "dwell.nc"
    prog.write_text("M03 S500\nG04 X100000.\nM30\n")
    trace = tmp_path / "run.parquet"
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", str(prog), "--trace", str(trace), "--no-check",
                          "--no-progress"], env={**os.environ, "PYTHONPATH": str(ROOT)},
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parts = trace.with_name(trace.name + ".part")
    deadline = time.monotonic() + 60
    while not list(parts.glob("*.parquet")) and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.02)  # in the dwell (its first row group is on disk)
    p.send_signal(sig)
    try:
        out, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        pytest.fail("the run went on in its dwell after the signal")
    assert p.returncode == 128 + sig, err
    assert f"STOPPED by {sig.name}" in out and "0xDE03" not in out
    a = TraceFile(trace).arrays(["t", "X_sw", "Z_sw", "X_cmd", "Z_cmd"])
    assert a["t"][-1] < 3000.0  # ended where the signal came, not at max_time
    assert all(int(a[f"{ax}_sw"][-1]) & 0x6F != OP_ENABLED for ax in ("X", "Z"))
    assert all(len(set(a[f"{ax}_cmd"].tolist())) == 1 for ax in ("X", "Z"))  # nothing moved
