"""deltahil as a library (issue 22): `hil.run`, `hil.path`, `hil.load_trace` on the same code path as
the `hil run` command, and the override switches at power-on."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import hil
from hil.session import InputError
from nc.moves import Move

ROOT = Path(__file__).resolve().parents[1]
MILL = ROOT / "benches" / "mill-3axis.toml"
LATHE = ROOT / "benches" / "lathe-2axis.toml"
TURN = ROOT / "tests" / "data" / "campaign" / "short_turn.nc"


@pytest.fixture
def square(tmp_path) -> Path:
    p = tmp_path / "square.nc"
    p.write_text("G21 G17 G90 G94\nG01 X20. F1200\nY20.\nX0.\nY0.\nM30\n")
    return p


def test_run_returns_what_the_command_prints(square, tmp_path):
    r = hil.run(square, bench=MILL, trace=tmp_path / "t.parquet")
    assert r.ok and r.completed and not r.alarms
    assert r.final_position == pytest.approx({"X": 0.0, "Y": 0.0, "Z": 100.0}, abs=1e-4)
    assert 4.0 < r.program_time < 4.5  # 80 mm at 20 mm/s, plus four jerk-limited stops
    assert set(r.max_following_error) == {"X", "Y", "Z"}
    table = r.trace.load()
    assert table.num_rows == r.cycles and {"t", "X_cmd", "Y_act"} <= set(table.column_names)
    assert hil.load_trace(tmp_path / "t.parquet").num_rows == r.cycles
    out = subprocess.run([sys.executable, "-m", "hil.cli", "run", str(square), "--bench", str(MILL)],
                         capture_output=True, text=True, env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert f"program time   {r.program_time:.3f} s simulated" in out.stdout
    assert f"cycles         {r.cycles} " in out.stdout


@pytest.mark.parametrize("bench, program", [(MILL, None), (LATHE, TURN)])
def test_feed_override_at_power_on_stretches_the_feed_moves(bench, program, square):
    prog = program or square
    times = [hil.run(prog, bench=bench, feed_override=f, check=False).program_time for f in (50, 100, 150)]
    assert times[0] > times[1] > times[2]


def test_the_bench_checks_run_and_fail_the_result(tmp_path):
    bench = tmp_path / "tight.toml"
    bench.write_text(LATHE.read_text().replace("max_following_error = { X = 0.1, Z = 0.1 }",
                                               "max_following_error = { X = 0.001, Z = 0.1 }"))
    r = hil.run(TURN, bench=bench)
    assert r.completed and not r.ok and not r.checks_ok
    assert [c.name for c in r.checks if not c.ok] == ["following error X"]
    assert r.trace is None  # the checks' own trace is not kept unless asked for


def test_a_program_alarm_is_a_result_and_bad_input_raises(tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("G21\nG01 X10. F100\nG07.7 X1.\nM30\n")
    r = hil.run(bad, bench=LATHE, check=False)
    assert not r.ok and r.alarms[0].code == 0x021D and r.alarms[0].line == 3
    with pytest.raises(InputError, match="feed override"):
        hil.run(TURN, bench=LATHE, feed_override=151)
    with pytest.raises(InputError, match="no_such"):
        hil.run(TURN, bench=tmp_path / "no_such.toml")


def test_path_gives_the_moves_in_machine_coordinates(square):
    moves = [m for m in hil.path(square, bench=MILL) if isinstance(m, Move)]
    assert [tuple(round(m.end[a], 6) for a in "XY") for m in moves] == [(20, 0), (20, 20), (0, 20), (0, 0)]
    assert all(m.end["Z"] == 100.0 for m in moves)


def test_import_hil_stays_light():
    code = "import sys, hil; print(any(m.startswith(('nc.', 'matplotlib', 'pyarrow', 'fieldbus')) for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "False"


def test_a_run_without_a_spline_fit_does_not_import_scipys_fitting_parts(tmp_path):
    """scipy.interpolate/sparse/linalg (≈ 0.17 s of every `hil run`) and the fit's own modules (B91) are imported by a
    spline fit when it runs, and before paced cycles (hil/runner.py _preload), where the import would overrun a
    cycle."""
    names = "('scipy.interpolate', 'scipy.sparse', 'scipy.linalg', 'nc.motion.spline_runs', 'nc.motion.spline_join')"
    code = ("import sys, hil; r = hil.run('examples/lathe_demo.nc'); "
            f"print(r.run.ok, any(m in sys.modules for m in {names}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.split() == ["True", "False"], out.stderr
    code = ("import sys; from hil.bench import default_lathe; from hil.runner import _preload; "
            f"_preload(default_lathe()); print(all(m in sys.modules for m in {names}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "True", out.stderr


def test_importing_the_report_leaves_matplotlibs_backend_alone(tmp_path):
    code = ("import matplotlib; matplotlib.use('svg'); import hil.report, hil.plot; "
            "print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "svg", out.stderr


def test_the_api_returns_the_reports_figures(square, tmp_path):
    from matplotlib.figure import Figure

    r = hil.run(square, bench=MILL, trace=tmp_path / "t.parquet")
    figs = r.figures()
    assert set(figs) == {"path", "following_error", "velocity_torque", "jitter", "signals"}
    assert all(isinstance(f, Figure) for f in figs.values())
    ax = figs["path"].axes[0]
    assert [l.get_label() for l in ax.get_lines()][:3] == ["programmed", "commanded", "actual (feedback)"]


def test_hil_version():
    out = subprocess.run([sys.executable, "-m", "hil.cli", "--version"], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0 and out.stdout.startswith("hil (deltahil) ")
