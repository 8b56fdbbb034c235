"""The planner's cruise sampling (decision motion 44): blocks run at their cap sampled across blocks without a
solve, and the buffer rows a stretch may take (nc.motion.stretch). A mixin of `Planner`."""

from __future__ import annotations

import math

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

if cython.compiled:  # C's floor, the function math.floor calls on a float (session 31, decision bench B204)
    from cython.cimports.libc.math import floor as _c_floor
else:
    _c_floor = math.floor

from nc.motion.block import Block
from nc.motion.plan_core import PlanCore  # the planner's C fields where compiled (bench B172)
from nc.motion.plan_state import CHUNK, _Plan
from nc.motion.sample_rows import slab_rows  # a cruise's buffers as slab rows (bench B176)

# Rows a cruise samples at a refill: whole blocks until at least this many. Its cost is per block (~45 blocks for
# 64 rows on the CAM program: 0.2-0.7 ms in one cycle, a real-time cycle's spike); the chain goes on at the next
# refill exactly as at a break (`_break_chain`, then `_cruise`), so the rows are the same bits (issue 17)
ROWS = 16


def _cruises(b: Block, v: float) -> bool:
    """A solve at b's start (or within b) from speed v at zero acceleration would cruise at v to b's end:
    its run ends there (b's end speed is not below its cap), its cap is v, nothing re-plans it per cycle.
    Not a corner blend (decision motion 45): measured, its solve does not give a cruise bit for bit.
    (A C function compiled: asked per block of a cruise, issue 17.)"""
    if not (b.kind == "path" and b.cap == v and b.vend >= v):
        return False
    mv = b.move
    return not mv.per_rev and mv.css is None and "G31" not in mv.tags and b.seg.kind != "blend"



# The filter stop's walks over the queue (nc.motion.filter_ramps), here where they run compiled: at a program's end
# each plan walked the whole queue in Python, ~3k instructions a block (bench B168). The same tests and sums in the
# same order as the Python they replace.
@cython.locals(b=Block, k=cython.Py_ssize_t, n=cython.Py_ssize_t, rest=cython.double, rapid_whole=cython.bint,
               cut_on=cython.bint)
def plain_rest(blocks: object, s: float, rapid_whole: bool, cut_on: bool) -> float | None:
    """`FilterStops._stop_rest`'s walk: the path left from s in blocks[0] to the end of the queue, None where a
    block is not plain (`FilterStops._plain`, the limits' `rapid_whole` and `cut_on` given) or a junction before
    the last block stops."""
    rest = -s
    n = len(blocks)
    k = 0
    for b in blocks:
        mv = b.move
        if not (b.kind == "path" and not mv.per_rev and mv.css is None and "G31" not in mv.tags
                and not (rapid_whole if b.rapid else cut_on)) or (k + 1 < n and b.vjunc <= 1e-9):
            return None
        rest += b.length
        k += 1
    return rest


@cython.locals(b=Block, k=cython.Py_ssize_t, n=cython.Py_ssize_t, vmax=cython.double, x=cython.double)
def tail_speed(blocks: object, cap: float) -> float:
    """`FilterStops._tail_speed`: the least cap and junction speed from blocks[0] to the end of the queue
    (min(vmax, x) spelt out: the first of equal ones kept, as `min`)."""
    vmax = cap
    n = len(blocks)
    k = 0
    for b in blocks:
        x = b.cap
        if x < vmax:
            vmax = x
        if k + 1 < n:
            x = b.vjunc
            if x < vmax:
                vmax = x
        k += 1
    return vmax


@cython.locals(b=Block, lo_a=cython.double, lo_j=cython.double, first=cython.bint)
def least_limits(blocks: object) -> tuple[float, float]:
    """(min(b.a for b in blocks), min(b.j for b in blocks)) in one walk (each `min` keeps the first of equal ones);
    ValueError on an empty queue, as `min` raises."""
    first = True
    lo_a = lo_j = 0.0
    for b in blocks:
        if first:
            lo_a, lo_j, first = b.a, b.j, False
            continue
        if b.a < lo_a:
            lo_a = b.a
        if b.j < lo_j:
            lo_j = b.j
    if first:
        raise ValueError("least_limits() of an empty queue")
    return lo_a, lo_j


