"""Does a hold's stop fit the path it runs along? (decision motion 63)

A feed hold, a reset or an alarm stops the path with one jerk-limited velocity ramp to rest (`solve_velocity`),
which may run on across the queue's junctions. Where it would cross a junction faster than the look-ahead allows
there (a corner's end speed, the queue's end), the planner brakes for that junction as a plan would, and stops
from there. Before, the ramp ran through a sharp corner at speed (a G76's return into its infeed: 110 mm/s round a
90° corner, X at 2× its acceleration after the filter) or past the queue's last point (clipped there)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from nc.motion.block import Block
from nc.motion.profile import Piecewise

SAMPLES = 256  # points of the ramp's speed over its path: only read when a hold is planned


def crosses_too_fast(ramp: Piecewise, s: float, blocks: Iterable[Block]) -> bool:
    """True when the ramp (path position from s in blocks[0], to rest) passes a junction of the queue faster
    than that junction's planned end speed (`vend`: its own limit or one set downstream)."""
    t = np.linspace(0.0, ramp.duration, SAMPLES)
    p, v, _ = ramp.sample(t)
    end = float(p[-1])
    at = 0.0  # the path position of the next junction, in blocks[0]'s coordinates
    for b in blocks:
        at += b.length
        if at > end + 1e-9:
            return False  # the ramp ends inside this block
        if at >= s and float(np.interp(at, p, v)) > b.vend * (1.0 + 1e-6) + 1e-6:
            return True
    return end > at + 1e-9  # past the queue's last point
