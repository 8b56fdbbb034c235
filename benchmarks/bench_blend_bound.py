"""What local corner blends could buy on the issue-18 programs, with the axis jerk held (decision motion 40).

Each corner of a program's polyline gets the curvature-continuous blend of least curvature change
a local blend allows: a symmetric clothoid pair (curvature rising linearly to θ/L and back, so the
path is G2 and its axis jerk bounded), sized as LinuxCNC's tp sizes its blend arcs (tc/blendmath.c:
the tolerance, and no more than half of each segment). The speed in a blend is held to the
programmed feed, the centripetal acceleration v²·κ ≤ A and the centripetal jerk v³·|dκ/ds| ≤ J;
the lines between blends run at the feed. Speed changes cost no time here and the position filter
is off: the time printed is a LOWER bound for any planner that blends corners one by one.

    python benchmarks/bench_blend_bound.py
    python benchmarks/bench_blend_bound.py --crossfade V   # the filter share λ on a blended path at V mm/s

A, J: the X/Y limits of benches/mill-3axis.toml (5,000 mm/s², 250,000 mm/s³), all of them
("full", nothing left for the tangential profile) or the normal share LinuxCNC gives its blends
(√(1 − 0.5²) of the acceleration) and the same share of the jerk ("shared").
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from scipy.special import fresnel

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from benchmarks.bench_vs_linuxcnc import START, TOL, cam_polyline, cam_surface, programs  # noqa: E402
from tests.motion_helpers import polyline_deviation  # noqa: E402

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


# ---- the filter share on a blended path (decision motion 40 b) -----------------------------------
def unit_clothoid(theta: float, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) at s (0 … 1) of the unit-length clothoid of a pair turning by theta, heading 0 at s = 0."""
    a = math.sqrt(1.0 / theta)
    sf, cf = fresnel(s / (a * math.sqrt(math.pi)))
    return a * math.sqrt(math.pi) * cf, a * math.sqrt(math.pi) * sf


def blended_path(points: np.ndarray, tol: float) -> list[tuple]:
    """The polyline as pieces ("line", length, (start, u)) and ("blend", 2L, geometry): a clothoid
    pair at every corner, sized as `bound` sizes it."""
    d = np.diff(points, axis=0)
    seg = np.linalg.norm(d, axis=1)
    u = d / seg[:, None]
    trim = np.zeros((len(seg), 2))
    blends: list[tuple | None] = []
    for i in range(len(seg) - 1):
        theta = math.acos(max(-1.0, min(1.0, float(u[i] @ u[i + 1]))))
        if theta < 1e-7:
            blends.append(None)
            continue
        t1, dev1 = clothoid_pair(theta)
        length = min(tol / dev1, 0.5 * min(seg[i], seg[i + 1]) / t1)
        trim[i, 1] = trim[i + 1, 0] = t1 * length
        blends.append((theta, length, t1 * length))
    pieces: list[tuple] = []
    for i in range(len(seg)):
        pieces.append(("line", max(seg[i] - trim[i].sum(), 0.0), (points[i] + u[i] * trim[i, 0], u[i])))
        if i < len(seg) - 1 and blends[i] is not None:
            theta, length, t = blends[i]
            u1, u2, vx = u[i], u[i + 1], points[i + 1]
            n1 = u2 - (u1 @ u2) * u1  # towards the turn, normal to each leg
            n2 = (u1 @ u2) * u2 - u1
            pieces.append(("blend", 2.0 * length, (theta, length, vx - u1 * t, u1, n1 / np.linalg.norm(n1),
                                                   vx + u2 * t, u2, n2 / np.linalg.norm(n2))))
    return pieces


def sample_path(pieces: list[tuple], s: np.ndarray) -> np.ndarray:
    """Positions at path lengths s (increasing) along `blended_path`'s pieces."""
    out = np.empty((len(s), 3))
    s0 = 0.0
    for kind, ln, g in pieces:
        m = (s >= s0) & (s < s0 + ln)
        if m.any():
            x = s[m] - s0
            if kind == "line":
                out[m] = g[0] + x[:, None] * g[1]
            else:  # the first clothoid from its start, the second back from its end
                theta, length, q0, u1, n1, q1, u2, n2 = g
                first = x <= length
                pts = np.empty((len(x), 3))
                cx, cy = unit_clothoid(theta, x[first] / length)
                pts[first] = q0 + (length * cx)[:, None] * u1 + (length * cy)[:, None] * n1
                cx, cy = unit_clothoid(theta, (2.0 * length - x[~first]) / length)
                pts[~first] = q1 - (length * cx)[:, None] * u2 + (length * cy)[:, None] * n2
                out[m] = pts
        s0 += ln
    kind, ln, g = pieces[-1]
    out[s >= s0] = g[0] + ln * g[1]
    return out


