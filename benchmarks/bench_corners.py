"""Corners and short segments with and without the position filter (N1.036/N1.037): simulated
execution time against the feed-limited time, and planning throughput. Prints, asserts nothing.
Run: python benchmarks/bench_corners.py"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from nc.motion.offline import run  # noqa: E402
from nc.motion.planner import Planner  # noqa: E402
from tests.motion_helpers import AX, circle_chords, lines, mill_cfg, worst_ratio  # noqa: E402
from benchmarks.bench_motion import cam_moves, plan_only  # noqa: E402


def configs():
    yield "no filter", mill_cfg()
    for ms in (8.0, 16.0):
        for tol in (None, 0.02):
            yield (f"filter {ms:g}+{ms:g} ms, tol {tol if tol else 'none'}",
                   mill_cfg(filter_time=ms / 1000, filter_scurve=ms / 1000, path_tolerance=tol, min_segment_cycles=0.25))


def programs():
    square = [(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0), (0, 0, 0)]
    rng = np.random.default_rng(5)
    s = np.cumsum(rng.uniform(0.01, 0.1, 1500))
    cam = [(0.0, 0.0, 0.0)] + [(x, 3.0 * math.sin(x / 4.0), 0.2 * math.cos(x / 3.0) - 0.2) for x in s]
    ring = circle_chords(2.0, 0.05)
    for name, pts in (("square 10 mm, F3000", square), ("CAM 0.01-0.1 mm, F3000", cam),
                      ("circle r2 of 0.05 chords, F3000", ring)):
        length = float(np.sum(np.linalg.norm(np.diff(np.array(pts, float), axis=0), axis=1)))
        yield name, pts, length / 50.0


def main() -> None:
    for name, pts, ideal in programs():
        print(f"{name}: feed-limited {ideal:.3f} s")
        for label, cfg in configs():
            st = run(lines(pts, 3000), cfg, dict(zip(AX, pts[0])))
            r = worst_ratio(st, cfg)
            print(f"  {label:28s} {st.time:7.3f} s = {st.time / ideal:5.2f}x  "
                  f"peak v/a/j of limit {r['v']:.2f}/{r['a']:.2f}/{r['j']:.2f}")
    for label, cfg in configs():
        pl = Planner(cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
        n = 50_000
        t = time.perf_counter()
        plan_only(pl, cam_moves(n))
        w = time.perf_counter() - t
        print(f"planning {n} CAM segments, {label:28s}: {n / w:8,.0f} blocks/s")


if __name__ == "__main__":
    main()
