"""`hil check` and `hil report` judge a trace against the bench it was recorded on, name that
bench, and refuse when nobody says which bench it was (issue 20; decision R4). Before, a trace
checked with --limits and no --bench was silently judged against the built-in lathe's limits."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = ROOT / "examples" / "servo_params.nc"


def fast_z_bench(tmp_path: Path) -> Path:
    """The shipped lathe bench with Z allowed 800 mm/s (the built-in lathe: 400). The program's
    rapid runs Z at 422 mm/s: within the recorded bench, over the built-in one."""
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    text = text.replace('name = "lathe-2axis"', 'name = "lathe-fast-z"')
    text = text.replace("limits = { velocity = 400.0, acceleration = 4000.0", "limits = { velocity = 800.0, acceleration = 4000.0")
    assert "velocity = 800.0" in text
    p = tmp_path / "fast-z.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_check_uses_the_bench_recorded_in_the_trace(hil, tmp_path, suffix):
    bench = fast_z_bench(tmp_path)
    trace = tmp_path / f"t{suffix}"
    assert hil("run", PROGRAM, "--bench", bench, "--trace", trace).code == 0
    r = hil("check", trace, "--limits")
    assert r.code == 0, r.out + r.err  # the built-in lathe's 400 mm/s would fail it
    assert f"bench lathe-fast-z (recorded in the trace, {bench})" in r.out
    assert "ok    velocity Z: 421.8 mm/s <= 800 mm/s" in r.out


def test_a_trace_that_does_not_say_its_bench_is_refused(hil, tmp_path):
    trace = tmp_path / "t.csv"
    assert hil("run", PROGRAM, "--bench", fast_z_bench(tmp_path), "--trace", trace).code == 0
    (tmp_path / "t.csv.meta.json").unlink()  # as a CSV trace from elsewhere, or an older deltahil
    r = hil("check", trace, "--limits")
    assert r.code == 2 and "give --bench FILE for --limits" in r.err
    r = hil("report", trace, "--out", tmp_path / "rep", "--limits")
    assert r.code == 2 and "give --bench FILE" in r.err
    # a following-error check needs no bench: the trace's own axes are judged
    r = hil("check", trace, "--max-ferr", "0.1")
    assert r.code == 0 and "following error X" in r.out and "following error Z" in r.out


def test_an_explicit_bench_wins_and_the_mismatch_is_said(hil, tmp_path):
    trace = tmp_path / "t.parquet"
    assert hil("run", PROGRAM, "--bench", fast_z_bench(tmp_path), "--trace", trace).code == 0
    r = hil("check", trace, "--limits", "--bench", ROOT / "benches" / "lathe-2axis.toml")
    assert r.code == 1, r.out + r.err
    assert "recorded on bench lathe-fast-z; checking against lathe-2axis" in r.err
    assert "bench lathe-2axis (" in r.out and "FAIL  velocity Z: 421.8 mm/s > 400 mm/s" in r.out


def test_no_flags_judges_the_trace_as_its_run_was(hil, tmp_path):
    """With no check asked for, the recorded bench's [checks] apply (the run's own verdict)."""
    trace = tmp_path / "t.parquet"
    assert hil("run", PROGRAM, "--bench", fast_z_bench(tmp_path), "--trace", trace).code == 0
    r = hil("check", trace)
    assert "following error X" in r.out and "velocity Z: 421.8 mm/s <= 800" in r.out and "jitter p99" in r.out
    # the bench's contour check takes the program the run recorded (B75); this one reads servo parameters, which
    # only a run answers, so its path is unknown offline and the check is skipped saying so, as after `hil run`
    assert f"program {PROGRAM.resolve()} (recorded in the trace)" in r.out
    assert "SKIP  contour error: the program does not run offline" in r.out and r.code == 0, r.out + r.err


def test_the_recorded_program_judges_the_path_while_its_file_is_unchanged(hil, tmp_path):
    """Decision B75: `hil check/report TRACE` judge the contour against the program the run recorded (path and
    SHA-256 in the trace); once the file changed, they say so and the check needs --program again."""
    prog = tmp_path / "p.nc"
    prog.write_text((ROOT / "examples" / "lathe_demo.nc").read_text())
    trace = tmp_path / "t.parquet"
    assert hil("run", prog, "--bench", ROOT / "benches" / "lathe-2axis.toml", "--trace", trace).code == 0
    r = hil("check", trace)
    assert r.code == 0, r.out + r.err
    assert f"program {prog.resolve()} (recorded in the trace)" in r.out and "ok    contour error: " in r.out
    r = hil("report", trace, "--out", tmp_path / "rep")
    assert r.code == 0 and f"program {prog.resolve()} (recorded in the trace)" in r.out
    prog.write_text(prog.read_text() + "(edited after the run)\n")
    r = hil("check", trace)
    assert r.code == 1 and "SKIP  contour error: needs the program (--program)" in r.out
    assert f"note: the program the run recorded, {prog.resolve()}, has changed since the run" in r.err
    r = hil("check", trace, "--program", ROOT / "examples" / "lathe_demo.nc")  # the user's word wins
    assert r.code == 0 and "ok    contour error: " in r.out and "recorded in the trace)\n" not in r.out
