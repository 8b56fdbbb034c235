"""The filter corners' running sums (decision bench B189): each junction's Σ|Δu| per axis, Σ|Δu| norms and signed
Σ Δu per axis are C doubles in a row buffer beside the junction history (`FilterCorners._cs`, row k + `_cs_off` for
hist[k]), no longer tuples on each Block. The rows must follow the history through its drops from the front (TRIM),
the buffer's moves and growths and the stops that clear it: every row held after every push is the sum the tuples
held, the same additions in the same order, bit for bit, and the setpoints stay those of tests/planner_digests.py."""

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

# Lines, exact stops (G09: a stop clears the history) and arcs, then the CAM program's short segments
STOPS = """G90 G17 G94 G64 G01 F3000
G00 X0 Y0 Z5
G01 X10 Y2
G01 X20 Y-1
G09 G01 X30 Y4
G02 X40 Y4 R6
G01 X41 Y9 Z4
G04 X0.1
G01 X50 Y0 Z5
G03 X60 Y0 R5
G01 X61 Y1
M30
"""


def _check(text: str, trim: int) -> tuple[int, int, int]:
    """Runs `text` on the 3-axis mill with TRIM = trim, checking every held row after every push against sums kept
    here as the tuples were made; returns (pushes checked, most rows held, buffer moves and growths)."""
    cfg = load_bench_file(BENCH).motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(parse_program(text, name="t.nc"))
    ref: dict[int, tuple[float, ...]] = {}  # sequence number -> the row as the tuples held it (cum, then scum)
    seen = {"pushes": 0, "held": 0, "moves": 0}

    class Watched(blending.FilterCorners):  # the look-ahead makes this one instead (compiled methods stay, B115)
        def window(self, blocks):
            hist = self._hist
            h0, last, off0, size0 = self._h0, len(hist), self._cs_off, len(self._cs)
            out = super().window(blocks)
            j = blocks[-2] if len(blocks) >= 2 else None
            if j is None or j.du is None:
                return out  # nothing joined (a stop clears the history)
            seq0, k_j = self._seq0, len(self._hist) - 1
            # J's sums from the junction before it where that one was within reach, else from zeros: the tuples'
            # rule, `prev + d` per axis (Python floats: the same IEEE additions)
            prev = ref[seq0 + k_j - 1] if last > h0 else (0.0,) * self._csw
            steps = tuple(j.du) + (j.du_n,) + tuple(j.dv)
            ref[seq0 + k_j] = tuple(p + d for p, d in zip(prev, steps))
            w, off = self._csw, self._cs_off
            for k in range(self._h0 - 1 if self._h0 > 0 else 0, k_j + 1):
                row = tuple(self._cs[(k + off) * w + i] for i in range(w))
                assert row == ref[seq0 + k], (seq0 + k, row, ref[seq0 + k])
            seen["pushes"] += 1
            seen["held"] = max(seen["held"], k_j + 1)
            seen["moves"] += self._cs_off < off0 or len(self._cs) != size0  # rows moved to the front, or grown
            return out

    old = blending.TRIM
    blending.TRIM, lookahead.FilterCorners = trim, Watched
    try:
        st = run(events, cfg, {"X": 0.0, "Y": 0.0, "Z": 100.0})
    finally:
        blending.TRIM, lookahead.FilterCorners = old, blending.FilterCorners
    assert not st.alarms
    return seen["pushes"], seen["held"], seen["moves"]


def test_rows_follow_the_history_through_drops_and_moves():
    pushes, held, moves = _check(cam_program(1500), 8)  # drops every few pushes: the buffer moves its rows
    assert pushes > 1400 and held > 256 and moves >= 2


def test_rows_grow_with_a_history_that_keeps_every_junction():
    pushes, held, moves = _check(cam_program(1500), 10 ** 9)  # never drops: the buffer grows
    assert pushes > 1400 and held > 1400 and moves >= 2


def test_rows_start_from_zero_after_a_stop():
    pushes, held, moves = _check(STOPS, blending.TRIM)
    assert pushes >= 6
