"""What a curvature-continuous fit of a CAM run could reach (issue 18, decision motion 48; measured, not built).

Corner blends sized by the half rule change curvature at θ/L² and their centripetal jerk holds the CAM
rows near 1.14–1.19× the feed-limited time (decision 47). This script fits the whole polyline with one
cubic smoothing spline (C2: bounded jerk at a constant speed) through samples of the polyline, smoothed
locally as much as N1.053 allows (reweighted until every point of the curve is within the tolerance of
the programmed polyline), and bounds its time: at path speed v each axis has acceleration v²·r''(s) and
jerk v³·r'''(s) (s the arc length), so v(s) ≤ min(F, √(A·share/|r''|), ∛(J·share/|r'''|)) per axis; the
time is ∫ds/v with speed changes free, and again with them limited to a tangential acceleration
(forward/backward pass on v²). A lower bound for a planner that fits the run; no jerk between speeds.

    python benchmarks/bench_spline_bound.py [--n 400] [--share 0.8] [--tol 0.02]
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from scipy.interpolate import make_smoothing_spline

from benchmarks.bench_vs_linuxcnc import START, Program, cam_polyline, cam_surface

ACC = np.array([5000.0, 5000.0, 3000.0])  # benches/mill-3axis.toml
JERK = np.array([250_000.0, 250_000.0, 150_000.0])
PER_SEG = 4  # polyline samples a segment the fit is made to
LAM = 0.01  # the smoothing spline's λ (mm³): the weights then hold it to the tolerance locally


def _samples(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(chord-length parameter, points, segment index) of PER_SEG samples a segment, vertices included."""
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    f = np.arange(PER_SEG) / PER_SEG
    idx = np.repeat(np.arange(len(seg)), PER_SEG)
    ff = np.tile(f, len(seg))
    u = cum[idx] + ff * seg[idx]
    p = pts[idx] + ff[:, None] * (pts[idx + 1] - pts[idx])
    return np.append(u, cum[-1]), np.vstack([p, pts[-1]]), cum


