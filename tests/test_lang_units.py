"""G20 inch input scales linear axis words only: rotary axis words stay in degrees (decisions
language.md "G20 and rotary axes")."""

from __future__ import annotations

from pathlib import Path

from lang_helpers import run_path

ROOT = Path(__file__).resolve().parent.parent
LATHE_C = ROOT / "benches" / "lathe-c-axis.toml"


def test_g20_keeps_rotary_c_in_degrees_on_lathe(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G20 G98\nG01 X1. Z-1. C90. F10.\nH45. W-0.5\nC45\nM30\n",
                 "--bench", str(LATHE_C), profile="nc5-lathe-a")
    assert r.code == 0, r.alarm
    assert r.ends("X", "Z", "C") == [(25.4, -25.4, 90.0), (25.4, -38.1, 135.0), (25.4, -38.1, 0.045)]
    assert r.moves[0]["feed"] == 254.0  # F in inch/min
    assert r.machine("X")[0] == (12.7,)  # X diameter -> radius in machine coordinates


def test_g20_mill_a_axis_and_work_offset(capsys, tmp_path):
    bench = (ROOT / "benches" / "mill-3axis.toml").read_text()
    bench = bench.replace("[[spindles]]", '[[axes]]\nname = "A"\nunits = "deg"\nlead = 360.0\n'
                                          'limits = { velocity = 3600.0, acceleration = 36000.0, jerk = 1800000.0 }\n\n'
                                          "[[spindles]]", 1)
    b = tmp_path / "mill4.toml"
    b.write_text(bench)
    r = run_path(capsys, tmp_path, "G20 G90 G54\nG10 L2 P1 X1. A10.\nG00 X2. Y1. A30.\nG91 G01 X0.5 A-5. F20.\nM30\n",
                 "--bench", str(b), profile="nc5-mill")
    assert r.code == 0, r.alarm
    assert r.ends("X", "Y", "A") == [(50.8, 25.4, 30.0), (63.5, 25.4, 25.0)]
    assert r.machine("X", "A") == [(76.2, 40.0), (88.9, 35.0)]  # G54 X 1 inch, A 10 degrees


def test_g21_rotary_unchanged_and_linear_unscaled(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G21 G98\nG01 X10. Z-2. C7.5 F100.\nM30\n",
                 "--bench", str(LATHE_C), profile="nc5-lathe-a")
    assert r.ends("X", "Z", "C") == [(10.0, -2.0, 7.5)]
