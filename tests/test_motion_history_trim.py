"""The filter corners' junction history (nc.motion.blending.FilterCorners) drops the junctions no scan reads any
more a few at a time (issue 17, session 18), not 4,096 at once: on the 5,000-block CAM program the setpoints are
those of a history that keeps every junction (whose scans answer as the bulk drop's did) bit for bit, the history
stays bounded, and no push drops more than a few dozen junctions (the bulk drop freed 4,096 blocks in one cycle)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import nc.motion.blending as blending
import nc.motion.lookahead as lookahead
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from nc.interp import Interpreter
from nc.motion.offline import run
from nc.profiles import make_profile
from nc.program.blocks import parse_program

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def _run(trim: int) -> tuple[np.ndarray, int, int, int]:
    """(setpoints, most junctions held, most dropped by one push, the bulk drop's cut) with TRIM = trim."""
    cfg = load_bench_file(BENCH).motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(
        parse_program(cam_program(5000), name="cam.nc"))
    seen = {"held": 0, "drop": 0, "bulk": 0}

    # A subclass the look-ahead makes instead (the compiled FilterCorners' methods cannot be replaced, B115)
    class Watched(blending.FilterCorners):
        def window(self, blocks):
            seq0 = self._seq0
            out = super().window(blocks)
            seen["held"] = max(seen["held"], len(self._hist))
            seen["drop"] = max(seen["drop"], self._seq0 - seq0)
            seen["bulk"] = max(seen["bulk"], self._seq_v)
            return out

    old = blending.TRIM
    blending.TRIM, lookahead.FilterCorners = trim, Watched
    try:
        st = run(events, cfg, {"X": 0.0, "Y": 0.0, "Z": 100.0})
    finally:
        blending.TRIM, lookahead.FilterCorners = old, blending.FilterCorners
    assert not st.alarms
    return st.positions, seen["held"], seen["drop"], seen["bulk"]


def test_history_drops_a_few_junctions_at_a_time_with_the_same_setpoints():
    pos, held, drop, bulk = _run(blending.TRIM)
    ref, ref_held, ref_drop, ref_bulk = _run(10 ** 9)  # never drops: every junction kept
    assert np.array_equal(pos, ref)
    assert bulk == ref_bulk > 0  # the bulk drop's cut was passed, and the scans still answer by it
    assert ref_drop == 0 and ref_held > blending.BULK
    assert 0 < drop <= 4 * blending.TRIM
    assert held < ref_held // 2
