"""From a run to a report: hil run with bench checks, --realtime jitter, hil trace, hil report."""

from pathlib import Path

import pytest

from hil.cli import main

BENCHES = Path(__file__).resolve().parent.parent / "benches"
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nG02 X30. Z-6. R3.\nM30\n"


@pytest.fixture
def prog(tmp_path):
    p = tmp_path / "p.nc"
    p.write_text(PROGRAM)
    return p


def test_run_trace_report(tmp_path, prog, capsys):
    trace = tmp_path / "run.parquet"
    assert main(["run", str(prog), "--bench", str(BENCHES / "lathe-2axis.toml"), "--trace", str(trace)]) == 0
    out = capsys.readouterr().out
    assert "checks" in out and "ok    contour error" in out and "FAIL" not in out

    assert main(["trace", str(trace), "--from", "L4", "--to", "L4"]) == 0
    out = capsys.readouterr().out
    assert "program lines  1 (4 … 4)" in out and "axis Z" in out
    sliced = tmp_path / "slice.csv"
    assert main(["trace", str(trace), "--from", "0.1", "--to", "0.2", "--out", str(sliced), "--columns", "Z_cmd"]) == 0
    lines = sliced.read_text().splitlines()
    assert lines[0].replace('"', "") == "t,line,Z_cmd" and len(lines) == 1 + 101

    rep = tmp_path / "rep"
    assert main(["report", str(trace), "--out", str(rep), "--bench", str(BENCHES / "lathe-2axis.toml"),
                 "--program", str(prog)]) == 0
    html = (rep / "index.html").read_text()
    for png in ("path.png", "following_error.png", "velocity_torque.png", "jitter.png", "signals.png"):
        data = (rep / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
        assert png in html
    assert "Checks: <span class='ok'>PASS</span>" in html


def test_failed_bench_check_exits_3(tmp_path, prog, capsys):
    """A completed run whose check fails exits 3, apart from an alarm's 1 (issue 22: distinct codes)."""
    bench = tmp_path / "tight.toml"
    bench.write_text((BENCHES / "lathe-2axis.toml").read_text().replace(
        "max_following_error = { X = 0.1, Z = 0.1 }", "max_following_error = { X = 0.001, Z = 0.1 }"))
    assert main(["run", str(prog), "--bench", str(bench)]) == 3
    out = capsys.readouterr().out
    assert "FAIL  following error X" in out and "at cycle" in out and ", line " in out


def test_realtime_run_prints_jitter_percentiles(tmp_path, capsys):
    p = tmp_path / "short.nc"
    p.write_text("G98\nG01 Z99. F3000.\nM30\n")  # ~0.3 s of real time
    assert main(["run", str(p), "--realtime", "--overrun", "warn", "--no-check"]) == 0
    out = capsys.readouterr().out
    assert "real time" in out
    line = next(ln for ln in out.splitlines() if ln.startswith("cycle jitter"))
    for key in ("p50", "p99", "p99.9", "max"):
        assert f" {key} " in line
