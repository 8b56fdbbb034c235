"""M99 Call Stop (NC5 App. B: M2x026 "the NC system will slow down to stop and then stop all process when executing
M99", M3x047 "M99 Call Stop Status", decision mlc M25-1): a main program that loops with M99 — a bench's endurance
run — ends at its M99, at rest, once the MLC turns M2x026 ON, and M3x047 says so. Set here with `hil run --at`, as
an MLC or a panel would; checked on the trace's X and device columns in simulated time."""

from __future__ import annotations

import csv

import numpy as np

from tests.conftest import ROOT

# one pass: X (diameter) out to 30 and back to 20, 5 mm of radius each way at 50 mm/s (≈ 0.2 s + the ramps), a
# counter, M99. The trace's X is the machine's radius: 15 and 10.
LOOP = "G98 G01 X30. F3000\nX20.\n#100=#100+1\nM99\n"


def _bench(tmp_path, restarts: int = 1000):
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    text = text.replace("[params]\n", f'[params]\n"M99 main restarts" = {restarts}\n', 1)
    bench = tmp_path / "lathe.toml"
    bench.write_text(text)
    return bench


def _run(hil, tmp_path, *at: str, restarts: int = 1000):
    prog = tmp_path / "loop.nc"
    prog.write_text(LOOP)
    trace = tmp_path / "t.csv"
    args = [a for e in at for a in ("--at", e)]
    r = hil("run", str(prog), "--bench", _bench(tmp_path, restarts), "--no-check", "--trace",
            str(trace), "--trace-signals", "M21026,M31047,M31021,M31016", *args)
    assert trace.exists(), r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    cols = {k: np.array([float(x[k]) for x in rows]) for k in ("t", "X_cmd", "line", "M21026", "M31047", "M31021",
                                                               "M31016")}
    return r, cols


def _passes(x: np.ndarray) -> int:
    """Passes begun: the times X set off from 10 towards 15 (the first from its start at 60)."""
    out = (x[1:] > 10.0 + 1e-6) & (x[:-1] <= 10.0 + 1e-6)
    return 1 + int(out.sum())


def test_m2x026_ends_a_looping_main_program_at_its_m99_at_rest(hil, tmp_path):
    r, c = _run(hil, tmp_path, "t=1.2:set M21026=1")
    assert r.code == 0, r.out + r.err
    assert "result         completed" in r.out
    on = np.flatnonzero(c["M21026"] == 1)[0]
    assert abs(c["t"][on] - 1.2) < 0.0015
    # the loop runs on after M2x026 came ON only to the next M99 (the pass in progress), then X stands at the
    # M99's position (X20: 10 mm radius, end of line 2)
    runs = c["M31016"] == 1
    last_run = np.flatnonzero(runs)[-1]
    assert c["t"][last_run] - 1.2 < 0.35, c["t"][last_run]
    assert abs(c["X_cmd"][-1] - 10.0) < 1e-9 and np.ptp(c["X_cmd"][last_run:]) < 1e-9
    v = np.diff(c["X_cmd"]) / 0.001
    a = np.diff(v) / 0.001
    # reached by decelerating within X's acceleration (3000 mm/s²), not cut: at rest when the program ended
    assert np.abs(a).max() <= 3000.0 * 1.001 and np.abs(v[last_run:]).max() < 1e-9
    # M3x047 ON from the stop to the end of the run; the plain program end M3x021 stays OFF (it was no M02/M30)
    status = np.flatnonzero(c["M31047"] == 1)
    assert len(status) and status[0] > last_run and status[-1] == len(c["t"]) - 1
    assert not (c["M31021"] == 1).any()
    # the first pass (X from 60 to 15 and back to 10: ≈ 1.1 s) ended at an M99 before 1.2 s and the program ran
    # again; the M99 that ends the second pass is the first one reached with M2x026 ON
    assert _passes(c["X_cmd"]) == 2


def test_without_m2x026_the_loop_runs_to_the_emulators_restart_limit(hil, tmp_path):
    r, c = _run(hil, tmp_path, restarts=3)
    assert r.code == 0, r.out + r.err
    assert _passes(c["X_cmd"]) == 4  # the program and its 3 restarts (decision A22), no M99 stop
    assert not (c["M31047"] == 1).any() and (c["M31021"] == 1).any()  # a plain end: M3x021, no M3x047


def test_m2x026_set_from_the_start_stops_at_the_first_m99(hil, tmp_path):
    r, c = _run(hil, tmp_path, "cycle=1:set M21026=1")
    assert r.code == 0, r.out + r.err
    assert _passes(c["X_cmd"]) == 1
    assert abs(c["X_cmd"][-1] - 10.0) < 1e-9 and (c["M31047"][-1] == 1)


def test_m2x026_turned_off_again_before_the_m99_is_read_lets_the_loop_run_on(hil, tmp_path):
    # ON for 2 ms in the middle of a long X move (the M99 is read at the move's end): the level the channel sees
    # when it reads the M99 counts, as for the program-flow switches (single block, optional stop)
    r, c = _run(hil, tmp_path, "t=0.30:set M21026=1", "t=0.302:set M21026=0", restarts=2)
    assert r.code == 0, r.out + r.err
    assert _passes(c["X_cmd"]) == 3 and not (c["M31047"] == 1).any()
