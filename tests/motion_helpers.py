"""Shared builders for the motion tests: moves straight from point lists (the Move seam)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from nc.motion import AxisLimits, MotionConfig
from nc.motion.offline import Stream, run
from nc.moves import Move

AX = ("X", "Y", "Z")


def mill_cfg(**kw) -> MotionConfig:
    lim = {"X": AxisLimits(400, 4000, 200_000), "Y": AxisLimits(400, 4000, 200_000), "Z": AxisLimits(200, 2000, 100_000)}
    return MotionConfig(axes=AX, limits=lim, **kw)


def lines(pts, feed, kind="line", first_line=1, **kw) -> list[Move]:
    out = []
    for k in range(1, len(pts)):
        s = dict(zip(AX, map(float, pts[k - 1])))
        e = dict(zip(AX, map(float, pts[k])))
        out.append(Move(kind, first_line + k - 1, "", s, e, e, feed=feed, plane=("X", "Y"), **kw))
    return out


def arc(s, e, c, d, feed, line=0) -> Move:
    s = dict(zip(AX, map(float, s)))
    e = dict(zip(AX, map(float, e)))
    return Move("arc", line, "", s, e, e, center={"X": c[0], "Y": c[1], "Z": 0.0}, dir=d, feed=feed, plane=("X", "Y"))


def circle_chords(radius: float, chord: float) -> list[tuple[float, float, float]]:
    n = int(2 * math.pi * radius / chord)
    return [(radius * math.cos(2 * math.pi * k / n), radius * math.sin(2 * math.pi * k / n), 0.0) for k in range(n + 1)]


def worst_ratio(st: Stream, cfg: MotionConfig) -> dict[str, float]:
    """Largest |v|/v_max, |a|/a_max, |j|/j_max over every cycle and axis (finite differences)."""
    v, a, j = st.derivatives()
    out = {"v": 0.0, "a": 0.0, "j": 0.0}
    for i, ax in enumerate(cfg.axes):
        lim = cfg.limit(ax)
        out["v"] = max(out["v"], float(np.abs(v[:, i]).max()) / lim.max_velocity)
        out["a"] = max(out["a"], float(np.abs(a[:, i]).max()) / lim.max_acceleration)
        out["j"] = max(out["j"], float(np.abs(j[:, i]).max()) / lim.max_jerk)
    return out


def jagged_polyline(n: int = 300, seed: int = 1) -> list[np.ndarray]:
    """A random walk of 0.01–0.1 mm segments turning sharply in X/Y and less in Z."""
    rng = np.random.default_rng(seed)
    p, d, pts = np.zeros(3), np.array([1.0, 0, 0]), [np.zeros(3)]
    for _ in range(n):
        d = d + rng.normal(0, 0.3, 3) * [1, 1, 0.5]
        d /= np.linalg.norm(d)
        p = p + d * rng.uniform(0.01, 0.1)
        pts.append(p)
    return pts


def polyline_deviation(positions: np.ndarray, pts) -> float:
    """Largest distance of any setpoint from the programmed polyline `pts` (mm)."""
    P = np.asarray(positions, float)
    pts = np.asarray(pts, float)
    A, D = pts[:-1], np.diff(pts, axis=0)
    L2 = np.maximum((D * D).sum(1), 1e-30)
    out = 0.0
    for k in range(0, len(P), 500):
        Q = P[k:k + 500][:, None, :]
        t = np.clip(((Q - A) * D).sum(2) / L2, 0.0, 1.0)
        out = max(out, float(np.sqrt((((A + t[..., None] * D) - Q) ** 2).sum(2)).min(1).max()))
    return out


TOL = 1.0 + 1e-6


def check(moves, cfg: MotionConfig, start=(0.0, 0.0, 0.0)) -> Stream:
    """Run moves offline; the program must finish without an alarm and every cycle's finite-difference
    velocity, acceleration and jerk stay within the axis limits."""
    st = run(moves, cfg, dict(zip(AX, start)))
    assert st.state.value == "finished" and not st.alarms
    r = worst_ratio(st, cfg)
    assert r["v"] <= TOL and r["a"] <= TOL and r["j"] <= TOL, r
    return st


def single_block_operator(stops: list) -> Callable:
    """An `on_cycle` hook that runs single block: records where each block stopped and presses Cycle Start."""
    from nc.channel import RunState

    def ctl(n, ch):
        ch.single_block = True
        if ch.state is RunState.BLOCK_STOP:
            stops.append(ch.planner.position.copy())
            ch.cycle_start()
    return ctl


def profile_time(length: float, v: float, a: float, j: float) -> float:
    """A rest-to-rest jerk-limited move that reaches its cruise speed v (tangential a, j): a trapezoidal
    acceleration, or a triangular one where v comes before a does (v·j < a²)."""
    return length / v + (2.0 * (v / j) ** 0.5 if v * j < a * a else v / a + a / j)


# benches/mill-3axis.toml's axes as bench-file text (tests that write their own bench around them)
MILL_AXES = """
[[axes]]
name = "X"
limits = { velocity = 500.0, acceleration = 5000.0, jerk = 250000.0 }
[[axes]]
name = "Y"
limits = { velocity = 500.0, acceleration = 5000.0, jerk = 250000.0 }
[[axes]]
name = "Z"
start = 100.0
limits = { velocity = 300.0, acceleration = 3000.0, jerk = 150000.0 }
"""
