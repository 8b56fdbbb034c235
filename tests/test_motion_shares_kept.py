"""The jerk-factor scan's kept verdicts (nc.motion.shares._verdicts, issue 17 session 11) give, at every scan of
a run, the answer the walk over every junction gives (`shares.WALK`, the code before them), and the same
setpoints bit for bit: on the CAM program (with feed override changes, which change every cap), and on a mill
program of arcs, exact stops, a dwell and short corners (the arcs' and the stops' early answers)."""

from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from pathlib import Path

import numpy as np
import pytest

import nc.motion.shares as shares
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from nc.interp import Interpreter
from nc.motion.offline import run
from nc.profiles import make_profile
from nc.program.blocks import parse_program

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def _mixed() -> str:
    lines = ["G90 G17 G94 G01 F2400 X0 Y0"]
    for k in range(1, 121):
        x, y = 0.05 * k, 0.02 * math.sin(k / 3.0)
        lines.append(f"X{x:.4f} Y{y:.4f}")
        if k % 40 == 0:
            lines.append(f"G02 X{x + 1.0:.4f} Y{y:.4f} I0.5 J0")
            lines.append(f"G03 X{x + 2.0:.4f} Y{y:.4f} I0.5 J0")
            lines.append(f"G01 X{x:.4f} Y{y:.4f}")
        if k == 60:
            lines.append("G09 X3.2 Y0.1")
        if k == 90:
            lines.append("G04 P50")
    lines.append("M30")
    return "\n".join(lines) + "\n"


def _run(text: str, overrides: dict[int, float], checked: list[int]) -> np.ndarray:
    """The run's setpoints; every scan is made both ways and must agree (`checked`: scans, junctions read
    in the reaches, verdicts found again)."""
    scan = shares._scan
    found = [0]

    def both(fc, blocks, pos, run_end, reach, closed, v_stop=-1.0):
        shares.WALK = True
        try:
            ref = scan(fc, blocks, pos, run_end, reach, closed, v_stop)
        finally:
            shares.WALK = False
        # the verdicts the kept scan finds again: from the reach's first one not kept on
        k_lo, k_hi = bisect_left(fc._hist_s, pos - reach), bisect_right(fc._hist_s, run_end + reach)
        part = fc._sc[k_lo:k_hi]
        found[0] += len(part) - (part.index(None) if None in part else len(part))
        got = scan(fc, blocks, pos, run_end, reach, closed, v_stop)
        assert got == ref
        checked[0] += 1
        checked[1] += sum(1 for s in fc._hist_s if pos - reach <= s <= run_end + reach)
        return got

    cfg = load_bench_file(BENCH).motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(parse_program(text, name="t.nc"))

    def on_cycle(n, ch):
        if n in overrides:
            ch.planner.feed_override = overrides[n]

    shares.CHECK = both  # jerk_factor's scans go through `both` (the scan is a C call where compiled)
    try:
        st = run(events, cfg, {"X": 0.0, "Y": 0.0, "Z": 100.0}, on_cycle=on_cycle)
    finally:
        shares.CHECK = None
    checked[2] = found[0]
    assert not st.alarms
    return st.positions


def _walked(text: str, overrides: dict[int, float]) -> np.ndarray:
    cfg = load_bench_file(BENCH).motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(parse_program(text, name="t.nc"))

    def on_cycle(n, ch):
        if n in overrides:
            ch.planner.feed_override = overrides[n]

    shares.WALK = True
    try:
        return run(events, cfg, {"X": 0.0, "Y": 0.0, "Z": 100.0}, on_cycle=on_cycle).positions
    finally:
        shares.WALK = False


@pytest.mark.parametrize("name", ["cam", "cam overrides", "mixed", "mixed overrides"])
def test_kept_verdicts_answer_as_the_walk(name):
    text = _mixed() if name.startswith("mixed") else cam_program(1200)
    overrides = {300: 0.8, 700: 1.2, 900: 1.0} if name.endswith("overrides") else {}
    checked = [0, 0, 0]
    pos = _run(text, overrides, checked)
    scans, read, found = checked
    assert scans > 100
    if name.startswith("cam"):
        # the point of keeping them: most verdicts of a reach were found at an earlier scan
        assert found < 0.25 * read
    assert np.array_equal(pos, _walked(text, overrides))
