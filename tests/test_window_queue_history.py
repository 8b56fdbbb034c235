"""FilterCorners.window walks the queued junctions through its history list, not through the queue (issue 17,
decision bench B171): that holds only while the queue and the history run side by side, each queued block that
has a junction in the history at the index `last + 2 - len(blocks)` places before it. Pinned here on the CAM
program (corner blends join the queue through nc.motion.planner_corners) and on a mill program with stops (a stop
clears the history): after every push the history's suffix is the queue's blocks, the same objects in order."""

from __future__ import annotations

from pathlib import Path

import nc.motion.blending as blending
import nc.motion.lookahead as lookahead
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from nc.interp import Interpreter
from nc.motion.offline import run
from nc.profiles import make_profile
from nc.program.blocks import parse_program

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"

STOPS = """G21 G90 G17 G64
G0 X0 Y0 Z5
G1 Z0 F600
G1 X10 Y0 F3000
G1 X20 Y3
G1 X30 Y0
G3 X40 Y0 I5 J0
G1 X50 Y2
G4 P100
G1 X60 Y0
G1 X70 Y4
G1 X80 Y0
G9 G1 X90 Y3
G1 X100 Y0
G1 X110 Y5
G0 Z5
M30
"""


def _walk(text: str) -> tuple[int, int, int]:
    """(pushes checked, the most queued blocks matched in one, pushes with blocks queued before a stop) for the program; asserts the alignment each push."""
    cfg = load_bench_file(BENCH).motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(parse_program(text, name="t.nc"))
    seen = {"pushes": 0, "most": 0, "behind": 0}

    class Watched(blending.FilterCorners):  # the look-ahead makes this instead (compiled methods stay, B115)
        def window(self, blocks):
            out = super().window(blocks)
            hist = self._hist
            if len(blocks) >= 2 and hist and hist[-1] is blocks[-2]:
                last = len(hist) - 1
                lo_q = last + 2 - len(blocks)  # hist[lo_q] is blocks[0]'s junction
                lo = max(lo_q, 0)
                for k in range(lo, last + 1):
                    assert hist[k] is blocks[k - lo_q], (seen["pushes"], k)
                seen["pushes"] += 1
                seen["most"] = max(seen["most"], last + 1 - lo)
                seen["behind"] += lo_q < 0  # queued blocks from before a stop: not in the history
            return out

    lookahead.FilterCorners = Watched
    try:
        st = run(events, cfg, {"X": 0.0, "Y": 0.0, "Z": 100.0})
    finally:
        lookahead.FilterCorners = blending.FilterCorners
    assert not st.alarms
    return seen["pushes"], seen["most"], seen["behind"]


def test_queue_and_history_side_by_side_on_the_cam_program():
    pushes, most, _ = _walk(cam_program(600))
    assert pushes > 500 and most > 10  # every push's junction joined, a long queue matched


def test_queue_and_history_side_by_side_across_stops():
    pushes, most, behind = _walk(STOPS)
    assert pushes >= 8 and most >= 3 and behind > 0
