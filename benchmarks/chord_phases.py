"""Where a chord circle's time over the feed-limited bound goes, phase by phase (issue 18, decision motion 52).

Runs `bench_vs_linuxcnc.chord_circle(r)` offline on benches/mill-3axis.toml and prints, for the filtered
output and for the raw interpolation that enters the filter, the time lost against the feed (cycle
count minus path length / feed) at: the end of the lead-in (the start and the braking into the 90°
corner), 2 mm past the corner (the speed-up out of it), 2 mm before the end (the circle) and the end
(the stop, and the filter's settling). Simulated 1 ms cycles; asserts nothing.

    python benchmarks/chord_phases.py [RADIUS ...]      (default 10 5 2)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from benchmarks.bench_vs_linuxcnc import BENCH, START, chord_circle  # noqa: E402
from hil.bench_file import load_bench_file  # noqa: E402
from nc.motion.offline import run  # noqa: E402
from nc.motion.planner import Planner  # noqa: E402
from nc.moves import Move  # noqa: E402
from tests.motion_helpers import polyline_deviation  # noqa: E402


def moves(points: list) -> list[Move]:
    pts = [START] + points
    return [Move("line", k, "", dict(zip("XYZ", pts[k - 1])), dict(zip("XYZ", pts[k])), dict(zip("XYZ", pts[k])),
                 feed=3000.0, plane=("X", "Y")) for k in range(1, len(pts))]


def lost(P: np.ndarray, feed: float, marks: list[float]) -> list[float]:
    """ms lost against the feed when the path length first reaches each mark, and at the end."""
    mv = np.nonzero(np.any(np.abs(np.diff(P, axis=0)) > 1e-9, axis=1))[0]
    Q = P[mv[0]:mv[-1] + 2]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])
    late = (np.arange(len(s)) * 0.001 - s / feed) * 1000.0
    marks = [m if m >= 0 else s[-1] + m for m in marks]
    return [float(late[min(np.searchsorted(s, m), len(s) - 1)]) for m in marks] + [float(late[-1])]


def main() -> None:
    radii = [float(a) for a in sys.argv[1:]] or [10.0, 5.0, 2.0]
    cfg = load_bench_file(BENCH).motion_config()
    print("ms lost against the feed: lead-in end | +2 mm past the corner | 2 mm before the end | end")
    for r in radii:
        prog = chord_circle(r)
        raw: list[np.ndarray] = []
        step = Planner._step_path

        def spy(self):  # the raw interpolation, before the filter
            sp = step(self)
            raw.append(sp.positions.copy())
            return sp

        Planner._step_path = spy
        try:
            c0 = time.process_time()
            st = run(moves(prog.points), cfg, dict(zip("XYZ", START)))
            cpu = time.process_time() - c0
        finally:
            Planner._step_path = step
        feed = prog.feed / 60.0
        marks = [r, r + 2.0, -2.0]
        out = lost(st.positions, feed, marks)
        inp = lost(np.vstack([st.positions[:1], np.array(raw)]), feed, marks)
        dev = polyline_deviation(st.positions, [START] + prog.points)
        print(f"r{r:g}: bound {prog.feed_limited():.3f} s, output {st.time:.3f} s, deviation {dev:.4f} mm, "
              f"CPU {cpu:.2f} s")
        print("   output  " + " | ".join(f"{x:6.1f}" for x in out))
        print("   raw     " + " | ".join(f"{x:6.1f}" for x in inp))


if __name__ == "__main__":
    main()