@cython.locals(pl=PlanCore, k=cython.Py_ssize_t)
def _take_row(pl: object, i: int) -> int:
    """`CruiseSampling._take(i)`: the state after handing out buffer row i, a cruise's blocks before row i's
    finished (a C function compiled: called by `cut_rows` a stretch's part and by `Planner._step_path`)."""
    blk = pl._buf_blk
    if blk is not None:
        k = blk[i]
        while pl._buf_popped < k:
            pl._finish_block(True)  # keep_plan (positional: a keyword call builds a dict)
            pl._buf_popped += 1
    pl.position = pl._buf_pos[i]
    pl.line = pl._buf_line[i]
    pl.s, pl.v, pl.a = pl._buf_state[i]
    return 0


# A stretch's part (nc.motion.stretch, hil/stretch_pass.py `Pass._group`): here where they run compiled, typed on
# the planner's C fields (issue 17, session 31, decision bench B190; as Python they were ≈ 11k instructions a
# part, ≈ 2,600 parts a CAM run). nc.motion.stretch imports them under the same names.
@cython.locals(pl=PlanCore)
def refuses(pl: object, mv: object, per_rev: bool = False) -> bool:
    """Whether a stretch may not take rows of the front block's move: a feed-per-revolution path (unless the caller
    samples per revolution: Planner._check_spindle re-plans it from the measured speed), a thread, G31."""
    if mv.per_rev and not per_rev:
        p = pl.plan
        if p is not None and p.kind == "path":
            return True
    return mv.kind == "thread" or "G31" in mv.tags


@cython.locals(pl=PlanCore, i=cython.Py_ssize_t, m=cython.Py_ssize_t, j=cython.Py_ssize_t, off=cython.Py_ssize_t)
def cut_rows(pl: object, i: int, m: int, mv: object) -> tuple:
    """Take the buffer's rows i … i + m − 1 (the planner left as after their steps): (raw rows, λ, lines, path
    speeds, mv, the move of each row where they cross into a cruise's next block, else None)."""
    j = i + m - 1
    pos, vel, lines = pl._buf_pos, pl._buf_vel, pl._buf_line
    if i != 0 or m != len(pos):
        pos, vel, lines = pos[i:i + m], vel[i:i + m], lines[i:i + m]
    # (else the whole buffer: its own arrays and list, whose rows nothing writes again, not views of all of them:
    # a numpy slice costs ≈ 1k instructions; nearly half the parts of a CAM run, bench B191)
    moves = None
    blk = pl._buf_blk
    if blk is not None and blk[j] != pl._buf_popped:
        off = pl._buf_popped
        blocks = pl.blocks
        moves = [blocks[k - off].move for k in blk[i:i + m]]
    # the filter's share per row (decision motion 45); None without share zones, share_rows' own first test (its
    # Python call ≈ 600 instructions a part)
    lam = None if pl._zones is None else pl.share_rows(i, m)
    pl._buf_i = i + m
    _take_row(pl, j)
    return pos, lam, lines, vel, mv, moves


