"""`hil check TRACE --against REF` (decision B127): a run judged against a reference run of the same program, as a
bench's regression check — the commanded path both ways within --path-tol, the program's time within --time-tol,
the same end, the same MLC signal values in the same order. Runs through `hil run` on the lathe bench, in
simulated time."""

from __future__ import annotations

import json

import pytest

from tests.conftest import ROOT

PROGRAM = "G98 M03 S800\nG00 X24. Z2.\nG01 Z-40. F300.\nX30.\nZ-60.\nG00 X60. Z100.\nM05\nM30\n"
SIGNALS = "M31064,D31048"


def _trace(hil, tmp_path, name: str, program: str = PROGRAM, *args: str, bench: str | None = None):
    prog = tmp_path / f"{name}.nc"
    prog.write_text(program)
    trace = tmp_path / f"{name}.parquet"
    r = hil("run", prog, "--trace", trace, "--trace-signals", SIGNALS, "--no-check", *args,
            *(["--bench", bench] if bench else []))
    assert trace.exists(), r.out + r.err
    return trace


def _checks(out: str) -> dict[str, dict]:
    return {d["check"]: d for d in map(json.loads, out.splitlines()) if d["check"].endswith("vs reference")}


def test_a_run_against_itself_and_its_repeat_passes_every_comparison(hil, tmp_path):
    a, b = _trace(hil, tmp_path, "a"), _trace(hil, tmp_path, "b")
    r = hil("check", b, "--against", a, "--json")
    assert r.code == 0, r.out + r.err
    c = _checks(r.out)
    assert set(c) == {"path vs reference", "program time vs reference", "end vs reference", "signals vs reference"}
    assert all(x["ok"] and not x["skipped"] for x in c.values()), c
    assert c["path vs reference"]["value"] == 0.0 and c["program time vs reference"]["value"] == 0.0


def test_a_slower_run_of_the_same_path_fails_the_time_only(hil, tmp_path):
    a = _trace(hil, tmp_path, "a")
    b = _trace(hil, tmp_path, "b", PROGRAM, "--feed-override", "80")
    r = hil("check", b, "--against", a, "--json")
    assert r.code == 1, r.out + r.err
    c = _checks(r.out)
    assert c["path vs reference"]["ok"] and c["path vs reference"]["value"] <= 0.001
    t = c["program time vs reference"]
    assert not t["ok"] and "+" in t["detail"] and t["value"] > 0.01 * 1e3 * 5  # 80 % feed: the cuts take longer
    assert c["end vs reference"]["ok"] and c["signals vs reference"]["ok"]
    # a looser time tolerance lets it pass
    assert hil("check", b, "--against", a, "--time-tol", "60").code == 0


def test_a_moved_point_fails_the_path_at_its_line(hil, tmp_path):
    a = _trace(hil, tmp_path, "a")
    b = _trace(hil, tmp_path, "b", PROGRAM.replace("X30.", "X30.02"))  # 0.02 on the diameter: 0.01 mm of radius
    r = hil("check", b, "--against", a, "--json")
    assert r.code == 1
    p = _checks(r.out)["path vs reference"]
    assert not p["ok"] and p["value"] == pytest.approx(0.01, abs=2e-4), p
    assert p["line"] in (4, 5), p  # the moved X30. block or the Z-60. cut that runs at the moved X


def test_an_alarm_run_fails_end_path_and_signals_saying_what_differs(hil, tmp_path):
    a = _trace(hil, tmp_path, "a")
    b = _trace(hil, tmp_path, "b", PROGRAM, "--at", "t=1.0:set A1=1")
    r = hil("check", b, "--against", a)
    assert r.code == 1
    assert "FAIL  end vs reference" in r.out and "reason 'alarm' against 'completed'; alarm 'A1' against None" in r.out
    assert "FAIL  path vs reference" in r.out and "not run by this one" in r.out
    assert "FAIL  signals vs reference" in r.out


def test_bad_references_are_usage_errors(hil, tmp_path):
    a = _trace(hil, tmp_path, "a")
    junk = tmp_path / "junk.csv"
    junk.write_text("x,y\n1,2\n")
    r = hil("check", a, "--against", junk)
    assert r.code == 2 and "not a bench trace" in r.err
    mill = _trace(hil, tmp_path, "m", "G90 G01 X5. F3000\nM30\n", bench=str(ROOT / "benches" / "mill-3axis.toml"))
    r = hil("check", a, "--against", mill)
    assert r.code == 2 and "a reference must be a run of the same bench's axes" in r.err
    r = hil("check", a, "--against", a, "--path-tol", "-1")
    assert r.code == 2 and "--path-tol -1" in r.err
    assert "Traceback" not in r.err
