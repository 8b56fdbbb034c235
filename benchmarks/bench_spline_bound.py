"""What a curvature-continuous fit of a CAM run could reach (issue 18, decision motion 48; measured, not built).

Corner blends sized by the half rule change curvature at θ/L² and their centripetal jerk holds the CAM
rows near 1.14–1.19× the feed-limited time (decision 47). This script fits the whole polyline with one
cubic smoothing spline (C2: bounded jerk at a constant speed) through samples of the polyline, smoothed
locally as much as N1.053 allows (reweighted until every point of the curve is within the tolerance of
the programmed polyline), and bounds its time: at path speed v each axis has acceleration v²·r''(s) and
jerk v³·r'''(s) (s the arc length), so v(s) ≤ min(F, √(A·share/|r''|), ∛(J·share/|r'''|)) per axis; the
time is ∫ds/v with speed changes free, and again with them limited to a tangential acceleration
(forward/backward pass on v²). A lower bound for a planner that fits the run; no jerk between speeds.
The fit and its spans are nc.motion.spline_runs' (decision 49); "span caps" is Σ length / min(F, cap)
over the spans with `span_limits`' budget.

    python benchmarks/bench_spline_bound.py [--n 400] [--share 0.8] [--tol 0.02]
    python benchmarks/bench_spline_bound.py --cost [--n 400] [--window 40] [--every 20]

--cost times what a streaming planner pays (decision 53): `fit_run` and `spans` on windows of `--window`
segments taken every `--every` segments, CPU time (time.process_time) a segment of the windows, best of 3,
split by part, with the fit's rounds a window and the load.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from unittest import mock

import numpy as np

from benchmarks.bench_vs_linuxcnc import BENCH, START, Program, cam_polyline, cam_surface, measure
from hil.bench_file import load_bench_file
from nc.motion.block import Block
from nc.motion.offline import Stream, run
from nc.motion.planner import Planner
from nc.motion.spline_runs import LAM, Cost, FitError, fit_run, polyline_distance, span_limits, spans
from nc.moves import Move

ACC = np.array([5000.0, 5000.0, 3000.0])  # benches/mill-3axis.toml
JERK = np.array([250_000.0, 250_000.0, 150_000.0])
VEL = np.array([500.0, 500.0, 300.0])


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


def deviation(curve: np.ndarray, cu: np.ndarray, pts: np.ndarray, cum: np.ndarray) -> float:
    return float(polyline_distance(curve, cu, pts, cum).max())


def best_fit(pts: np.ndarray, tol: float, lam: float = LAM):
    return fit_run(pts, tol, lam), lam


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
    cut = spans(spl, cum, ("X", "Y", "Z"))
    caps = np.array([span_limits(sp, VEL, ACC, JERK)[0] for sp in cut])
    lens = np.array([sp.length for sp in cut])
    return {"spans": float(np.sum(lens / np.minimum(caps, F))), "lam": lam, "dev": deviation(cp, uu, pts, cum),
            "free": free, "limited": limited,
            "bound": prog.feed_limited(), "v_median": float(np.median(v)), "v_p5": float(np.percentile(v, 5)),
            "length": float(np.sum(ds))}


def through_planner(prog: Program, tol: float) -> Stream:
    """The fitted spans run through today's planner (decision 50), one block a programmed line in place of
    the line, with `span_limits`; the bench's limits, its filter off (on a blended or fitted stretch the
    filter's share is 0 and the output is the raw path delayed, decision 45). An experiment: Planner._block
    is patched for the run, the planner has no hook for spans yet."""
    cfg = load_bench_file(BENCH).motion_config()
    cfg = dataclasses.replace(cfg, filter_time=0.0, filter_scurve=0.0, fit_runs=False)  # its own spans, not the planner's fit
    pts = np.array([START] + prog.points, dtype=float)
    cut = spans(*fit_run(pts, tol), cfg.axes)
    lims = [np.array([getattr(cfg.limit(a), f) for a in cfg.axes])
            for f in ("max_velocity", "max_acceleration", "max_jerk")]
    line_block = Planner._block

    def span_block(self: Planner, move: Move) -> Block | None:
        b = line_block(self, move)
        if b is None:
            return None
        sp = cut[move.line - 1]
        return Block(move, "path", sp, sp.length, *span_limits(sp, *lims), b.feed)

    moves = [Move("line", k, "", dict(zip("XYZ", pts[k - 1])), dict(zip("XYZ", pts[k])), dict(zip("XYZ", pts[k])),
                  feed=prog.feed, plane=("X", "Y")) for k in range(1, len(pts))]
    with mock.patch.object(Planner, "_block", span_block):
        return run(moves, cfg, dict(zip("XYZ", START)))


def cost(prog: Program, tol: float, window: int, every: int, repeat: int = 3) -> dict[str, float]:
    """CPU ms a segment of fit_run's and spans' parts on windows of the program, the best of `repeat` runs,
    and the fit's rounds a window."""
    pts = np.array([START] + prog.points, dtype=float)
    wins = [pts[k:k + window + 1] for k in range(0, len(pts) - window, every)]
    best: dict[str, float] = {}
    for _ in range(repeat):
        fc, sc = Cost(parts={}), Cost(parts={})
        t0 = time.process_time()
        fits = [fit_run(w, tol, cost=fc) for w in wins]
        t1 = time.process_time()
        for f in fits:
            spans(*f, ("X", "Y", "Z"), cost=sc)
        t2 = time.process_time()
        run = {"fit": t1 - t0, "spans": t2 - t1, **{f"fit {k}": v for k, v in fc.parts.items()},
               **{f"spans {k}": v for k, v in sc.parts.items()}}
        if not best or run["fit"] + run["spans"] < best["fit"] + best["spans"]:
            best = run
    segs = window * len(wins)
    out = {k: 1e3 * v / segs for k, v in best.items()}
    out["rounds"] = fc.rounds / len(wins)
    out["windows"] = len(wins)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=400)
    ap.add_argument("--tol", type=float, default=0.02)
    ap.add_argument("--share", type=float, default=0.8)
    ap.add_argument("--at", type=float, default=1000.0, help="tangential acceleration of speed changes, mm/s²")
    ap.add_argument("--planner", action="store_true", help="run the spans through the planner (filter off)")
    ap.add_argument("--cost", action="store_true", help="CPU time of the fit and the spans on streaming windows")
    ap.add_argument("--window", type=int, default=40, help="--cost: segments a window")
    ap.add_argument("--every", type=int, default=20, help="--cost: segments between windows' starts")
    args = ap.parse_args()
    for make in (cam_polyline, cam_surface):
        prog = make(args.n)
        if args.cost:
            try:
                c = cost(prog, args.tol, args.window, args.every)
            except FitError as e:
                raise SystemExit(f"{prog.name}: {e}") from None
            parts = ", ".join(f"{k} {v:.4f}" for k, v in c.items() if k.count(" "))
            print(f"{prog.name:38s} {c['windows']:.0f} windows of {args.window}: fit {c['fit']:.4f} + spans "
                  f"{c['spans']:.4f} = {c['fit'] + c['spans']:.4f} ms CPU a segment, {c['rounds']:.2f} rounds "
                  f"a window | {parts} | load {os.getloadavg()[0]:.1f}")
            continue
        if args.planner:
            try:
                st = through_planner(prog, args.tol)
            except FitError as e:
                raise SystemExit(f"{prog.name}: {e}") from None
            r = measure(st.positions, prog)
            print(f"{prog.name:38s} feed-limited {prog.feed_limited():7.3f} s | spans through the planner "
                  f"{st.time:7.3f} s ({st.time / prog.feed_limited():.3f}×), {st.state.value}, "
                  f"dev {r.deviation:.4f} mm, "
                  f"v/a/j {r.v:.2f}/{r.a:.2f}/{r.j:.2f}")
            continue
        try:
            r = bound(prog, args.tol, args.share, args.at)
        except FitError as e:
            raise SystemExit(f"{prog.name}: {e}") from None
        print(f"{prog.name:38s} feed-limited {r['bound']:7.3f} s | fit λ {r['lam']:.2e} dev {r['dev']:.4f} mm, "
              f"length {r['length']:.1f} mm | speed changes free {r['free']:7.3f} s ({r['free'] / r['bound']:.3f}×), "
              f"at {args.at:g} mm/s² {r['limited']:7.3f} s ({r['limited'] / r['bound']:.3f}×) | "
              f"span caps (span_limits) {r['spans']:7.3f} s ({r['spans'] / r['bound']:.3f}×) | "
              f"v median {r['v_median']:.1f}, 5 % {r['v_p5']:.1f} mm/s")


if __name__ == "__main__":
    main()
