"""The planner's plain state records (nc.motion.planner and its mixins share them)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nc.motion.profile import Piecewise
from nc.moves import Move

CHUNK = 64  # cycles sampled per vectorised step


def _near(a: np.ndarray, b: np.ndarray) -> bool:
    """np.allclose(a, b, atol=1e-6) on plain floats: checked at every block start, where numpy's
    call cost more than the three comparisons (issue 17)."""
    return all(abs(x - y) <= 1e-6 + 1e-5 * abs(y) for x, y in zip(a.tolist(), b.tolist()))


@dataclass
class Setpoint:
    positions: np.ndarray  # machine coordinates per axis, in MotionConfig.axes order
    line: int  # program line of the active move (0 when idle before any move)
    path_velocity: float  # mm/s along the path
    move: Move | None


@dataclass
class _Plan:
    kind: str  # "path" (to the block end), "ramp" (velocity change, may span blocks), "dwell", "indep"
    pw: Piecewise | None
    duration: float
    t_next: float  # plan time of the next sample
    base: float = 0.0  # plan position at the start of blocks[0] (ramps that cross blocks)
    target: float = 0.0  # ramp target speed
    rpm: float = 0.0  # spindle speed the feed-per-rev cap used
    settled: bool = False  # that speed was the command the spindle had reached
    emitted: bool = False  # some of its samples went out (the planner state is the last of them)
    # A path solve whose jerk factor the queue could not tell yet (nc.motion.shares): sampled a
    # few cycles at a time and solved again once more than `queued` moves were pushed.
    open: bool = False
    queued: int = 0
    # A "cruise" (decision motion 44): whole blocks sampled at once; `carry` the next plan's t0 after the last
    # of them, `last` its offset from blocks[0] when sampled.
    carry: float = 0.0
    last: int = 0
