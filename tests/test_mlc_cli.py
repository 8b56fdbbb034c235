"""The exercising commands a user runs: hil mpg, hil spindle, hil script."""

from __future__ import annotations

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