def _moving(x: np.ndarray, n: int) -> np.ndarray:
    c = np.cumsum(np.vstack([np.repeat(x[:1], n, axis=0), x]), axis=0)
    return (c[n:] - c[:-n]) / n


def _shares(q: np.ndarray, pts: np.ndarray) -> str:
    v = np.diff(q, axis=0) / 1e-3
    a = np.diff(v, axis=0) / 1e-3
    j = np.diff(a, axis=0) / 1e-3
    lim = np.array([[500.0, 5000.0, 250_000.0]] * 2 + [[300.0, 3000.0, 150_000.0]])
    r = [float((np.abs(x).max(axis=0) / lim[:, k]).max()) for k, x in enumerate((v, a, j))]
    return f"v/a/j {r[0]:.2f}/{r[1]:.2f}/{r[2]:.2f} dev {polyline_deviation(q, pts):.4f}"


def crossfade(v: float, n1: int = 16, n2: int = 16) -> None:
    """The two 400-segment CAM programs blended, run at a constant v (no speed changes), through no
    filter, the whole 16 + 16 ms filter F, and out = p(t − D) + λ·(F − p(t − D)) with λ going 1 → 0 at
    cycle 1000 and back at 2000 over a quintic smoothstep of R cycles: per-axis peak v/a/j of the
    limits and the deviation, on the ramps, between them (λ = 0), and of the raw path there."""
    d = (n1 + n2 - 2) // 2
    for prog in (cam_surface(400), cam_polyline(400)):
        pts = np.array([START] + prog.points, dtype=float)
        pieces = blended_path(pts, TOL)
        n = int(sum(p[1] for p in pieces) / v / 1e-3)
        raw = sample_path(pieces, v * 1e-3 * np.arange(n))
        f = _moving(_moving(raw, n1), n2)
        raw_d = np.vstack([np.repeat(raw[:1], d, axis=0), raw[:-d]])
        inner = slice(64, n - 64)
        print(f"{prog.name}, {v:g} mm/s: blended, no filter {_shares(raw[inner], pts)}; "
              f"the whole filter {_shares(f[inner], pts)}")
        t = np.arange(n)
        for r in (15, 30, 60):
            x1, x2 = np.clip((t - 1000) / r, 0.0, 1.0), np.clip((t - 2000) / r, 0.0, 1.0)
            lam = 1.0 - x1 ** 3 * (10 - 15 * x1 + 6 * x1 * x1) + x2 ** 3 * (10 - 15 * x2 + 6 * x2 * x2)
            out = raw_d + lam[:, None] * (f - raw_d)
            print(f"  R = {r:2d} ms: ramp down {_shares(out[960:1040 + r], pts)} | λ = 0 "
                  f"{_shares(out[1040 + r:1960], pts)} | ramp up {_shares(out[1960:2040 + r], pts)}")
        print(f"  raw p(t − D) there:  {_shares(raw_d[960:1070], pts)} | {_shares(raw_d[1070:1960], pts)} | "
              f"{_shares(raw_d[1960:2070], pts)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--crossfade", type=float, metavar="V", help="the filter share on a blended path at V mm/s")
    args = ap.parse_args()
    if args.crossfade:
        crossfade(args.crossfade)
        return
    print(f"local clothoid-pair blends, N1.053 = {TOL} mm, filter off, speed changes free (a lower bound)")
    print(f"{'program':36s} {'feed bound':>10s} {'full A, J':>10s} {'shared':>10s}")
    for prog in programs():
        pts = np.array([START] + prog.points, dtype=float)
        f = prog.feed / 60.0
        print(f"{prog.name:36s} {prog.feed_limited():10.3f} {bound(pts, f, TOL, 1.0):10.3f} "
              f"{bound(pts, f, TOL, SHARE_N):10.3f}")


if __name__ == "__main__":
    main()
