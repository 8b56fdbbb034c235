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

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from benchmarks.bench_vs_linuxcnc import START, TOL, Program, cam_polyline, cam_surface, programs  # noqa: E402
from nc.motion.clothoid import corner_blend  # noqa: E402
from nc.motion.path import Segment  # noqa: E402
from nc.motion.smoothing import PositionFilter, smoothstep  # noqa: E402
from tests.motion_helpers import polyline_deviation  # noqa: E402

A_AXIS, J_AXIS = 5000.0, 250_000.0
SHARE_N = math.sqrt(1.0 - 0.5 ** 2)  # LinuxCNC's BLEND_ACC_RATIO_NORMAL


def _lines(points: np.ndarray) -> list[Segment]:
    pts = points[np.r_[True, np.linalg.norm(np.diff(points, axis=0), axis=1) > 1e-9]]
    out = []
    for p, q in zip(pts[:-1], pts[1:]):
        ln = float(np.linalg.norm(q - p))
        out.append(Segment(("X", "Y", "Z"), p.astype(float), q.astype(float), ln, "line",
                           _dir=tuple(((q - p) / ln).tolist())))
    return out


def bound(points: np.ndarray, feed: float, tol: float, share: float) -> float:
    lines = _lines(points)
    acc, jerk = share * A_AXIS, share * J_AXIS
    time = 0.0
    used = np.zeros(len(lines))  # path each line gives to the blends at its two ends
    for i, (s1, s2) in enumerate(zip(lines[:-1], lines[1:])):
        b = corner_blend(s1, s2, tol, s1.length, s2.length)
        if b is None:
            continue
        v = min(feed, math.sqrt(acc / b.kappa_max), (jerk / b.dkappa) ** (1.0 / 3.0))
        time += b.length / v
        used[i] += b.tlen
        used[i + 1] += b.tlen
    return time + float(np.sum(np.maximum(np.array([s.length for s in lines]) - used, 0.0))) / feed


# ---- the filter share on a blended path (decision motion 40 b) -----------------------------------
def blended_path(points: np.ndarray, tol: float) -> list[Segment]:
    """The polyline as segments: its lines, trimmed, and a clothoid pair (nc.motion.clothoid) at
    every corner, sized as `bound` sizes it."""
    lines = _lines(points)
    trim = np.zeros((len(lines), 2))
    blends = []
    for i, (s1, s2) in enumerate(zip(lines[:-1], lines[1:])):
        b = corner_blend(s1, s2, tol, s1.length, s2.length)
        blends.append(b)
        if b is not None:
            trim[i, 1] = trim[i + 1, 0] = b.tlen
    pieces: list[Segment] = []
    for i, s in enumerate(lines):
        u = np.array(s.tangent(False))
        ln = max(s.length - trim[i].sum(), 0.0)
        p = s.start + u * trim[i, 0]
        pieces.append(Segment(s.axes, p, p + u * ln, ln, "line", _dir=s._dir))
        if i < len(blends) and blends[i] is not None:
            pieces.append(blends[i])
    return pieces


def sample_path(pieces: list[Segment], s: np.ndarray) -> np.ndarray:
    """Positions at path lengths s (increasing) along `blended_path`'s pieces."""
    out = np.empty((len(s), 3))
    s0 = 0.0
    for seg in pieces:
        m = (s >= s0) & (s < s0 + seg.length)
        if m.any():
            out[m] = seg.points(s[m] - s0)
        s0 += seg.length
    out[s >= s0] = pieces[-1].end
    return out


def _shares(q: np.ndarray, pts: np.ndarray) -> str:
    v = np.diff(q, axis=0) / 1e-3
    a = np.diff(v, axis=0) / 1e-3
    j = np.diff(a, axis=0) / 1e-3
    lim = np.array([[500.0, 5000.0, 250_000.0]] * 2 + [[300.0, 3000.0, 150_000.0]])
    r = [float((np.abs(x).max(axis=0) / lim[:, k]).max()) for k, x in enumerate((v, a, j))]
    return f"v/a/j {r[0]:.2f}/{r[1]:.2f}/{r[2]:.2f} dev {polyline_deviation(q, pts):.4f}"


def share_ramps(n: int, r: int) -> np.ndarray:
    """λ per cycle: 1, going to 0 at cycle 1000 and back to 1 at cycle 2000, each over a smoothstep of r cycles."""
    t = np.arange(n)
    return 1.0 - smoothstep((t - 1000) / r) + smoothstep((t - 2000) / r)


def crossfade_run(prog: Program, v: float, lam: np.ndarray | None, n1: int = 16, n2: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """(raw, out): the program blended (`blended_path`) sampled at a constant v, and that through
    nc.motion.smoothing.PositionFilter with the share lam per cycle (None: the whole filter)."""
    pts = np.array([START] + prog.points, dtype=float)
    pieces = blended_path(pts, TOL)
    n = int(sum(p.length for p in pieces) / v / 1e-3)
    raw = sample_path(pieces, v * 1e-3 * np.arange(n))
    f = PositionFilter(n1, n2, raw[0])
    return raw, f.push_many(raw, None if lam is None else lam[:n])


def crossfade(v: float, n1: int = 16, n2: int = 16) -> None:
    """The two 400-segment CAM programs blended, run at a constant v (no speed changes), through no
    filter, the whole 16 + 16 ms filter F, and out = p(t − D) + λ·(F − p(t − D)) with λ going 1 → 0 at
    cycle 1000 and back at 2000 over a quintic smoothstep of R cycles: per-axis peak v/a/j of the
    limits and the deviation, on the ramps, between them (λ = 0), and of the raw path there."""
    d = (n1 + n2 - 2) // 2
    for prog in (cam_surface(400), cam_polyline(400)):
        pts = np.array([START] + prog.points, dtype=float)
        raw, f = crossfade_run(prog, v, None, n1, n2)
        n = len(raw)
        raw_d = np.vstack([np.repeat(raw[:1], d, axis=0), raw[:-d]])
        inner = slice(64, n - 64)
        print(f"{prog.name}, {v:g} mm/s: blended, no filter {_shares(raw[inner], pts)}; "
              f"the whole filter {_shares(f[inner], pts)}")
        for r in (15, 30, 60):
            out = crossfade_run(prog, v, share_ramps(n, r), n1, n2)[1]
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
