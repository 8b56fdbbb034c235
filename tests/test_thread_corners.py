"""The corner between a thread and its chamfer pull-out (G92/G76, N1.177/N1.178) inside one
spindle-locked chain: Z cannot slow down there, so X must not step from rest to the chamfer's
speed in one cycle (it did: 2.5e4 mm/s² on a 3,000 mm/s² axis). The corner is rounded within X's
acceleration and jerk, the same on every pass (nc.motion.thread_corners; decision A42b)."""

from __future__ import annotations

import math

import numpy as np

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.motion.thread_corners import SHARE
from nc.program import parse_program

# Manual N§ G92: the chamfer is r = N1.178 × 0.1 × lead (default 1 lead) at N1.177 (default 45°).
G92 = "G21 G18 G99\nS800 M03\nG00 X28. Z5.\nG92 X21.4 Z-22. F2.\nG00 X60. Z20.\nM30\n"
LEAD, RPM = 2.0, 800.0
VERTEX = (10.7, -20.0)  # X radius, Z: where the thread (Z5 → Z-20) turns into the chamfer


def run(text: str) -> np.ndarray:
    bench = default_lathe()
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    rows: list[tuple[int, float, float]] = []
    runner.on_cycle = lambda r: rows.append((r.line, r._commands[0], r._commands[1])) if r.channel else None
    result = runner.run_program(parse_program(text))
    assert result.alarms == [], result.alarms
    return np.array(rows)


def test_chamfer_corner_keeps_x_within_its_acceleration_and_jerk():
    bench = default_lathe()
    lim = bench.axes[0].limits
    m = run(G92)
    x = m[m[:, 0] == 4][:, 1]  # X commands on the G92 line
    dt = bench.cycle
    acc = np.abs(np.diff(x, 2)) / dt ** 2
    jerk = np.abs(np.diff(x, 3)) / dt ** 3
    assert acc.max() <= lim.max_acceleration, acc.max()
    assert jerk.max() <= lim.max_jerk, jerk.max()
    # the pull-out still ends exactly where the program puts it
    g92 = m[m[:, 0] == 4]
    end = int(np.flatnonzero(g92[:, 2] <= -22.0 + 1e-12)[0])
    assert abs(g92[end, 1] - 12.7) < 1e-9


def test_chamfer_corner_is_rounded_by_the_documented_kernel():
    """X = programmed polyline + ΔK·(w−|t|)³/(6w²) around the vertex, with w the least half-width
    that keeps X within SHARE of its limits at the locked Z speed; the vertex is passed w/6 away."""
    bench = default_lathe()
    lim = bench.axes[0].limits
    v = LEAD * RPM / 60.0  # locked Z speed, mm/s
    dk = 1.0  # X slope per unit of Z travel: 0 on the thread, tan 45° on the chamfer
    w = max(v * v * dk / (SHARE * lim.max_acceleration), math.sqrt(v ** 3 * dk / (SHARE * lim.max_jerk)))
    m = run(G92)
    g92 = m[m[:, 0] == 4]
    g92 = g92[:int(np.flatnonzero(g92[:, 2] <= -22.0 + 1e-12)[0]) + 1]  # up to the chamfer's end
    t = VERTEX[1] - g92[:, 2]  # Z travel past the vertex (Z runs negative)
    near = np.abs(t) < w
    assert near.sum() > 10  # the corner spans many cycles, not one
    line = VERTEX[0] + dk * np.maximum(t[near], 0.0)
    expect = line + dk * (w - np.abs(t[near])) ** 3 / (6 * w * w)
    assert np.max(np.abs(g92[near, 1] - expect)) < 1e-8
    # outside the window X is exactly on the programmed thread and chamfer
    far = (np.abs(t) >= w) & (g92[:, 2] < 4.0)
    assert np.max(np.abs(g92[far, 1] - (VERTEX[0] + dk * np.maximum(t[far], 0.0)))) < 1e-8
    assert abs(w / 6 - 0.0625) < 1e-3  # 26.7 mm/s, J = 150,000 mm/s³: the vertex is passed 0.06 mm off in X
