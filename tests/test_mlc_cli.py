"""The exercising commands a user runs: hil mpg, hil spindle, hil script."""

from __future__ import annotations

import pytest

from tests.conftest import ROOT


def test_hil_mpg_reports_pulses_times_ratio(hil):
    r = hil("mpg", "X", "100", "--ratio", "10")
    assert r.code == 0, r.err
    assert "commanded +1.0000 mm" in r.out and "X       60.0000 →    61.0000" in r.out


def test_hil_mpg_unknown_axis_is_a_usage_error(hil):
    r = hil("mpg", "Q", "10")
    assert r.code == 2 and "axis 'Q'" in r.err


def test_hil_spindle_ramps_up_and_down_in_csv(hil):
    r = hil("spindle", "1200", "--seconds", "0.2")
    assert r.code == 0, r.err
    assert "1200.0 rpm at speed" in r.out and "modes CSV" in r.out


def test_hil_script_runs_the_shipped_spindle_example(hil):
    r = hil("script", str(ROOT / "examples" / "scripts" / "spindle_ramps.py"))
    assert r.code == 0, r.err
    assert "drive at 3000.0 rpm" in r.out and "peak   3000.0 rpm" in r.out


def test_hil_script_missing_file(hil, tmp_path):
    r = hil("script", str(tmp_path / "nope.py"))
    assert r.code == 2 and "does not exist" in r.err


def test_hil_run_with_a_user_mlc_module(hil, tmp_path):
    import csv

    prog = tmp_path / "p.nc"
    prog.write_text("M08\nM09\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", str(prog), "--mlc", str(ROOT / "examples" / "mlc" / "coolant_only.py"), "--trace", str(trace),
            "--trace-signals", "M_STROBE,MST_FINISH,M_CODE")
    assert r.code == 0, r.err
    rows = list(csv.DictReader(trace.open()))
    on = [float(x["t"]) for x in rows if x["M31064"] == "1"]
    fin = [float(x["t"]) for x in rows if x["M21016"] == "1"]
    assert fin and min(fin) - min(on) == pytest.approx(0.05, abs=0.0015)  # the module's 50 ms timer
