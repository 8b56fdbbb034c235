"""The block skip switch M2x010 (NC5 App. B.2.1.1 "Single Block Skip ('/')": the program skips the block
containing '/' when this function is enabled; R/W, MLC → NC) as an MLC drives it during `hil run` on the lathe
bench: the '/' blocks read after the scan that turned it ON are skipped, those read before run (decision M21-1)."""

from __future__ import annotations

import csv

from tests.conftest import ROOT

# X in diameter: X40 → machine X 20, X36 → 18, X20 → 10 (the lathe bench starts at X 60, Z 100)
PROGRAM = "G98 G00 X40. Z10.\n/G01 X36. F600\nG01 Z5. F600\n{halt}\n/G01 X20.\nG01 Z0.\nM30\n"
SKIP_MLC = '''from mlc import lathe
SCAN_ON_CHANGE = True
def setup(mlc):
    lathe.setup(mlc)
    mlc.set("BLOCK_SKIP")  # the panel's block skip switch ON at power-on
def scan(mlc):
    lathe.scan(mlc)
'''


def _run(hil, tmp_path, *args: str, halt: str = "G01 Z4.9", bench: str | None = None):
    prog = tmp_path / "skip.nc"
    prog.write_text(PROGRAM.format(halt=halt))
    trace = tmp_path / "skip.csv"
    extra = ("--bench", bench) if bench else ()
    r = hil("run", str(prog), *extra, "--no-check", "--trace", str(trace), "--trace-signals", "M21010", *args)
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    return r, rows, sorted({int(row["line"]) for row in rows}), [float(row["X_act"]) for row in rows]


def test_switch_off_runs_every_slash_block(hil, tmp_path):
    _, rows, lines, x = _run(hil, tmp_path, "--mlc", "lathe")
    assert {2, 5} <= set(lines) and abs(min(x) - 10.0) < 1e-2
    assert all(row["M21010"] == "0" for row in rows)


def test_switch_on_from_the_mlc_skips_the_slash_blocks(hil, tmp_path):
    mlc = tmp_path / "skip_mlc.py"
    mlc.write_text(SKIP_MLC)
    r, rows, lines, x = _run(hil, tmp_path, "--mlc", str(mlc))
    assert 2 not in lines and 5 not in lines, lines
    assert abs(min(x) - 20.0) < 1e-2  # neither X36 (18) nor X20 (10) was reached
    assert "X 20.0000" in r.out  # final machine position: the X40 of line 1
    assert all(row["M21010"] == "1" for row in rows)


def _halt_bench(tmp_path) -> str:
    """The lathe bench with M200 as a preview-halt M code (N1.118 = 200, N1.119 = 1): the NC reads nothing after it
    until the motion before it has run out, so the switch's moment is the user's, not the look-ahead's."""
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    text = text.replace("[params]\n", '[params]\n"N1.118" = 200\n"N1.119" = 1\n', 1)
    path = tmp_path / "halt.toml"
    path.write_text(text)
    return str(path)


def test_switch_turned_on_mid_program_skips_the_blocks_read_after_it(hil, tmp_path):
    bench = _halt_bench(tmp_path)
    _, rows, lines, x = _run(hil, tmp_path, "--at", "line=3:set M21010=1", halt="M200", bench=bench)
    # line 2 was read (and run) before the switch; line 5, read after M200 once the switch was ON, was skipped
    assert 2 in lines and 5 not in lines, lines
    assert abs(min(x) - 18.0) < 1e-2
    first_on = next(i for i, row in enumerate(rows) if row["M21010"] == "1")
    assert int(rows[first_on]["line"]) == 3


def test_switch_turned_on_after_the_block_was_read_is_too_late(hil, tmp_path):
    bench = _halt_bench(tmp_path)
    _, _, lines, x = _run(hil, tmp_path, "--at", "line=5:set M21010=1", halt="M200", bench=bench)
    assert 5 in lines and abs(min(x) - 10.0) < 1e-2
