"""Arcs on the mill bench run at the speed their limits allow (session 20, decisions motion 64 and 65).

What a user checks: `hil run` of a G2/G3 program on benches/mill-3axis.toml, timed in simulated cycles
(first to last change of the commanded position), the bench's checks passing, and every commanded point
on the circle within N1.053 (0.02 mm) of its radius. Before decision 64 the filter's radius shrink was
bounded with (T1+T2)² and before decision 65 an arc's tangential acceleration with a 0.075 share of the
jerk: R10 at F6000 took 3.059 s for three circles (LinuxCNC 2.9: 2.065 s), R5 at F3000 0.915 s (0.775 s).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from benchmarks.bench_vs_linuxcnc import BENCH, hil_trace

TOL = 0.02  # N1.053 of the bench (mm)


def run(tmp_path: Path, text: str) -> tuple[int, str, np.ndarray]:
    prog = tmp_path / "arc.nc"
    prog.write_text(text)
    r, pos = hil_trace(prog, BENCH)
    return r.returncode, r.stdout, pos


def motion_time(pos: np.ndarray) -> float:
    moving = np.nonzero(np.any(np.abs(np.diff(pos, axis=0)) > 1e-9, axis=1))[0]
    return (int(moving[-1]) + 1 - int(moving[0])) * 0.001


@pytest.mark.parametrize("radius, feed, turns, limit", [(10.0, 6000.0, 3, 2.25), (5.0, 3000.0, 1, 0.80)])
def test_circle_time_within_limits_and_tolerance(tmp_path, radius, feed, turns, limit):
    text = "\n".join(["G21 G17 G90 G94", f"G1 X{radius:.1f} Y0. F{feed:.0f}."]
                     + [f"G3 X{radius:.1f} Y0. I{-radius:.1f} J0." for _ in range(turns)] + ["M30", ""])
    rc, out, pos = run(tmp_path, text)
    assert rc == 0, out  # every check of the bench: velocity, acceleration, jerk, contour, following error
    t = motion_time(pos)
    assert t <= limit, f"{turns} circle(s) R{radius:g} F{feed:g}: {t:.3f} s (main before decisions 64/65: slower)"
    # the circle itself (after the lead-in reached (r, 0) and left it): radius within N1.053
    on_arc = np.nonzero(pos[:, 1] > 0.5)[0]
    ring = pos[on_arc[0]:on_arc[-1] + 1]
    r = np.hypot(ring[:, 0], ring[:, 1])
    away = np.hypot(ring[:, 0] - radius, ring[:, 1]) > 0.5  # off the lead-in's corner
    assert np.abs(r[away] - radius).max() <= TOL
    assert np.allclose(pos[:, 2], 100.0)
    # and the arc is run near its feed: a user sees the programmed speed on the circle
    v = np.linalg.norm(np.diff(ring, axis=0), axis=1) * 1000.0
    assert v.max() >= 0.95 * min(feed / 60.0, math.sqrt(24 * TOL * radius / (2 * (16 * 16 - 1) * 1e-6)))  # decision 64, N1.036 = N1.037 = 16 ms
