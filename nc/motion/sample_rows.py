"""A solved plan's next rows on plain floats where only a few are kept (issue 17, session 11).

On a dense CAM program a block lasts a cycle or two: `Planner._sample` samples up to CHUNK (64) cycles of the
plan with numpy, keeps the one or two that lie in the current block (or only reads the first, to see that it lies
in the next block and re-solve there) and drops the rest, and its ~40 numpy calls on tiny arrays cost more than
the arithmetic. `few_rows` makes the same decisions from the rows it needs only: the first, and those
`np.searchsorted(s, length + 1e-12, side="right")` probes (its binary search, replayed on rows computed on demand:
numpy's loop is the same bisection as `bisect_right`), and the rows kept. Each row is `Piecewise.at`, the same
operations in the same order as `Piecewise.sample`, and a line's points the same `start + u·(end − start)`, so
the buffer holds the same bits. Where more than FEW rows are kept, an arc's points, or a ramp runs on into the
next block, it leaves the planner untouched and `_sample` runs as before.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.motion.block import Block
from nc.motion.plan_state import _Plan
from nc.motion.profile import _lists0, _pos_at, _row_at  # Piecewise.at's steps (C functions compiled)

if TYPE_CHECKING:
    from nc.motion.planner import Planner

FEW = 6  # rows kept up to which plain floats beat numpy (a row ≈ 1 µs, numpy's sample ≈ 25 µs a call)
SLAB = 1024  # rows of a `_Slab`


class _Slab:
    """Rows for `few_rows`' buffers (session 30, decision bench B175): `np.array` of its row lists cost ≈ 7k
    instructions for two rows of three axes and ≈ 3k for their speeds (numpy discovers the nesting and packs each
    float), a slice of a slab made once ≈ 1.3k. The rows are written once, from C doubles (memoryviews compiled),
    and handed out as consecutive slices that never overlap; a full slab is replaced by a new one, and the old one
    lives on as long as a buffer sliced from it does. So each buffer is its own rows, as a fresh array's were: the
    same shape, dtype (float64), C order and values; only `.base` (the slab) differs, which nothing reads."""

    def __init__(self, m: int) -> None:
        self.m = m
        self.pos = np.empty((SLAB, m))
        self.vel = np.empty(SLAB)
        self._pv = self.pos  # (typed memoryviews where compiled, sample_rows.pxd)
        self._vv = self.vel
        self.at = 0


_slab = _Slab(3)


@cython.locals(sl=_Slab)
def _claim(m: int, rows: int) -> _Slab:
    """The slab whose rows `at - rows` … `at - 1` are now the caller's (`rows` <= SLAB): the current one, or a new
    one where it holds another axis count or too few rows left. Claimed before the caller writes or calls anything,
    so that another planner's few_rows or cruise takes the rows after them."""
    global _slab
    sl = _slab
    if sl.m != m or sl.at + rows > SLAB:
        sl = _slab = _Slab(m)
    sl.at += rows
    return sl


@cython.locals(T=cython.double, t_next=cython.double, base=cython.double, length=cython.double, x=cython.double,
               s=cython.double, u=cython.double, seg_len=cython.double, n=cython.Py_ssize_t, keep=cython.Py_ssize_t,
               lo=cython.Py_ssize_t, hi=cython.Py_ssize_t, mid=cython.Py_ssize_t, i=cython.Py_ssize_t,
               m=cython.Py_ssize_t, k=cython.Py_ssize_t, q0=cython.double, q1=cython.double, q2=cython.double,
               d0=cython.double, d1=cython.double, d2=cython.double, dur=cython.double, c=tuple, t0=list,
               pp=list, vv=list, aa=list, jj=list, b=Block, sl=_Slab, at=cython.Py_ssize_t)
