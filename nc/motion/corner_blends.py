"""Corner blends in the look-ahead queue (decision motion 42, issue 18).

When a line follows a line, the junction may get a clothoid pair (nc.motion.clothoid) as a block of
its own: the two lines are shortened by its tangent length, the blend runs between them with the
incoming block's move (program line, feed), and it is planned on its own curvature
(`Limits.block_limits`). It is only built where it is the faster answer (decision 40 a): its speed
cap, with the feed, must beat the speed today's junction model allows (`Limits.junction`).
"""

from __future__ import annotations

import math

from nc.motion.clothoid import ClothoidBlend, corner_blend
from nc.motion.block import Block
from nc.motion.lookahead import Limits, change_distance, reach

MIN_SPEED = 1e-3  # mm/s (and mm/s², mm/s³): below it no blend is built
KEEP = 1e-6  # mm a line keeps between two blends (a block of zero length would stall nothing, but
# every pass divides by lengths): its share of the half rule is that much smaller


def blend_block(lim: Limits, prev: Block, b: Block, tol: float) -> Block | None:
    """The blend block for the junction prev → b (prev.vjunc already set), after shortening both
    lines; None (and nothing changed) where no blend is built."""
    if prev.kind != "path" or b.kind != "path" or prev.rapid or b.rapid or prev.move.exact_stop \
            or prev.move.per_rev or b.move.per_rev or prev.seg is None or b.seg is None \
            or prev.seg.kind != "line" or b.seg.kind != "line" or prev.vjunc <= 0.0:
        return None
    # The half rule counts the programmed lengths (prev may already have given its start away).
    len1 = min(prev.length + prev.trim0, 2.0 * (prev.length - KEEP))
    len2 = b.length - 2.0 * KEEP
    if len1 <= 0.0 or len2 <= 0.0:
        return None
    seg = corner_blend(prev.seg, b.seg, tol, len1, len2)
    if seg is None:
        return None
    v, a, j = lim.block_limits(seg)
    if not (v >= MIN_SPEED and a >= MIN_SPEED and j >= MIN_SPEED):
        return None  # absurd limits (acceleration 1e-50): the planner's own alarm says so, not ruckig
    if not _faster(seg, min(v, prev.feed or 0.0), prev, b):
        return None  # the junction as it is is no slower
    _trim(prev, end=seg)
    _trim(b, start=seg)
    prev.cap_hard, prev.a, prev.j = lim.block_limits(prev.seg, short_ok=prev.trim0 > 0.0)
    b.cap_hard, b.a, b.j = lim.block_limits(b.seg)  # its end is not known yet: a corner, maybe
    blk = Block(prev.move, "path", seg, seg.length, v, a, j, prev.feed)
    prev.vjunc = lim.junction(prev, blk)  # tangent, no curvature jump: the caps alone
    prev.vbud = prev.vctol = math.inf  # the filter's corner there is gone (nc.motion.shares reads them)
    prev.viso = 0.0
    blk.vjunc = lim.junction(blk, b)
    return blk


def _trim(b: Block, start: ClothoidBlend | None = None, end: ClothoidBlend | None = None) -> None:
    seg = b.seg
    assert seg is not None
    if end is not None:
        seg.end = end.start.copy()
        seg.length -= end.tlen
    if start is not None:
        seg.start = start.end.copy()
        seg.length -= start.tlen
        b.trim0 = start.tlen
    b.length = seg.length


def _faster(seg: ClothoidBlend, vb: float, prev: Block, b: Block) -> bool:
    """Whether crossing the corner on the blend at vb loses less time than the junction at
    prev.vjunc: each loses the time of slowing from the speed F the lines reach (their cap, or what
    half the shorter one allows from the corner's speed) and speeding up again, against cruising at F;
    the blend also crawls its length 2L at vb where F would have covered the 2·tlen it cuts.
    (A 90° corner on long lines: the blend's jerk holds it near 6 mm/s over 0.2 mm, 35 ms, where a
    stop at the corner costs less.)"""
    vj = prev.vjunc
    if vb <= vj:
        return False
    a, j = min(prev.a, b.a), min(prev.j, b.j)
    f = min(prev.cap, b.cap, reach(vj, 0.5 * min(prev.length, b.length), a, j))
    if f <= vb:
        return True  # the lines cannot outrun the blend

    def lost(v: float) -> float:  # time lost slowing f → v (and again speeding up)
        dv = f - v
        t = 2.0 * math.sqrt(dv / j) if dv * j <= a * a else dv / a + a / j
        return t - change_distance(f, v, a, j) / f

    return 2.0 * lost(vb) + seg.length / vb - 2.0 * seg.tlen / f < 2.0 * lost(vj)
