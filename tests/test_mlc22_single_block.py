"""Single block M2x008 stops after every block, an M/S/T-only block included, once its handshake is finished
(App. B.2.1.1: "the program stops after one block is executed"; decision M22-2). Read from the lathe bench's trace:
the block stop relay M3x024, the M strobe M3x064 and the M code D3x048, per line, with `hil run --at`."""

from __future__ import annotations

import csv

STARTS = [f"t={t}.0:cycle-start" for t in range(1, 7)]


def _stops(hil, tmp_path, program: str, starts: list[str]):
    """(line, M code at the stop, strobe at the stop) for each single-block stop, and the run's output."""
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    trace = tmp_path / "p.csv"
    args = [a for e in ["cycle=1:set M21008=1", *starts] for a in ("--at", e)]
    r = hil("run", str(prog), "--no-check", "--trace", str(trace), "--trace-signals", "M31024,M31064,D31048", *args)
    assert r.code == 0 and "result         completed" in r.out, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    stops = [(int(b["line"]), b["D31048"], b["M31064"]) for a, b in zip(rows, rows[1:])
             if a["M31024"] == "0" and b["M31024"] == "1"]
    return stops, r


def test_an_m_code_only_block_is_a_block_stopped_after_once_its_finish_is_in(hil, tmp_path):
    stops, _ = _stops(hil, tmp_path, "G98 G01 X40. F3000\nM08\nZ90.\nM30\n", STARTS[:3])
    # the stop at line 2 comes after M08's handshake: the strobe is down, D3x048 still shows the code
    assert stops == [(1, "0", "0"), (2, "8", "0"), (3, "8", "0")]


def test_m03_with_s_on_one_line_is_one_block_and_one_stop(hil, tmp_path):
    stops, r = _stops(hil, tmp_path, "G98 G01 X40. F3000\nM03 S1000\nZ90.\nM30\n", STARTS[:3])
    assert [s[0] for s in stops] == [1, 2, 3]  # line 2 hands S1000 and M03, and stops once, after both
    assert "never triggered" not in r.out


def test_a_code_on_a_motion_line_belongs_to_that_block(hil, tmp_path):
    stops, _ = _stops(hil, tmp_path, "G98 G01 X40. F3000 M08\nZ90.\nM30\n", STARTS[:2])
    assert [s[0] for s in stops] == [1, 2]


def test_the_cycle_start_releasing_m00_is_that_blocks_stop(hil, tmp_path):
    # the M00 hold waits for a cycle start; under single block that press ends the block: no second stop at line 2.
    # (The press at the line-1 stop reads M00 in its own scan and releases it at once, decision bench B56.)
    stops, r = _stops(hil, tmp_path, "G98 G01 X40. F3000\nM00\nZ90.\nM30\n", STARTS[:2])
    assert [s[0] for s in stops] == [1, 3]
    assert "never triggered" not in r.out
