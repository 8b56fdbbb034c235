"""The path checks start where the run's program started (decision B51).

A bench with drive homing (here CiA 402 method 35: the home position is where the axis stands, X renamed 60 → 5)
starts its program from the homed position, as a real bench starts from wherever its axes stand. The contour check
used to rebuild the programmed path from the bench's power-on `start`, and the setpoint-limit check differentiated
across the homing's new origin: both failed on a run that did nothing wrong (contour error 5 mm, X velocity
5.5e4 mm/s at the homing cycle)."""

from __future__ import annotations

import pytest

from hil import api
from hil.checks import program_row, program_start
from hil.cli import main
from hil.trace_read import TraceFile
from tests.conftest import ROOT

PROGRAMS = {
    "absolute": "G98\nG01 X20. F600\nZ90.\nM30\n",  # X is a diameter: X20. is 10 mm
    "incremental": "G98\nG01 U20. F600\nW-10.\nU-6.\nM30\n",  # every end depends on the start
}


@pytest.fixture
def homed_bench(tmp_path):
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    assert "start = 60.0\n" in text
    path = tmp_path / "homed.toml"
    path.write_text(text.replace("start = 60.0\n", "start = 60.0\nhoming = { method = 35, position = 5.0 }\n", 1))
    return path


@pytest.mark.parametrize("kind", sorted(PROGRAMS))
def test_a_homed_run_passes_its_path_checks(tmp_path, homed_bench, kind):
    prog = tmp_path / f"{kind}.nc"
    prog.write_text(PROGRAMS[kind])
    trace = tmp_path / "run.parquet"
    res = api.run(prog, homed_bench, trace=trace, check=True)
    assert res.run.ok
    by_name = {c.name: c for c in res.checks}
    assert by_name["contour error"].ok and by_name["contour error"].value < 0.02
    assert by_name["velocity X"].ok and by_name["velocity X"].value == pytest.approx(10.0, rel=1e-3)  # F600
    assert all(c.ok for c in res.checks), [str(c) for c in res.checks if not c.ok]
    tf = TraceFile(str(trace))
    start = program_start(tf, ["X", "Z"])
    assert start == pytest.approx({"X": 5.0, "Z": 100.0}, abs=1e-6)  # homed X, Z where it stood
    row = program_row(tf)
    assert int(tf.arrays(["line"])["line"][row]) == 0 and int(tf.arrays(["line"])["line"][row + 1]) > 0
    expected_x = {"absolute": 10.0, "incremental": 5.0 + 10.0 - 3.0}[kind]
    assert res.final_position["X"] == pytest.approx(expected_x, abs=1e-3)
    # `hil check` on the trace judges it the same way
    assert main(["check", str(trace), "--program", str(prog)]) == 0


def test_a_trace_whose_program_never_started_judges_no_setpoint(tmp_path):
    """Power-up and a homing that renamed X, then the run ended before any block (line 0 throughout): no start
    row, and the homing's step is not judged as a speed."""
    from hil.bench import default_lathe
    from hil.checks import run_checks

    rows = ["t,line,cycle,X_cmd,X_act,X_sw,Z_cmd,Z_act,Z_sw"]
    for k in range(1, 11):
        x = 60.0 if k < 6 else 5.0
        rows.append(f"{k / 1000},0,{k},{x},{x},{0x1637},100.0,100.0,{0x1637}")
    path = tmp_path / "t.csv"
    path.write_text("\n".join(rows) + "\n")
    tf = TraceFile(str(path))
    assert program_row(tf) is None and program_start(tf, ["X", "Z"]) is None
    bench = default_lathe()
    bench.checks.limits = True
    results = {c.name: c for c in run_checks(tf, bench.checks, bench)}
    assert results["velocity X"].ok and results["velocity X"].value == 0.0
