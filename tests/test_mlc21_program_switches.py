"""Program-flow switches of App. B.2.1.1 set by the MLC (here `hil run --at`, as a panel would) and the status
relays of B.2.2.1 that answer them, read from the trace's device columns on the lathe bench: single block M2x008
→ M3x024 / M3x039, and the M/S/T lock M2x011 (no strobe, the motion runs; decision H9)."""

from __future__ import annotations

import csv

PROGRAM = "G98 G01 X40. F3000\nM08\nZ90.\nM30\n"


def _changes(rows, cols):
    """(t, line, values…) at each change of the columns."""
    out, prev = [], None
    for r in rows:
        k = tuple(r[c] for c in cols)
        if k != prev:
            out.append((float(r["t"]), int(r["line"])) + k)
            prev = k
    return out


def _run(hil, tmp_path, signals: str, *at: str):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    trace = tmp_path / "p.csv"
    args = [a for e in at for a in ("--at", e)]
    r = hil("run", str(prog), "--no-check", "--trace", str(trace), "--trace-signals", signals, *args)
    assert r.code == 0, r.out + r.err
    return r, list(csv.DictReader(trace.open()))


def test_single_block_stops_after_each_block_until_cycle_start(hil, tmp_path):
    # Revised by decision M22-2 (it pinned M21-6's stop after motion blocks only): the M08-only line 2 is a block
    # too, so the channel now stops after lines 1, 2 (its handshake finished first) and 3.
    r, rows = _run(hil, tmp_path, "M31024,M31039,M31016", "cycle=1:set M21008=1", "t=1.0:cycle-start",
                   "t=2.0:cycle-start", "t=3.0:cycle-start")
    assert "result         completed" in r.out
    stops = [(t, line) for t, line, hold, done, run in _changes(rows, ("M31024", "M31039", "M31016"))
             if hold == "1"]
    # stopped after line 1 (X40), line 2 (M08) and line 3 (Z90); M3x024 and M3x039 together, "running" OFF meanwhile
    assert [line for _, line in stops] == [1, 2, 3]
    for r_ in rows:
        if r_["M31024"] == "1":
            assert r_["M31039"] == "1" and r_["M31016"] == "0"
    # each stop lasts until the cycle start of the panel (1.0 s, 2.0 s, 3.0 s): the next block starts in that scan
    ends = [float(r_["t"]) for a, r_ in zip(rows, rows[1:]) if a["M31024"] == "1" and r_["M31024"] == "0"]
    assert [round(t, 3) for t in ends] == [1.0, 2.0, 3.0]


def test_mst_lock_hands_no_code_to_the_mlc_and_the_motion_runs(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "M21011,M31064,D31048", "cycle=1:set M21011=1")
    assert "result         completed" in r.out and "X 20.0000  Z 90.0000" in r.out
    assert all(r_["M31064"] == "0" and r_["D31048"] == "0" for r_ in rows)  # M08: no strobe, no M data
    assert {2, 3} <= {int(r_["line"]) for r_ in rows}
    _, unlocked = _run(hil, tmp_path, "M31064,D31048")
    assert any(r_["M31064"] == "1" and r_["D31048"] == "8" for r_ in unlocked)  # without the lock M08 is handed
