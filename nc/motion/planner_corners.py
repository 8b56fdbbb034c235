"""The planner's corner blends as they are pushed (decisions motion 42, 45) and the position filter's share λ
along the path (decision motion 43, nc.motion.share_zones). A mixin of `Planner`."""

from __future__ import annotations

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115; this module since bench B136)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.motion.corner_blends import blend_block
from nc.motion.block import Block
from nc.motion.plan_core import PlanCore  # the planner's C fields where compiled (bench B172)
from nc.motion.lookahead import Limits, change_distance
from nc.motion.share_zones import ShareZones


class CornerShares:
    """Methods of `nc.motion.planner.Planner` (its state is the planner's own: see that module's doc)."""

    def _corner(self, prev: Block, b: Block) -> int:
        """The junction prev → b (prev.vjunc set): a corner blend between them where one is built
        (decisions motion 42, 45), or, under the filter, a hard junction where λ < 1 planned raw.
        Returns the blocks added (the blend: 1). `_corner_at` (`Planner._push` calls that in C)."""
        return _corner_at(self, prev, b)

    def _may_blend(self, prev: Block) -> bool:
        """Whether the tail may still give path to a corner blend (decision motion 42): `_blend_room`."""
        return _blend_room(self, prev)

    def _now(self) -> float:
        """Path position (Block.s_end's scale) of the last sample handed out."""
        return _path_now(self)

    @cython.locals(self=PlanCore)
    def _share(self) -> float:
        """The filter's share λ at the present path position (nc.motion.share_zones)."""
        z = self._zones
        if z is None or not z.zones:
            lam = 1.0
        elif abs(self.v) < 1e-12:
            # At rest λ holds: the output is still settling there (F(p) ≠ p(t − D)). A plan starts only
            # once the filter has settled, where λ may change at once (a stop cuts the zones).
            lam = self._lam
        else:
            lam = z.lam(_path_now(self))
        self._lam = lam
        return lam

    @cython.locals(self=PlanCore)
    def share_rows(self, i: int, m: int) -> np.ndarray | None:
        """λ of buffer rows i … i + m − 1 as step() would take them one by one (`_share` after `_take`), for a
        stretch's push_many (nc.motion.stretch); None where λ is 1 throughout (no zone left)."""
        z = self._zones
        if z is None or not z.zones:
            return None
        out = np.empty(m)
        blk, popped, blocks = self._buf_blk, self._buf_popped, self.blocks
        for r in range(m):
            s, v, _ = self._buf_state[i + r]
            if not z.zones:
                lam = 1.0
            elif abs(v) < 1e-12:
                lam = self._lam
            else:
                b = blocks[blk[i + r] - popped] if blk is not None else blocks[0]
                self._share_s = b.s_end - b.length + s
                lam = z.lam(self._share_s)
            self._lam = out[r] = lam
        return out

    def share_standing(self, n: int) -> np.ndarray | None:
        """λ of n cycles standing (nc.motion.stretch.stand_stretch): the held one."""
        if self._zones is None or not self._zones.zones:
            return None
        return np.full(n, self._share())


@cython.locals(blk=Block, x=Block, top=cython.double, zones=ShareZones, lim=Limits)
def _corner_at(pl: CornerShares, prev: Block, b: Block) -> int:
    """The junction prev → b (prev.vjunc set): a corner blend between them where one is built
    (decisions motion 42, 45), or, under the filter, a hard junction where λ < 1 planned raw.
    Returns the blocks added (the blend: 1)."""
    zones = pl._zones
    if zones is not None and prev.vjunc <= 0.0:
        zones.stop(prev.s_end)
        return 0
    blk = None
    top = b.vtop if b.vtop > prev.vtop else prev.vtop  # max(prev.vtop, b.vtop)
    lim = pl.lim
    if zones is not None and zones.inside(prev.s_end, top):
        # λ stays below 1 here: not blended, the junction is taken as without the filter, and
        # that is what a blend must beat
        prev.vjunc = min(prev.vjunc, lim.junction(prev, b, raw=True))
    # `_may_blend` and `_now` as C calls (once a push each, session 28)
    if (lim.blend is None or zones is not None) and _blend_room(pl, prev):
        if zones is None or zones.blend_allowed(prev.s_end - prev.length, top, _path_now(pl),
                                                abs(pl.v) < 1e-12 and pl.plan is None):
            blk = blend_block(lim, prev, b, pl.cfg.path_tolerance or 0.0)
    if blk is None:
        if zones is not None and (prev.du_n > 1e-9 or "arc" in (prev.seg.kind, b.seg.kind)):
            if zones.hard(prev.s_end, top):
                prev.vjunc = min(prev.vjunc, lim.junction(prev, b, raw=True))
        return 0
    # Both lines gave path to it: the running lengths follow.
    prev.s_end -= blk.seg.tlen
    blk.s_end = prev.s_end + blk.length
    pl._path_s = blk.s_end
    if zones is not None:
        blk.vtop = min(blk.cap_hard, prev.vtop)
        zones.add_blend(blk.s_end - blk.length, blk.s_end, max(prev.vtop, b.vtop))
    for x in (prev, blk, b):
        pl._update_cap(x)
    blk.scan_plain = blk.kind == "path" and blk.seg is not None and blk.seg.kind != "arc"  # as `_push` sets it
    pl.blocks.append(blk)
    if lim.blend is not None:
        # The filter's windows walk the queue and their junction history side by side: the junction
        # prev → blend joins that history now, as any pushed block's does (b's comes with b).
        pl._need = max(pl._need, lim.blend.window(pl.blocks) + 1)
    return 1


# `_corner`'s helpers as C functions where compiled (planner_corners.pxd): a call to a method of the planner, a
# Python class, is an attribute lookup and a Python call (once a push each, session 28, decision bench B157).
@cython.locals(head=Block, room=cython.double, v=cython.double, tol=cython.double)
def _blend_room(pl: CornerShares, prev: Block) -> bool:
    """Whether the tail may still give path to a corner blend (decision motion 42): a tolerance
    to blend within, no hold (its ramp runs on across blocks), and no profile that could be
    caught by the shorter path: nothing planned yet, or the tail further beyond the active
    block than any stop from its speed needs, at half the least tangential limits."""
    x = pl.cfg.path_tolerance
    if x is None:
        return False
    tol = x
    if tol <= 0.0 or pl.held or pl._stopping:
        return False
    if not pl._started and pl.plan is None:
        return True
    head = pl.blocks[0]
    if prev is head:
        return False
    room = prev.s_end - prev.length - head.s_end
    v = abs(pl.v)
    return room >= change_distance(v if v > head.cap else head.cap, 0.0, pl._a_lo, pl._j_lo)  # max() spelt out


@cython.locals(b=Block)
def _path_now(pl: CornerShares) -> float:
    """Path position (Block.s_end's scale) of the last sample handed out."""
    blocks = pl.blocks
    if blocks:
        b = blocks[0]
        pl._share_s = b.s_end - b.length + (pl.s if pl._started else 0.0)
    return pl._share_s