class CruiseSampling:
    """Methods of `nc.motion.planner.Planner` (its state is the planner's own: see that module's doc)."""

    @cython.locals(self=PlanCore)
    def _block_rows(self) -> int:
        """Buffer rows left that lie in blocks[0] (a stretch stays within one block: nc.motion.stretch)."""
        i, n = self._buf_i, 0 if self._buf_pos is None else len(self._buf_pos)
        blk = self._buf_blk
        if blk is None:
            return n - i
        j = i
        while j < n and blk[j] == self._buf_popped:
            j += 1
        return j - i

    @cython.locals(self=PlanCore)
    def _before_take(self) -> None:
        """What a step does before it takes its row: a cruise's next block checked again where a push came since
        (`_chain_ok`), the refill where the buffer ran out (a stretch makes these steps too, hil/stretch_pass.py)."""
        # (`_buf_done` spelt out, read once: a property call twice a step, issue 17)
        pos = self._buf_pos
        i = self._buf_i
        if pos is not None and i < len(pos):
            blk = self._buf_blk
            if blk is None:
                return
            k = blk[i]
            if k <= self._buf_popped or (bad := self._chain_ok(self.plan, k)) > k:
                return
            self._break_chain(bad)  # (it drops the buffer: the refill below)
        self._refill()

    @cython.locals(self=PlanCore)
    def _cruise_rows(self, n: int) -> int:
        """Of the next n buffer rows, how many a stretch may take across a cruise's blocks: those before the
        first block whose own solve would no longer cruise (`_chain_ok`, with the queue as it stands)."""
        i = self._buf_i
        m = min(n, 0 if self._buf_pos is None else len(self._buf_pos) - i)
        blk = self._buf_blk
        if blk is None or m <= 0:
            return m
        last = blk[i + m - 1]
        if last > self._buf_popped and (bad := self._chain_ok(self.plan, last)) <= last:
            while m > 0 and blk[i + m - 1] >= bad:
                m -= 1
        return m

    def _take(self, i: int) -> None:
        """The state after handing out buffer row i: a cruise's blocks before row i's are finished."""
        _take_row(self, i)

    def _cruising(self, b: Block, v: float) -> bool:
        return _cruises(b, v)

    @cython.locals(self=PlanCore)
    def _cruise(self, b: Block, t0: float) -> _Plan | None:
        """Decision motion 44: at its cap, with zero acceleration, a run whose end speed is the cap solves to
        constant speed to the end of its block, and so does the next block's solve while the same holds there.
        Such a chain is sampled across its blocks at once (no solve): positions as the per-block solves give
        them (tests/test_motion_cruise.py). A push may change the junction speeds far back in the queue
        (FilterCorners.window): once one came, each block of the chain is checked again when its first row is
        due, when its own solve would run (`_chain_ok`)."""
        v = self.v
        if self.held or self._stopping or self.a != 0.0 or v <= 0.0:
            return None
        self.lookahead()
        if not _cruises(b, v):
            return None
        return _Plan("cruise", None, math.inf, t0, queued=self._pushes)

    @cython.locals(self=PlanCore, b=Block, T=cython.double, v=cython.double, s0=cython.double, t_next=cython.double,
                   duration=cython.double, length=cython.double, seg_len=cython.double, x=cython.double,
                   u=cython.double, k=cython.Py_ssize_t, nb=cython.Py_ssize_t, n=cython.Py_ssize_t,
                   i=cython.Py_ssize_t, a=cython.Py_ssize_t, m=cython.Py_ssize_t, rows=cython.Py_ssize_t,
                   line=cython.bint, three=cython.bint, snap=cython.bint, q0=cython.double, q1=cython.double,
                   q2=cython.double, e0=cython.double, e1=cython.double, e2=cython.double, d0=cython.double,
                   d1=cython.double, d2=cython.double, carry=cython.double, y=cython.double, f=cython.double)
    def _sample_cruise(self, p: _Plan) -> None:
        """The rows of a cruise, whole blocks up to at least ROWS rows: each block as its own solve gives them
        (a constant-speed profile from s0 at the plan time t0, s = s0 + v·t, sampled a CHUNK at a time while
        t <= duration + 1e-9 cycles, as `_refill` and `_sample` do; the next block's t0 the time left over, as
        `_end_plan` carries it), and the snap of a block's start to where the last one ended (`_start_plan`)."""
        T = self.cfg.cycle
        v = self.v
        blocks = self.blocks
        s0, t_next, k, nb = self.s, p.t_next, 0, len(blocks)
        pos: list[list[float]] = []  # rows as plain floats (a block's one or two: numpy's calls cost more)
        st: list[float] = []
        offs: list[int] = []
        lines: list[int] = []
        carries: list[float] = []  # the plan time left over at the end of each block
        rows = 0
        end: list[float] = []  # the last block's end as floats
        q0 = q1 = q2 = e0 = e1 = e2 = d0 = d1 = d2 = 0.0
        while True:
            b = blocks[k]
            seg = b.seg
            start = seg.start_floats  # a line from the run feed keeps its lists: no array (bench B156)
            m = len(start)
            three = m == 3
            # _near(seg.start, the last block's end) on the lists, and the snap (session 12: each block's points
            # read once as floats); 3 axes on C doubles (the same comparisons, issue 17, bench B151)
            if three:
                q0, q1, q2 = start
                snap = (k > 0 and abs(q0 - e0) <= 1e-6 + 1e-5 * abs(e0) and abs(q1 - e1) <= 1e-6 + 1e-5 * abs(e1)
                        and abs(q2 - e2) <= 1e-6 + 1e-5 * abs(e2))
            else:
                snap = k > 0 and all(abs(q - r) <= 1e-6 + 1e-5 * abs(r) for q, r in zip(start, end))
            if snap:
                seg.start_floats = end  # blocks[k - 1].seg.end, as floats (lists are never changed in place)
                start = end
                q0, q1, q2 = e0, e1, e2
            end = seg.end_floats
            if three:
                e0, e1, e2 = end
                d0, d1, d2 = e0 - q0, e1 - q1, e2 - q2  # seg.end - seg.start: the same float subtraction
                d = None
            else:
                d = [e - q for e, q in zip(end, start)]  # seg.end - seg.start: the same float subtraction as numpy's
            duration = (b.length - s0) / v  # ruckig's duration of this profile, to the bit
            while True:
                # n = int(math.floor(y)) + 1, the rows left, on C's floor (n > 0: f >= 0; min(n, CHUNK): f >= CHUNK);
                # math.floor only where it raises (y not finite), as it did
                y = (duration - t_next) / T + 1e-9
                f = _c_floor(y)
                if f - f != 0.0:
                    n = int(math.floor(y)) + 1
                if not (t_next <= duration + 1e-12 and f >= 0.0):
                    break
                n = CHUNK if f >= CHUNK else int(f) + 1
                # t = t_next + T·arange(n), s = s0 + clip(t, 0, duration)·v and a line's points at clip(s, 0,
                # length) element by element: the same operations, so the same bits (nc.motion.sample_rows);
                # loops, not comprehensions, so that compiled the floats stay C doubles
                length = b.length
                line = seg.kind == "line" and seg.length > 0.0
                seg_len = seg.length if line else 1.0
                sc = []
                ko, lo = k, b.move.line  # each row's block offset and line, appended with the row (not `+= [k] * n`)
                for i in range(n):
                    x = t_next + T * i
                    if 0.0 >= x:
                        x = 0.0
                    if duration <= x:
                        x = duration
                    x = s0 + x * v
                    st.append(x)
                    offs.append(ko)
                    lines.append(lo)
                    if 0.0 >= x:
                        x = 0.0
                    if length <= x:
                        x = length
                    if line:
                        u = x / seg_len
                        if three:
                            pos.append([q0 + u * d0, q1 + u * d1, q2 + u * d2])
                        else:
                            pos.append([start[a] + u * d[a] for a in range(m)])
                    else:
                        sc.append(x)
                if not line:
                    pos += seg.points(np.array(sc)).tolist()
                t_next = (t_next + T * (n - 1)) + T
                rows += n
            carry = t_next - duration if t_next - duration > 1e-12 else t_next - duration + T
            carries.append(carry)
            if rows >= ROWS or k + 1 >= nb or not _cruises(blocks[k + 1], v):
                break
            k, s0, t_next = k + 1, 0.0, carry
        p.carry = carry  # (the plan's fields written once, for its last block)
        p.last = k
        p.emitted = True
        if pos:
            self._buf_pos, self._buf_vel = slab_rows(pos, len(pos[0]), rows, v)  # np.array(pos), np.full(rows, v)
        else:
            self._buf_pos, self._buf_vel = np.empty((0, len(self.axes))), np.full(rows, v)
        self._buf_line = lines
        self._buf_state = [(x, v, 0.0) for x in st]
        self._buf_blk = offs
        self._buf_popped = 0
        self._buf_i = 0
        self._buf_carry = carries

    @cython.locals(self=PlanCore)
    def _chain_ok(self, p: _Plan | None, upto: int) -> int:
        """The first block offset up to `upto` (where a cruise's next row lies) whose own solve would no longer
        cruise: a push since the chain was sampled changed its end speed (the same check `_cruise` makes, at
        the cycle the per-block solve would make it); `upto + 1` when all still cruise."""
        if p is None or p.kind != "cruise" or self._pushes == p.queued:
            return upto + 1
        self.lookahead()
        popped, blocks, v = self._buf_popped, self.blocks, self.v
        for k in range(popped + 1, upto + 1):
            if not _cruises(blocks[k - popped], v):
                return k
        return upto + 1

    @cython.locals(self=PlanCore)
    def _break_chain(self, k: int) -> None:
        """Block offset k does not cruise any more: the chain ends at the end of block k - 1, as that block's
        own plan would end there (`_end_plan`); the next refill solves block k."""
        while self._buf_popped < k - 1:
            self._finish_block(True)
            self._buf_popped += 1
        self._carry = self._buf_carry[k - 1]
        self.position = self.blocks[0].seg.end.copy()
        self.a = 0.0
        self._finish_block()
        self.plan = None
        self._buf_pos = None
        self._buf_blk = None