def deviation(curve: np.ndarray, cu: np.ndarray, pts: np.ndarray, cum: np.ndarray) -> float:
    """Largest distance of curve points (at chord parameters cu) from the polyline, over the segments
    within two of the one their parameter falls in."""
    k = np.clip(np.searchsorted(cum, cu) - 1, 0, len(pts) - 2)
    best = np.full(len(curve), np.inf)
    for off in (-2, -1, 0, 1, 2):
        i = np.clip(k + off, 0, len(pts) - 2)
        a, b = pts[i], pts[i + 1]
        d = b - a
        t = np.clip(np.einsum("ij,ij->i", curve - a, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(curve - (a + t[:, None] * d), axis=1))
    return float(best.max())


def fit(pts: np.ndarray, lam: float, w: np.ndarray | None = None):
    """Cubic smoothing splines x(u), y(u), z(u) (u the polyline's chord length) through its samples."""
    u, p, cum = _samples(pts)
    if w is None:
        w = np.ones(len(u))
    w = w.copy()
    w[0] = w[-1] = 1e6  # start and end where the program does
    return [make_smoothing_spline(u, p[:, k], w=w, lam=lam) for k in range(3)], u, cum


def evaluate(spl, u_end: float, step: float = 0.005):
    """Points, r''(s) and r'''(s) (arc length s) on a chord-parameter grid, and ds of each step."""
    uu = np.arange(0.0, u_end, step)
    d1 = np.stack([s.derivative(1)(uu) for s in spl], axis=1)
    d2 = np.stack([s.derivative(2)(uu) for s in spl], axis=1)
    sig = np.linalg.norm(d1, axis=1)
    t = d1 / sig[:, None]
    rss = (d2 - np.einsum("ij,ij->i", t, d2)[:, None] * t) / (sig * sig)[:, None]
    rsss = np.gradient(rss, uu, axis=0) / sig[:, None]
    pts = np.stack([s(uu) for s in spl], axis=1)
    return uu, pts, rss, rsss, sig * step


def _local_deviation(spl, u: np.ndarray, pts: np.ndarray, cum: np.ndarray) -> tuple[np.ndarray, float]:
    """Each polyline sample's largest nearby deviation of the curve, and the largest of all."""
    uu, cp, *_ = evaluate(spl, cum[-1])
    k = np.clip(np.searchsorted(cum, uu) - 1, 0, len(pts) - 2)
    best = np.full(len(cp), np.inf)
    for off in (-2, -1, 0, 1, 2):
        i = np.clip(k + off, 0, len(pts) - 2)
        a, d = pts[i], pts[i + 1] - pts[i]
        t = np.clip(np.einsum("ij,ij->i", cp - a, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(cp - (a + t[:, None] * d), axis=1))
    j = np.clip(np.searchsorted(u, uu), 0, len(u) - 1)
    dev = np.zeros(len(u))
    np.maximum.at(dev, j, best)
    np.maximum.at(dev, np.maximum(j - 1, 0), best)
    return dev, float(best.max())


def best_fit(pts: np.ndarray, tol: float, lam: float = LAM, rounds: int = 60):
    """A fit within tol, smoothed locally as much as it allows: a smoothing spline with a fixed λ whose
    sample weights grow where the curve strays beyond 0.9·tol (iteratively reweighted); the first round
    within tol."""
    u, _, cum = _samples(pts)
    w = np.ones(len(u))
    for _ in range(rounds):
        spl, _, _ = fit(pts, lam, w)
        dev, worst = _local_deviation(spl, u, pts, cum)
        if worst <= tol:
            return (spl, cum), lam
        w = w * np.clip(dev / (0.9 * tol), 1.0, 10.0) ** 3  # only grows: each round is closer
    raise RuntimeError(f"no fit within {tol} mm in {rounds} rounds (λ {lam:g})")


def bound(prog: Program, tol: float, share: float, a_t: float) -> dict[str, float]:
    pts = np.array([START] + prog.points, dtype=float)
    (spl, cum), lam = best_fit(pts, tol)
    uu, cp, rss, rsss, ds = evaluate(spl, cum[-1])
    F = prog.feed / 60.0
    with np.errstate(divide="ignore"):
        va = np.sqrt(share * ACC / np.abs(rss)).min(axis=1)
        vj = np.cbrt(share * JERK / np.abs(rsss)).min(axis=1)
    v = np.minimum(F, np.minimum(va, vj))
    free = float(np.sum(ds / v))
    # speed changes at a_t at most (forward/backward pass on v², from rest to rest)
    v2 = v * v
    v2[0] = v2[-1] = 0.0
    for k in range(1, len(v2)):
        v2[k] = min(v2[k], v2[k - 1] + 2.0 * a_t * ds[k - 1])
    for k in range(len(v2) - 2, -1, -1):
        v2[k] = min(v2[k], v2[k + 1] + 2.0 * a_t * ds[k])
    vv = np.sqrt(np.maximum(v2, 1e-12))
    limited = float(np.sum(ds[:-1] / np.maximum(0.5 * (vv[:-1] + vv[1:]), 1e-9)))
    return {"lam": lam, "dev": deviation(cp, uu, pts, cum), "free": free, "limited": limited,
            "bound": prog.feed_limited(), "v_median": float(np.median(v)), "v_p5": float(np.percentile(v, 5)),
            "length": float(np.sum(ds))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=400)
    ap.add_argument("--tol", type=float, default=0.02)
    ap.add_argument("--share", type=float, default=0.8)
    ap.add_argument("--at", type=float, default=1000.0, help="tangential acceleration of speed changes, mm/s²")
    args = ap.parse_args()
    for make in (cam_polyline, cam_surface):
        prog = make(args.n)
        try:
            r = bound(prog, args.tol, args.share, args.at)
        except RuntimeError as e:
            raise SystemExit(f"{prog.name}: {e}") from None
        print(f"{prog.name:38s} feed-limited {r['bound']:7.3f} s | fit λ {r['lam']:.2e} dev {r['dev']:.4f} mm, "
              f"length {r['length']:.1f} mm | speed changes free {r['free']:7.3f} s ({r['free'] / r['bound']:.3f}×), "
              f"at {args.at:g} mm/s² {r['limited']:7.3f} s ({r['limited'] / r['bound']:.3f}×) | "
              f"v median {r['v_median']:.1f}, 5 % {r['v_p5']:.1f} mm/s")


if __name__ == "__main__":
    main()
