"""What local corner blends could buy on the issue-18 programs, with the axis jerk held (decision motion 40).

Each corner of a program's polyline gets the curvature-continuous blend of least curvature change
a local blend allows: a symmetric clothoid pair (curvature rising linearly to θ/L and back, so the
path is G2 and its axis jerk bounded), sized as LinuxCNC's tp sizes its blend arcs (tc/blendmath.c:
the tolerance, and no more than half of each segment). The speed in a blend is held to the
programmed feed, the centripetal acceleration v²·κ ≤ A and the centripetal jerk v³·|dκ/ds| ≤ J;
the lines between blends run at the feed. Speed changes cost no time here and the position filter
is off: the time printed is a LOWER bound for any planner that blends corners one by one.

    python benchmarks/bench_blend_bound.py

A, J: the X/Y limits of benches/mill-3axis.toml (5,000 mm/s², 250,000 mm/s³), all of them
("full", nothing left for the tangential profile) or the normal share LinuxCNC gives its blends
(√(1 − 0.5²) of the acceleration) and the same share of the jerk ("shared").
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from scipy.special import fresnel

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from benchmarks.bench_vs_linuxcnc import START, TOL, programs  # noqa: E402

A_AXIS, J_AXIS = 5000.0, 250_000.0
SHARE_N = math.sqrt(1.0 - 0.5 ** 2)  # LinuxCNC's BLEND_ACC_RATIO_NORMAL


def clothoid_pair(theta: float) -> tuple[float, float]:
    """(tangent length, deviation from the corner) of a symmetric clothoid pair turning by theta,
    each clothoid of unit length: both scale with the length L."""
    # A clothoid of length 1 turning by theta/2: s²/(2A²) = theta/2 at s = 1, so A² = 1/theta.
    a = math.sqrt(1.0 / theta)
    k = 1.0 / (a * math.sqrt(math.pi))  # fresnel(t) integrates cos(πt²/2): s = t·A·√π, here s = 1
    sf, cf = fresnel(k)  # scipy returns (S, C)
    x, y = a * math.sqrt(math.pi) * cf, a * math.sqrt(math.pi) * sf
    h = theta / 2.0
    t = x + y * math.tan(h)  # the pair's middle lies on the corner's axis of symmetry
    dev = math.hypot(x - t, y) * math.cos(h)  # distance of that middle from each leg
    return t, dev


def bound(points: np.ndarray, feed: float, tol: float, share: float) -> float:
    d = np.diff(points, axis=0)
    seg = np.linalg.norm(d, axis=1)
    keep = seg > 1e-9
    d, seg = d[keep], seg[keep]
    u = d / seg[:, None]
    acc, jerk = share * A_AXIS, share * J_AXIS
    time = 0.0
    used = np.zeros(len(seg))  # path each segment gives to the blends at its two ends
    for i in range(len(seg) - 1):
        theta = math.acos(max(-1.0, min(1.0, float(u[i] @ u[i + 1]))))
        if theta < 1e-9:
            continue
        t1, dev1 = clothoid_pair(theta)
        length = min(tol / dev1, 0.5 * min(seg[i], seg[i + 1]) / t1)  # L of each clothoid
        kmax, dk = theta / length, theta / length ** 2
        v = min(feed, math.sqrt(acc / kmax), (jerk / dk) ** (1.0 / 3.0))
        time += 2.0 * length / v  # the pair's path length is 2L
        used[i] += t1 * length
        used[i + 1] += t1 * length
    return time + float(np.sum(np.maximum(seg - used, 0.0))) / feed


def main() -> None:
    print(f"local clothoid-pair blends, N1.053 = {TOL} mm, filter off, speed changes free (a lower bound)")
    print(f"{'program':36s} {'feed bound':>10s} {'full A, J':>10s} {'shared':>10s}")
    for prog in programs():
        pts = np.array([START] + prog.points, dtype=float)
        f = prog.feed / 60.0
        print(f"{prog.name:36s} {prog.feed_limited():10.3f} {bound(pts, f, TOL, 1.0):10.3f} "
              f"{bound(pts, f, TOL, SHARE_N):10.3f}")


if __name__ == "__main__":
    main()