def few_rows(pl: "Planner", p: _Plan, n: int) -> bool:
    """`Planner._sample(p, n)` for a path or ramp plan, when it keeps at most FEW rows or re-solves at the next
    block; False (nothing changed) where `_sample` must run."""
    T = pl.cfg.cycle
    t_next, base, pw = p.t_next, p.base, p.pw
    blocks = pl.blocks
    b = blocks[0]
    length = b.length
    # Row i (time t_next + T·i) is `pw.at(t)` less base: its lists taken once here, and each probe the position
    # alone on C doubles (a Python call of `at` a probe, boxed floats and a memo dict, were ≈ 1k instructions each,
    # session 29, decision bench B169). A row asked for twice is computed twice: the same operations, the same bits.
    c = _lists0(pw)
    dur, t0, pp, vv, aa, jj = c[0], c[1], c[2], c[3], c[4], c[5]
    more = len(blocks) > 1 and blocks[1].kind == "path"
    if more and _pos_at(t_next + T * 0, dur, t0, pp, vv, aa, jj) - base > length + 1e-12:
        if not (p.kind == "path" or (p.kind == "ramp" and not pl.held and p is not pl._fr_plan)):
            return False  # a ramp runs on into the next block without a solve: _sample's loop
        # _sample's re-solve at the block boundary, from the last emitted state
        p.t_next = (t_next + T * (n - 1)) + T
        s_last = pl.s
        pl._finish_block(True)
        pl.s = s_last - length
        pl.plan = None
        pl._carry = T if p.emitted else t_next
        pl._buf_pos = None
        return True
    keep = n
    if more:
        x = length + 1e-12
        lo, hi = 0, n
        while lo < hi:
            mid = (lo + hi) >> 1
            s = _pos_at(t_next + T * mid, dur, t0, pp, vv, aa, jj) - base
            if x < s:
                hi = mid
            else:
                lo = mid + 1
        if 0 < lo < n:
            keep = lo
    seg = b.seg
    if keep > FEW or seg.kind != "line" or seg.length <= 0.0:
        return False
    p.t_next = t_next + T * keep if keep < n else (t_next + T * (n - 1)) + T
    # seg.points(clip(s, 0.0, b.length)) of a line, per element; seg.end - seg.start the same float subtraction
    # as numpy's, on the lists (path.Segment's, bench B156; 3 axes on C doubles, as planner_cruise samples a cruise)
    start = seg.start_floats
    end = seg.end_floats
    seg_len = seg.length
    m = len(start)
    q0 = q1 = q2 = d0 = d1 = d2 = 0.0
    d = None
    if m == 3:
        q0, q1, q2 = start
        d0, d1, d2 = end[0] - q0, end[1] - q1, end[2] - q2
    else:
        d = [e - q for e, q in zip(end, start)]
    sl = _claim(m, keep)
    at = sl.at - keep
    got = []
    for i in range(keep):
        r = _row_at(t_next + T * i, base, dur, t0, pp, vv, aa, jj)
        got.append(r)
        sl._vv[at + i] = r[1]
        s = r[0]
        s = 0.0 if 0.0 >= s else s
        u = (length if length <= s else s) / seg_len
        if m == 3:
            sl._pv[at + i, 0] = q0 + u * d0
            sl._pv[at + i, 1] = q1 + u * d1
            sl._pv[at + i, 2] = q2 + u * d2
        else:
            for k in range(m):
                sl._pv[at + i, k] = start[k] + u * d[k]
    p.emitted = True
    pl._buf_pos = sl.pos[at:at + keep]  # (rows of their own: never overlapping another buffer's, `_Slab`)
    pl._buf_vel = sl.vel[at:at + keep]
    pl._buf_line = [b.move.line] * keep
    pl._buf_i = 0
    pl._buf_state = got
    return True


def slab_rows(pos: list, m: int, rows: int, v: float) -> tuple:
    """A cruise's buffers (`Planner._sample_cruise`; session 30, decision bench B176): `np.array(pos)` of its
    `rows` row lists of `m` floats and `np.full(rows, v)` as slices of a `_Slab` (as `few_rows`' buffers, bench
    B175): numpy's discovery of the nesting and a float packed at a time cost more than the copy of the doubles.
    The same shape, dtype, C order and values; rows beyond a slab's take numpy's arrays, as before."""
    if rows > SLAB:
        return np.array(pos), np.full(rows, v)
    sl = _claim(m, rows)
    at = sl.at - rows
    for i in range(rows):
        r = pos[i]
        for k in range(m):
            sl._pv[at + i, k] = r[k]
        sl._vv[at + i] = v
    return sl.pos[at:at + rows], sl.vel[at:at + rows]
