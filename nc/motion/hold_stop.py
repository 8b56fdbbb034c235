"""Does a hold's stop fit the path it runs along? (decision motion 63)

A feed hold, a reset or an alarm stops the path with one jerk-limited velocity ramp to rest (`solve_velocity`),
which may run on across the queue's junctions. Where it would cross a junction faster than the look-ahead allows
there (a corner's end speed, the queue's end), the planner brakes for that junction as a plan would, and stops
from there. Before, the ramp ran through a sharp corner at speed (a G76's return into its infeed: 110 mm/s round a
90° corner, X at 2× its acceleration after the filter) or past the queue's last point (clipped there).

The same question for path profiles (decision motion 83): does a braking solve through lower caps get below each
before it reaches it (`brakes_below`), and does the profile a plan was following still fit the queue where its
re-solve missed (`fits_queue`, `later`)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from nc.motion.block import Block
from nc.motion.profile import Piecewise
# the kept profile's checks: C functions where the planner is compiled (session 31, decision bench B184)
from nc.motion.profile import fits_queue, later, peak_speed, time_at  # noqa: F401  (re-exported)

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



def _phases(pw: Piecewise) -> tuple[list[float], list[float], list[float], list[float], list[float]]:
    """DoF 0's phases as plain lists (start times, position, speed, acceleration, jerk): `Piecewise.at`'s own."""
    pw.at(0.0)  # (brings its lists up to date with the duration)
    return pw._lists[1:]


def brakes_below(pw: Piecewise, s: float, dist: float, blocks: Iterable[Block]) -> bool:
    """True when a braking solve (path position from s in blocks[0] to dist, its acceleration nowhere above
    zero) crosses every junction before dist no faster than the junction and the block after it allow (its
    `vjunc` and `cap`): a state above the caps of the blocks ahead, solved with its own speed as the top speed,
    gets below each before it reaches it (decision motion 83). Rare (a plan that no ordinary run could meet)."""
    if max(_phases(pw)[3]) > 1e-9:
        return False  # it speeds up somewhere: the junction speeds alone do not bound it in the blocks
    it = iter(blocks)
    b = next(it)
    at = 0.0  # the path position of b's end, in blocks[0]'s coordinates
    t = 0.0
    for nx in it:
        at += b.length
        if at >= dist - 1e-12:
            return True
        if at > s:
            lim = nx.cap if nx.cap < b.vjunc else b.vjunc
            if pw.at(t)[1] > lim:  # (its speed only falls: where it is below the limit already, so it is there)
                t = time_at(pw, at, t)
                if pw.at(t)[1] > lim * (1.0 + 1e-9) + 1e-12:
                    return False
        b = nx
    return True
