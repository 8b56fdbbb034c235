"""The planner's samples handed out a stretch at a time (issue 17: "the runner asks the channel for the next N
planned samples as arrays").

The planner samples each plan into a buffer (`Planner._buf_pos`, up to 64 cycles, within one block; a
cruise's across blocks, decision motion 44, of which a stretch takes the rows in the current block, or with
`across` in its later blocks too) and
`Planner.step` hands out one row per cycle, through the position filter. `sample_stretch(planner, n)` hands
out the next rows of that buffer at once — at most to its end, where the planner solves again — filtered by
`PositionFilter.push_many`, and leaves the planner as that many `step()` calls would. It refuses (None) what
a cycle-by-cycle step does differently: an empty buffer (refill, solve), a feed-per-revolution path (the
measured speed re-plans it; unless the caller bounds the stretch where it would, `per_rev`), a thread or G31
move (they bypass the filter), an offline planner that integrates its own spindle angle. `step()` also counts
how long the measured spindle speed has been at its command (threads arm on it): with a stretch the caller
reports the speeds afterwards, `settle_stretch`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from nc.motion.planner import Planner
from nc.motion.planner_cruise import cut_rows, refuses  # a part's take, compiled (issue 17, decision bench B190)
from nc.motion.threading import SETTLE_BAND, SETTLE_MIN_RPM
from nc.moves import Move


@dataclass
class Samples:
    """`step()`'s setpoints of the stretch's cycles, as rows."""

    positions: np.ndarray  # (cycles, axes), filtered as step() returns them
    lines: list[int]
    path_velocity: np.ndarray
    move: Move | None  # the move of every row, unless `moves` gives one per row (a cruise's blocks)
    moves: list[Move] | None = None
    raw: np.ndarray | None = None  # the rows before the filter, where they span buffers (hil/stretch_pass.py)


def sample_stretch(pl: Planner, n: int, across: bool = False, per_rev: bool = False) -> Samples | None:
    """The next min(n, rows left in the buffer) setpoints, or None where step() must run (module doc).
    `across`: a cruise's rows in its later blocks too, those blocks finished as step() finishes them (the
    caller sees to it that nothing reads the queue in between, nor pushes to it). `per_rev`: a
    feed-per-revolution path too, the caller ending the stretch before the first cycle whose measured spindle
    speed would re-plan it (`nc.motion.planner.replans`)."""
    rows = take_rows(pl, n, across, per_rev)
    if rows is None:
        return None
    raw, lam, smp = rows
    smp.positions = pl.filter.push_many(raw, lam) if pl.filter is not None else np.array(raw, dtype=float)
    pl.output = smp.positions[-1].copy()
    return smp


def take_rows(pl: Planner, n: int, across: bool = False,
              per_rev: bool = False) -> tuple[np.ndarray, np.ndarray | None, Samples] | None:
    """sample_stretch's planner part: the rows taken (the planner left as after their steps), their filter
    shares λ (None: 1 throughout) and their Samples, whose positions are the raw rows until the caller filters
    them."""
    got = take_parts(pl, n, across, per_rev)
    if got is None:
        return None
    raw, lam, lines, vel, mv, moves = got
    return raw, lam, Samples(raw, list(lines), np.array(vel, dtype=float), mv, moves)


def take_parts(pl: Planner, n: int, across: bool = False, per_rev: bool = False) -> tuple | None:
    """take_rows without its Samples: (raw rows, λ, lines, path speeds, move, moves), the rows and speeds views
    of the planner's buffer (a refill makes new ones, nothing writes them in place), so a part costs no dataclass
    and no copy (issue 17). A stretch that runs the NC's steps asks `refuses` and takes with `cut_rows` itself,
    once after its step (hil/stretch_pass.py `Pass._take_part`, decision bench B165)."""
    if n <= 0 or pl._integrate_angle or pl._buf_done:
        return None
    blocks = pl.blocks
    mv = blocks[0].move if blocks else None
    if mv is not None and refuses(pl, mv, per_rev):
        return None
    i = pl._buf_i
    m = pl._cruise_rows(n) if across else min(n, pl._block_rows())
    if m <= 0:
        return None  # the next row starts the cruise's next block: step() finishes this one
    return cut_rows(pl, i, m, mv)


def sample_per_rev(pl: Planner, n: int) -> Samples | None:
    """sample_stretch over a feed-per-revolution path (its `per_rev`), as a stretch's sampler."""
    return sample_stretch(pl, n, per_rev=True)


def stand_stretch(pl: Planner, n: int, queued: bool = False) -> Samples | None:
    """`n` setpoints of a planner with nothing to move (no block, no plan: waiting for an M/S/T finish, or the
    filter's tail after the last move), as step() gives them: the position where it stands through the filter.
    None unless step() would change nothing else: it stood so the cycle before (speed 0, no block started, no
    stop to flush, no axis moving on its own) and the filter needs no reset to that position. step()'s solve
    (which finds nothing) runs once the filter has settled, and leaves the carry at one cycle. `queued`: blocks
    wait behind an exact stop (Planner._refill starts nothing before the filter settled); the caller ends the
    stretch before the cycle that begins with the filter settled, whose solve starts the next block."""
    if n <= 0 or (pl.blocks and not queued) or pl.plan is not None or not pl._buf_done or pl._integrate_angle \
            or pl._stopping:
        return None
    if pl.v != 0.0 or pl.a != 0.0 or pl._started or np.any(pl._axis_v):
        return None
    f = pl.filter
    if f is not None and f.settled and not np.array_equal(pl.position, f.output):
        return None  # step() resets the filter to the position first
    raw = np.tile(pl.position, (n, 1))
    if f is None:
        positions, solved = raw, True
    else:  # Planner._refill solves (Planner._start_plan) in a step that begins with the filter settled
        lam = pl.share_standing(n)
        head = f.push_many(raw[:-1], None if lam is None else lam[:-1])
        solved = f.settled
        positions = np.vstack([head, f.push_many(raw[-1:], None if lam is None else lam[-1:])])
    if solved:
        pl._carry = pl.cfg.cycle
    pl.output = positions[-1].copy()
    return Samples(positions, [pl.line] * n, np.zeros(n), None)


def settle_stretch(pl: Planner, rpms: Sequence[float], commands: Sequence[float]) -> None:
    """The spindle settle count step() keeps, for a stretch's cycles: the measured and commanded speed each
    cycle's step() would have read."""
    if pl.spindle_command is None:
        return
    # SpindleSettle.update once per cycle, its test on locals (a method call per cycle was a tenth of a stretch)
    n = pl._settle.cycles
    for rpm, cmd in zip(rpms, commands):
        n = n + 1 if abs(cmd) >= 1.0 and abs(rpm - cmd) <= max(SETTLE_BAND * abs(cmd), SETTLE_MIN_RPM) else 0
    pl._settle.cycles = n
