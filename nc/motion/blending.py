"""Corner speeds under the post-interpolation filter (nc.motion.smoothing).

With the filter, a tangent jump Δu crossed at speed v is a velocity step v·Δu_i on each axis. The
two moving averages (T1 ≥ T2 window lengths) turn the steps into an acceleration
v·S_i(T1 window)/T1 and a jerk v·(S_i(T1 window) − S_i(the T1 window T2 earlier))/(T1·T2), S_i the
*signed* sum of the steps inside (issue 18): zig-zags from rounded coordinates cancel there, and on
a curve consecutive windows hold nearly the same sum. The caps are found first from the unsigned
sums (safe, cheap: the search for the stretch below), then raised to what the signed window sums
allow at the speed the windows are crossed (`_refine`). The deviation from the path is the kernel
model of nc.motion.deviation, evaluated per junction (`_tolerance`).

Why this file is over 500 lines: it is one class whose `window` runs on every push of a dense program;
its 3-axis sums are spelt out inline (issue 17: calls and numpy on 3-element arrays cost more than the
arithmetic), its sliding maxima are `_MaxQ`'s C methods (decision bench B134), and splitting the class would put its shared per-push state behind
attribute hops on that path. The module-level helpers at the end (`_held_caps`, `_refined` and theirs: typed loops
over memoryviews, decision bench B133) stay here because this module is in the compiled unit (setup.py) and
a new one would run as Python.

Every new junction J caps the junctions within one window behind it (J included) by
budget / (sum over that stretch). For any time window W, the fastest junction m of W lies within
one window behind W's last junction, whose cap was computed over a sum that holds all of W, so
Σ_W v·|Δu| ≤ v_m·Σ_W |Δu| ≤ budget.
"""

from __future__ import annotations

import math
from array import array
from collections import deque
from collections.abc import Sequence

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

if cython.compiled:  # C's fma and sqrt for `_deviations`' C form (decision bench B163) and `_cap_at` (B187)
    from cython.cimports.libc.math import fma as _fma, sqrt as _c_sqrt
else:
    _c_sqrt = math.sqrt

from nc.motion.block import Block
from nc.motion.deviation import CornerBound, KernelDeviation
from nc.motion.limits import MAX_FACTOR, MotionConfig  # (not from nc.motion.shares: it cimports FilterCorners, B182)
from nc.motion.profile import _at_or_above  # bisect_left on C doubles, shared with nc.motion.shares

_INF = math.inf  # a C double where compiled (blending.pxd): math.inf is a module attribute lookup
_NAN = math.nan  # the same (decision bench B187), math.nan's bits

USAGE_SCALE = 4.0  # below this many times the top speed a junction's budget use is worth refining
# The junction history's front: TRIM junctions dropped at a time once no scan reads them; BULK the drop before session
# 18 (every junction before _h0 once 4,096 were), whose cut nc.motion.shares still answers by (FilterCorners._seq_v)
TRIM = 32
BULK = 4096
_BULK = BULK  # a C constant where compiled (blending.pxd, decision bench B188); the name tests read stays


def _axis_cap(si: float, sg: float, bj: float, ba: float, c: float) -> float:
    """`FilterCorners._cap`'s bound of one axis: c lowered to the jerk budget bj over the jerk the stretch asks (si,
    at most twice the signed sum sg) and to the acceleration budget ba over sg (a C function where compiled: the
    3-axis case and the general one both call it)."""
    ja = si if si < 2.0 * sg else 2.0 * sg
    if ja > 1e-12:
        x = bj / ja
        if x < c:
            c = x
    if sg > 1e-12:
        x = ba / sg
        if x < c:
            c = x
    return c


class _MaxQ:
    """A sliding maximum: (sequence number, value) entries, values falling from the front, held in seqs[head:n],
    vals[head:n] (a cdef class with C methods where compiled, blending.pxd: the deque of tuples it replaces cost a
    method call, a tuple and generic indexing per operation, decision bench B134). The two are array.array buffers,
    typed memoryviews where compiled (decision bench B153: the lists of boxed numbers were an append, a pop and a
    float and an int object per entry); as Python they index to plain floats and ints."""

    def __init__(self) -> None:
        self.seqs = array("q", bytes(8 * 64))
        self.vals = array("d", bytes(8 * 64))
        self.head = 0
        self.n = 0

    def _grow(self) -> None:
        """Twice the room, the entries copied (a new buffer: one exporting its memory cannot be resized)."""
        n = self.n
        seqs = array("q", bytes(16 * n))
        vals = array("d", bytes(16 * n))
        for i in range(n):
            seqs[i] = self.seqs[i]
            vals[i] = self.vals[i]
        self.seqs, self.vals = seqs, vals

    def push(self, seq: int, x: float) -> None:
        """Append (seq, x), dropping the entries at the back no larger than x."""
        n = self.n
        while n > self.head and self.vals[n - 1] <= x:
            n -= 1
        self.n = n
        if n == len(self.vals):  # (compiled: the memoryview's shape[0])
            self._grow()
        self.vals[n] = x
        self.seqs[n] = seq
        self.n = n + 1

    def push_front(self, seq: int, x: float) -> None:
        """Extend it backwards by an entry older than all it holds."""
        if self.n == self.head or x > self.vals[self.head]:
            if self.head > 0:
                self.head -= 1
                self.seqs[self.head] = seq
                self.vals[self.head] = x
            else:
                n = self.n
                if n == len(self.vals):  # (compiled: the memoryview's shape[0])
                    self._grow()
                for i in range(n, 0, -1):
                    self.seqs[i] = self.seqs[i - 1]
                    self.vals[i] = self.vals[i - 1]
                self.seqs[0] = seq
                self.vals[0] = x
                self.n = n + 1

    def drop(self, seq_m: int) -> None:
        """Drop the entries older than seq_m from the front."""
        h, n = self.head, self.n
        while h < n and self.seqs[h] < seq_m:
            h += 1
        if h >= 64 and 2 * h >= n:  # the dropped entries' room used again now and then
            for i in range(h, n):
                self.seqs[i - h] = self.seqs[i]
                self.vals[i - h] = self.vals[i]
            self.n = n - h
            h = 0
        self.head = h

    def front(self) -> float:
        return self.vals[self.head]


class FilterCorners:
    def __init__(self, cfg: MotionConfig, acc: Sequence[float], jerk: Sequence[float]) -> None:
        n1, n2 = cfg.filter_cycles()
        t1, t2 = n1 * cfg.cycle, n2 * cfg.cycle
        self.t_a = t1  # window of the acceleration sum (s)
        self.t_j = t1 + t2  # window of the jerk sum (s)
        sc = cfg.share_corner
        self.budget_a = tuple(sc * a * t1 for a in acc)
        self.budget_j = tuple(sc * j * t1 * t2 for j in jerk)
        # Between lines only, the curvature share (arcs' centripetal terms, curvature jumps) is
        # unused: the filter's corners may have it too (issue 18, decision motion 38).
        lines = (sc + cfg.share_curvature) / sc if sc > 0.0 else 1.0
        self.budget_al = tuple(x * lines for x in self.budget_a)
        self.budget_jl = tuple(x * lines for x in self.budget_j)
        # per axis the smaller of the two (window's cap from the unsigned sums), between lines and not
        self._bmin = (tuple(a if a < j else j for a, j in zip(self.budget_al, self.budget_jl)),
                      tuple(a if a < j else j for a, j in zip(self.budget_a, self.budget_j)))
        self.tol = cfg.path_tolerance
        self.kd = KernelDeviation(n1, n2, cfg.cycle)
        self.cb = CornerBound(self.kd)  # the proved isolated-corner cap (decision motion 73)
        # kd's half window and G(0), and the tolerance, as C doubles for `_tolerance`'s quick test (decision bench
        # B153: attribute lookups on the KernelDeviation object and a boxed compare a push)
        self._half, self._g0 = float(self.kd.half), float(self.kd.g0)
        self._tol_v = math.inf if self.tol is None else float(self.tol)
        # G's table and np.interp's slopes between its points, for `_held_caps` (decision bench B133)
        gy, gg = self.kd._y, self.kd._g
        self._gy, self._gg = gy.copy(), gg.copy()
        self._gs = np.array([(float(gg[i + 1]) - float(gg[i])) / (float(gy[i + 1]) - float(gy[i]))
                             for i in range(len(gy) - 1)] or [0.0])
        self._iso_k = 0.25 * self.cb.span * self.cb.span  # isolated_cap's quick test (s²)
        self._boost: dict[tuple[float, float], float] = {}  # braking's growth per (a, j)
        self.t2sum = t1 * t1 + t2 * t2
        self._arc_k = (n1 * n1 + n2 * n2 - 2) * cfg.cycle * cfg.cycle  # arc_speed's shrink factor (s²)
        # One window of T1+T2 for both sums: a T1 window lies inside it.
        self.budget = tuple(min(ba, bj) for ba, bj in zip(self.budget_a, self.budget_j))
        self._axes = len(self.budget)
        # The junctions' running sums, a row each beside _hist (row k + _cs_off for hist[k]): Σ|Δu| per axis and
        # Σ|Δu| norms (`cum`), then the signed Σ Δu per axis (`scum`), C doubles (decision bench B189: they were two
        # tuples of float objects on each Block, made a push and read as objects)
        self._csw = 2 * self._axes + 1
        self._cs = array("d", bytes(8 * self._csw * 256))
        self._cs_off = 0
        self._scratch(64, 16, 64)  # `_held_caps`' arrays, grown as a call needs (decision bench B163)
        self._r_scratch(64)  # `_refined`'s, the same (decision bench B187)
        self._r_ba, self._r_bj = np.empty(self._axes), np.empty(self._axes)
        self._r_sums = np.empty((4, self._axes))
        self._x_gy, self._x_gg, self._x_gs = self._gy, self._gg, self._gs  # the same, typed memoryviews compiled
        # Junctions still inside some filter window, executed or not (for the sums).
        self._hist: list[Block] = []
        self._hist_s: list[float] = []  # their s_end, side by side: bisected without a key (issue 17)
        # window's search: the last two _cap(k) `_taken` found, as (k, cap) (C fields, no dict: decision bench B134;
        # _cap is a function of the search's state, so a value not kept is found again the same)
        self._w_k1 = self._w_k2 = -1
        self._w_c1 = self._w_c2 = 0.0
        self._clear()
        # The longest any window can be: no path speed or acceleration exceeds the norm of the
        # axis limits (a path direction can use every axis at once).
        vmax = math.sqrt(sum(cfg.limit(a).max_velocity ** 2 for a in cfg.axes))
        amax = math.sqrt(sum(cfg.limit(a).max_acceleration ** 2 for a in cfg.axes))
        self.span_max = vmax * self.t_j + amax * self.t_j ** 2
        self.amax = amax

    def _scratch(self, n: int, rows: int, cols: int) -> None:
        """`_held_caps`' arrays with room for n junctions and a kernel matrix of rows × cols (decision bench B163:
        typed memoryviews where compiled, kept from call to call, sliced to each call's sizes; a numpy array and a
        memoryview made afresh were ≈ 2.4k instructions each, eight a call)."""
        self._x_s, self._x_room, self._x_ct, self._x_rc = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        self._x_vb, self._x_se, self._x_rm, self._x_e = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        self._x_du = np.empty((n, self._axes))
        self._x_w = np.empty((rows, cols))

    def _r_scratch(self, n: int) -> None:
        """`_refined`'s arrays with room for n junctions (decision bench B187: kept from call to call, as
        `_scratch`'s)."""
        self._r_s, self._r_vb, self._r_al, self._r_vt = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        self._r_du = np.empty((n, self._axes))
        self._r_pre = np.empty((n + 1, self._axes))

    def _cs_room(self, last: int) -> int:
        """Room in `_cs` for hist[last]'s row: the rows still held (hist[0:last]) moved to the front, into a
        buffer twice as large where they would fill over half of it (a new one: a buffer exporting its memory
        cannot be resized, see `_MaxQ._grow`)."""
        cw, off = self._csw, self._cs_off
        n = len(self._cs)  # (compiled: the memoryview's shape[0])
        if 2 * (last + 1) * cw > n:
            n = 4 * (last + 1) * cw
        cs = array("d", bytes(8 * n))  # (compiled: a typed memoryview, the copy a C loop: blending.pxd)
        src = self._cs
        for i in range(last * cw):
            cs[i] = src[off * cw + i]
        self._cs = cs
        self._cs_off = 0
        return 0

    def _clear(self) -> None:
        self._hist.clear()
        self._cs_off = 0  # (no rows held)
        self._hist_s.clear()
        # nc.motion.shares' per-junction verdicts, beside _hist (issue 17, session 11): `_vt` their vtop (fixed at
        # the push), `_sc` the scan's verdict (None: to be found again), `_sc_dirty` the first index whose inputs
        # a push may have changed since (window, _tolerance), `_sc_head` the head block's cap the verdicts of the
        # junctions up to it were found with (their next block is the queue's head).
        self._vt: list[float] = []
        self._sc: list[float | None] = []
        self._sc_dirty = 0
        self._sc_head = math.nan
        # Kept by nc.motion.shares between scans (session 15): `_sc_ok` a range of _sc found already (no None
        # in it), `_vq` the sliding maximum of _vt over the range `_vq_at` the last scan read.
        self._sc_ok = (0, 0)
        self._vq: deque[tuple[int, float]] = deque()
        self._vq_at = (0, 0)
        self._h0 = 0  # first entry of _hist still within reach of a window
        self._m = 0  # where the last search for the first junction taken ended
        self._seq0 = 0  # junctions dropped from the front of _hist so far
        self._seq_v = 0  # ... and where a drop of every junction before _h0 once it passed BULK would have cut
        self._lim_s = -math.inf  # path position of the newest junction the tolerance limits
        self._arc_s = -math.inf  # path position where the newest arc block ends
        # The last window's budget share, for the next one: J's block (None: none yet), sequence number of the
        # stretch's first junction, c_bud. Every queued junction of that stretch has vbud <= c_bud. (Three C
        # fields, not a tuple of a Block, an int and a float made a push: decision bench B188.)
        self._bud_b: Block | None = None
        self._bud_seq = 0
        self._bud_c = 0.0
        # Sequence number from which the queued junctions' vbud rise (older <= newer) up to J (issue 17): a walk that
        # lowers them to a cap, newest first, stops at the first one already at or below it.
        self._mono = 0
        # Sliding maxima over _hist[_m:] as (sequence number, value) of the blocks' tangential
        # acceleration, vtop and length.
        self._maxima = (_MaxQ(), _MaxQ(), _MaxQ())

    def touch(self) -> None:
        """Every junction's caps may have changed (an override, dry run): nc.motion.shares finds its verdicts
        again. Code that changes a queued junction's vjunc, vbud, vtol, vctol or cap outside window/_tolerance
        (and the planner's head block) must call it too: the kept verdicts would not see the change
        (tests/test_motion_shares_kept.py compares them with the walk)."""
        self._sc_dirty = 0
        self._sc_head = math.nan

    def corner_budget(self, du: Sequence[float], lines: bool = False) -> float:
        """The acceleration and jerk budgets' cap of one isolated tangent jump."""
        v = math.inf
        for d, ba, bj in zip(du, self.budget_al if lines else self.budget_a,
                             self.budget_jl if lines else self.budget_j):
            if d > 1e-12:
                v = min(v, ba / d, bj / d)
        return v

    @cython.locals(v=cython.double, d=cython.double, x=cython.double, room=cython.double)  # its arguments: blending.pxd
    def corner_caps(self, du: Sequence[float], du_n: float, lines: bool, acc: float) -> tuple[float, float]:
        """(corner_budget(du, lines), corner_tolerance(du_n, acc)): one call a pushed junction, 3 axes spelt out
        (issue 17; min(a, b) / d is min(a / d, b / d) exactly, so `_bmin` serves for the two budgets)."""
        if len(du) != 3:
            return self.corner_budget(du, lines), self.corner_tolerance(du_n, acc)
        bm = self._bmin[0 if lines else 1]
        v = math.inf
        d = du[0]
        if d > 1e-12:
            x = bm[0] / d
            if x < v:
                v = x
        d = du[1]
        if d > 1e-12:
            x = bm[1] / d
            if x < v:
                v = x
        d = du[2]
        if d > 1e-12:
            x = bm[2] / d
            if x < v:
                v = x
        tol = self.tol
        if tol is None or du_n <= 1e-12:
            return v, math.inf
        room = tol - du_n * acc * self.t2sum / 192.0  # `braking` without a jerk
        return v, 0.0 if room <= 0.0 else room / (du_n * self.kd.g0)

    @cython.locals(leg=cython.double, top=cython.double)
    def isolated_cap(self, du_n: float, acc: float, jerk: float, b1: Block, b2: Block) -> float:
        """The proved cap of the line-line corner b1 → b2 alone in its filter windows (decision motion 73:
        nc.motion.deviation.CornerBound), for any raw profile within the blocks' acceleration and the solves'
        raised jerk (shares.MAX_FACTOR times theirs); 0 where it cannot be shown alone."""
        leg = b1.length if b1.length < b2.length else b2.length
        if self.tol is None or leg < self._iso_k * acc:
            # (a quarter of acc·span² is less than the path a window reaches from rest at zero acceleration under the
            # raised jerk whenever that reaches acc within 0.63 of the span: CornerBound.cap's 0, found cheaply
            # for the CAM programs' short blocks; 0 is always safe, the old cap stays)
            return 0.0
        # Where the leg after it holds a filter start (nc.motion.filter_ramps: a ramp far above the axis limits to
        # the block's top speed, a filter window's cruise at it, then braking), that start, checked against
        # N1.053 itself, needs the room a faster corner would take: it gains more there (a 100 mm square, session
        # 23: the corner 2 cycles sooner, the start 20 later). The old cap stays there, any lower one being safe.
        top = b2.vtop
        if b2.length >= top * self.t_j + top * top / (2.0 * b2.a) + top * b2.a / (2.0 * b2.j):
            return 0.0
        return self.cb.cap(self.tol, du_n, acc, MAX_FACTOR * jerk, b1.length, b2.length, b1.vtop, b2.vtop)

    def corner_tolerance(self, du_n: float, acc: float) -> float:
        """The path tolerance's cap of one isolated tangent jump of norm du_n: the deviation model
        is `_tolerance`'s, except that a corner whose braking alone cuts the tolerance is an
        exact stop (0). The corner's own term of the kernel model, alone: v·|Δu|·G(0)
        (nc.motion.deviation), a cap that only falls, so the model may charge each step at
        min(c, this cap)."""
        if self.tol is None or du_n <= 1e-12:
            return math.inf
        room = self.tol - self.braking(du_n, acc)
        if room <= 0.0:
            return 0.0
        return room / (du_n * self.kd.g0)

    def braking(self, du_n: float, acc: float, jerk: float = 0.0) -> float:
        """How far braking into and speeding out of a corner inside the filter window cuts it:
        about |Δu|·a·(T1²+T2²)/192 (measured on 90° corners: 1/240). When that alone exceeds the
        tolerance the corner is an exact stop (0), which the filter then passes exactly.
        `jerk`: the blocks' tangential jerk, when a solve raises it to shares.MAX_FACTOR times
        that (nc.motion.shares): a higher jerk reaches the deceleration closer to the corner, so
        the term grows by the kernel's own ratio for the two jerks."""
        b = du_n * acc * self.t2sum / 192.0
        return b * self._boost_ratio(acc, jerk) if jerk > 0.0 else b

    def braking_pair(self, du_n: float, acc: float, jerk: float) -> tuple[float, float]:
        """(braking(du_n, acc), braking(du_n, acc, jerk)) in one call: the shares' scan asks both per junction."""
        b = du_n * acc * self.t2sum / 192.0
        return b, b * self._boost_ratio(acc, jerk) if jerk > 0.0 else b

    def _boost_ratio(self, acc: float, jerk: float) -> float:
        key = (acc, jerk)
        r = self._boost.get(key)
        if r is None:
            r = self._boost[key] = max(1.0, self.kd.speed_up(acc, jerk * MAX_FACTOR) / self.kd.speed_up(acc, jerk))
        return r

    def arc_speed(self, radius: float) -> float:
        """Highest speed on an arc whose filtered radius shrinks by no more than the tolerance.

        A moving average of n samples of a circle stepping x = v·T/r rad a cycle keeps the radius
        times D_n(x) = (1/n)·Σ cos(m_k·x), m_k = k − (n−1)/2, and cos y ≥ 1 − y²/2 gives
        D_n ≥ 1 − x²·(n²−1)/24 (Σ m_k² = n(n²−1)/12); two in cascade keep D_n1·D_n2 ≥ 1 − (sum of
        both losses). So the shrink is at most v²·T²·(n1² + n2² − 2)/(24·r) at any speed up to v: an
        upper bound, not the second-order estimate it was written from (decision motion 64; it used
        (T1+T2)², 2× the T1² + T2² of equal windows, which cost arcs √2 of their speed).
        """
        if self.tol is None or radius <= 0.0:
            return math.inf
        if self._arc_k <= 0.0:
            return math.inf  # no filter: nothing shrinks
        return math.sqrt(24.0 * self.tol * radius / self._arc_k)

    @cython.locals(j_new=Block, tail=Block, b=Block, h0=cython.Py_ssize_t, last=cython.Py_ssize_t,
                   m=cython.Py_ssize_t, m0=cython.Py_ssize_t, k=cython.Py_ssize_t, idx=cython.Py_ssize_t,
                   seq=cython.Py_ssize_t, seq_m=cython.Py_ssize_t, seq0=cython.Py_ssize_t, cut=cython.Py_ssize_t,
                   lo_q=cython.Py_ssize_t, stop=cython.Py_ssize_t, mono=cython.Py_ssize_t, lim=cython.Py_ssize_t,
                   depth=cython.Py_ssize_t, s_j=cython.double, span_max=cython.double, t_w=cython.double,
                   top=cython.double, t_w2=cython.double, pad=cython.double, two_al=cython.double, v_hi=cython.double,
                   c=cython.double, c_bud=cython.double, c2=cython.double, lines=cython.bint, fast=cython.bint,
                   hist=list, hist_s=list, acc_q=_MaxQ, top_q=_MaxQ, len_q=_MaxQ, a0=cython.double,
                   a1=cython.double, a2=cython.double, a3=cython.double, d0=cython.double, d1=cython.double,
                   d2=cython.double, bud_seq=cython.Py_ssize_t, bud_c=cython.double, budget_a=tuple,
                   budget_j=tuple, s_h=cython.double, cw=cython.Py_ssize_t, co=cython.Py_ssize_t,
                   cp=cython.Py_ssize_t, i=cython.Py_ssize_t)
    def window(self, blocks: Sequence["Block"]) -> int:
        """Cap the junctions within one filter window behind the newest junction J (the end of
        blocks[-2]); returns how many blocks from the tail need a new backward pass.

        A window of duration T that ends at J (crossed at ≤ c) covers at most
        span(c) = c·T + A·T²/2 of path (going back in time the speed rises by at most A·t, A the
        highest tangential acceleration of the blocks in reach), so every junction sharing a
        window with J lies within span(c) behind it. Going back junction by junction, the cap is
        budget/sum until the span that cap (or the fastest J can ever be crossed, `vtop`) allows
        no longer reaches the next junction; every junction in that span gets the cap. Then for
        any window, with J its last junction: Σ v·|Δu| ≤ c_J · (the sum c_J was made from) ≤
        budget. The spans shrink as the sums grow, so the junctions taken form a suffix of the
        history; its first index never moves back while J advances (sums only grow, J only
        moves away), so it is found by stepping on from where the previous junction's search
        ended. One window of T1+T2 serves both budgets (per axis the smaller of the
        acceleration and jerk budget: a T1 window lies inside it) and the tolerance, one cap
        for all three (the least of them, which makes the span no longer than any of theirs).
        Junctions of blocks already executed still count (they stay in self._hist).
        """
        if len(blocks) < 2:
            return 0
        j_new = blocks[-2]
        j_new.vbase = j_new.vjunc
        hist = self._hist
        if j_new.du is None:
            # A stop: the planner waits there for the filter to settle, so no window holds
            # junctions from both sides of it.
            self._clear()
            return 0
        h0 = self._h0
        last = len(hist)
        # J's running sums, a row of `_cs` (decision bench B189: two tuples and seven float objects a push before)
        cw = self._csw
        if (last + self._cs_off + 1) * cw > len(self._cs):  # (compiled: the memoryview's shape[0])
            self._cs_room(last)
        co = (last + self._cs_off) * cw
        cp = co - cw  # the junction before J's row, where there is one within reach
        du = j_new.du
        dv = j_new.dv
        if self._axes == 3:  # the common case spelt out (this runs once per pushed block)
            # (each item read into a C double first: the sums are C additions of the same doubles, decision bench
            # B171)
            if last > h0:
                a0, a1, a2, a3 = self._cs[cp], self._cs[cp + 1], self._cs[cp + 2], self._cs[cp + 3]
            else:
                a0 = a1 = a2 = a3 = 0.0
            d0, d1, d2 = du[0], du[1], du[2]
            self._cs[co] = a0 + d0
            self._cs[co + 1] = a1 + d1
            self._cs[co + 2] = a2 + d2
            self._cs[co + 3] = a3 + j_new.du_n
            if last > h0:
                a0, a1, a2 = self._cs[cp + 4], self._cs[cp + 5], self._cs[cp + 6]
            else:
                a0 = a1 = a2 = 0.0
            d0, d1, d2 = dv[0], dv[1], dv[2]
            self._cs[co + 4] = a0 + d0
            self._cs[co + 5] = a1 + d1
            self._cs[co + 6] = a2 + d2
        else:
            for i in range(cw):  # cum's axes and norm, then scum's axes: the same additions
                a0 = self._cs[cp + i] if last > h0 else 0.0
                if i < self._axes:
                    d0 = du[i]
                elif i == self._axes:
                    d0 = j_new.du_n
                else:
                    d0 = dv[i - self._axes - 1]
                self._cs[co + i] = a0 + d0
        hist.append(j_new)
        s_j = j_new.s_end
        hist_s = self._hist_s
        hist_s.append(s_j)
        self._vt.append(j_new.vtop)
        self._sc.append(None)
        span_max = self.span_max
        s_h = hist_s[h0]  # (each read into a C double first: no float object a test, decision bench B188)
        while s_j - s_h > span_max:
            h0 += 1
            s_h = hist_s[h0]
        if h0 + self._seq0 - self._seq_v > _BULK:
            self._seq_v = self._seq0 + h0  # where the bulk drop would have cut (nc.motion.shares reads it)
        # The junctions no scan reads any more (further behind the queue's head than twice the longest window: a
        # scan's reach behind its position is at most one) are dropped TRIM at a time (session 18: dropped 4,096
        # at a time, their blocks were freed in one push, a 13.9 ms cycle on the CAM program)
        b = blocks[0]
        cut = _at_or_above(hist_s, b.s_end - b.length - 2.0 * span_max, 0, h0)  # bisect_left in C (B153)
        if cut >= TRIM:
            del hist[:cut]
            del hist_s[:cut]
            del self._vt[:cut]
            del self._sc[:cut]
            self._sc_dirty = max(0, self._sc_dirty - cut)
            lo, hi = self._sc_ok
            self._sc_ok = (max(0, lo - cut), max(0, hi - cut))
            lo, hi = self._vq_at
            if lo >= cut:  # the sliding maximum's range, moved with the junctions
                self._vq = deque([(k - cut, x) for k, x in self._vq])
                self._vq_at = (lo - cut, hi - cut)
            else:
                self._vq.clear()
                self._vq_at = (0, 0)
            self._seq0 += cut
            self._cs_off += cut  # (the sums' rows stay where they are: `_cs_room` moves them when it must)
            self._m -= cut
            last -= cut  # J's index, and its sequence number seq0 + last, stay the same
            h0 -= cut
        self._h0 = h0
        # The junction before J: its next block may have changed (a corner blend trims it and sets its cap).
        if last - 1 < self._sc_dirty:
            self._sc_dirty = max(0, last - 1)
        # The search starts where the previous junction's ended; the maxima of tangential
        # acceleration and vtop are kept over hist[m..last] for that m.
        m = self._m
        if m < h0:
            m = h0
        maxima = self._maxima
        acc_q, top_q, len_q = maxima
        seq, seq_m = self._seq0 + last, self._seq0 + m
        # the sliding maxima: append (dropping the smaller values before) and drop what fell out front
        # (_MaxQ's C methods where compiled, decision bench B134)
        acc_q.push(seq, j_new.a)
        acc_q.drop(seq_m)
        top_q.push(seq, j_new.vtop)
        top_q.drop(seq_m)
        len_q.push(seq, j_new.length)
        len_q.drop(seq_m)
        tail = blocks[-1]
        t_w = self.t_j
        # J is crossed no faster than either block beside it can run.
        top = tail.vtop if tail.vtop < j_new.vtop else j_new.vtop
        t_w2 = t_w * t_w
        # Going back in time from J the speed rises by at most the tangential acceleration.
        pad = 0.5 * acc_q.front() * t_w2
        two_al = 2.0 * acc_q.front() * len_q.front()
        v_hi = top_q.front()
        # J's block is the tail of the previous call, unless a stop cleared; `scan_plain` (set as a block joins the
        # queue): a path block that is no arc, so the arc test is False for it (session 15)
        if not j_new.scan_plain and j_new.seg is not None and j_new.seg.kind == "arc" and j_new.s_end > self._arc_s:
            self._arc_s = j_new.s_end
        if not tail.scan_plain and tail.seg is not None and tail.seg.kind == "arc" and tail.s_end > self._arc_s:
            self._arc_s = tail.s_end
        # Every junction a window ending at J charges lies within span_max behind J, so the
        # blocks it spans (and the tail's) are lines when the newest arc ended before that.
        lines = self._arc_s < s_j - span_max
        if lines:  # (two assignments, not a tuple made and unpacked a push: decision bench B188)
            budget_a, budget_j = self.budget_al, self.budget_jl
        else:
            budget_a, budget_j = self.budget_a, self.budget_j
        # The search's state for `_cap` and `_taken` (C fields: a closure scope, two function objects and a dict a
        # push were ≈ 5k instructions, decision bench B133)
        self._w_last, self._w_h0, self._w_s_j, self._w_top = last, h0, s_j, top
        self._w_pad, self._w_two_al, self._w_t_w2, self._w_v_hi = pad, two_al, t_w2, v_hi
        self._w_ba, self._w_bj = budget_a, budget_j
        self._w_bmin = self._bmin[0 if lines else 1]
        self._w_k1 = self._w_k2 = -1
        m0 = m
        if self._taken(m):
            while m > h0 and self._taken(m - 1):
                m -= 1
            while m < m0:
                # The stretch grew backwards past the maxima's start: take its blocks into them;
                # a higher acceleration widens the span, which may take more junctions still.
                for k in range(m0 - 1, m - 1, -1):
                    b = hist[k]
                    acc_q.push_front(self._seq0 + k, b.a)
                    top_q.push_front(self._seq0 + k, b.vtop)
                    len_q.push_front(self._seq0 + k, b.length)
                m0 = m
                pad = 0.5 * acc_q.front() * t_w2
                two_al = 2.0 * acc_q.front() * len_q.front()
                v_hi = top_q.front()
                self._w_pad, self._w_two_al, self._w_v_hi = pad, two_al, v_hi
                self._w_k1 = self._w_k2 = -1  # _cap reads v_hi
                while m > h0 and self._taken(m - 1):
                    m -= 1
        else:
            m += 1
            while not self._taken(m):
                m += 1
            sm = self._seq0 + m  # what fell out front, queue by queue
            acc_q.drop(sm)
            top_q.drop(sm)
            len_q.drop(sm)
        self._m = m
        if m == self._w_k1:
            c = self._w_c1
        elif m == self._w_k2:
            c = self._w_c2
        else:
            c = self._cap(m)
        c_bud = c  # the budgets' cap not held to top (nc.motion.shares)
        if c < top:
            # The sums over the whole stretch bound the filter's acceleration and jerk from
            # above; the windows themselves (at the speed they are crossed) are far less on a
            # curve, where consecutive windows hold nearly the same signed sum.
            c2, c_bud = _refined(self, hist, h0, last, c, top, budget_a, budget_j)  # (a C call, not `_refine`'s: B171)
            if c2 > c:
                c = c2
                while m > h0 and s_j - hist[m - 1].s_end <= c * t_w + pad:
                    m -= 1
        elif c < USAGE_SCALE * top:
            # Capped by nothing, but the share the corners use (vjunc / vbud, nc.motion.shares) is
            # read from the signed windows: the unsigned sums overstate it on a curve.
            c_bud = max(c, _refined(self, hist, h0, last, top, top, budget_a, budget_j)[1])
        depth = self._tolerance(blocks, v_hi) if self.tol is not None else 0
        if m < self._sc_dirty:
            self._sc_dirty = m  # the walks below lower vbud (and vjunc) over hist[m..last]
        fast = c >= top_q.front()  # no junction of the stretch can run as fast as this cap
        seq_m = self._seq0 + m
        bud_b, bud_seq, bud_c = self._bud_b, self._bud_seq, self._bud_c
        self._bud_b = j_new
        self._bud_seq = seq_m
        self._bud_c = c_bud
        if fast:
            # Only the budgets' share falls: the queued junctions hist[m..last] (blocks[-2] back),
            # without the bookkeeping the caps' backward-pass depth needs below (issue 17).
            seq0 = self._seq0
            lo_q = last + 2 - len(blocks)  # hist[lo_q] is blocks[0]'s junction: the oldest still queued
            if j_new.vbud > c_bud:
                j_new.vbud = c_bud
            if not (bud_b is not None and seq_m >= bud_seq and c_bud >= bud_c and len(blocks) > 2
                    and blocks[-3] is bud_b):
                # (Else the last window's stretch holds all of this one's junctions but J, at vbud <= its share
                # <= this one's: only J's can fall, issue 17.) The walk goes from the newest back and stops at
                # the first junction at or below c_bud within the rising run (`_mono`): the older ones there
                # are no higher. Below the run it walks on as before.
                stop = m if m > lo_q else lo_q
                mono = self._mono - seq0
                lim = mono if mono > stop else stop
                # hist[last - 1] down to hist[lim]: blocks[-3] back, the queue and the history side by side (each
                # queued block joined the history as it became blocks[-2]; lim >= lo_q). Read from the list, not
                # through islice(reversed(deque)): ≈ 2k instructions a push less, decision bench B171
                for k in range(last - 1, lim - 1, -1):
                    b = hist[k]
                    if b.vbud > c_bud:
                        b.vbud = c_bud
                    else:
                        break
                for b in hist[stop:lim]:
                    if b.vbud > c_bud:
                        b.vbud = c_bud
                if mono < m:
                    self._mono = seq0 + m  # hist[m..] rise still (min with c_bud keeps the order); before m: not known
            if last - 1 < lo_q:
                self._mono = seq0 + last
                return depth
            b = hist[last - 1]  # (typed: vbud read as a Block's field, not by attribute lookup, decision bench B188)
            if j_new.vbud < b.vbud:
                self._mono = seq0 + last  # J is below the junction before it: the rising run starts again at J
            return depth
        k = 2
        idx = last
        it = reversed(blocks)
        next(it)
        for b in it:
            if idx < m:
                break
            if b.vbud > c_bud:
                b.vbud = c_bud  # the budget share a junction uses is vjunc / vbud (nc.motion.shares)
            if not fast and b.vbase > c:
                b.vbase = c
                if b.vjunc > c:
                    b.vjunc = c
                    # Lowering a junction below its planned speed needs a new backward pass down
                    # to it; above it nothing changes (float noise included).
                    if c < b.vend * (1.0 - 1e-9) and k > depth:
                        depth = k
            k += 1
            idx -= 1
        self._mono = self._seq0 + last  # not followed through this walk: from J on
        return depth

    @cython.locals(m=cython.Py_ssize_t, k=cython.Py_ssize_t, i=cython.Py_ssize_t, c=cython.double,
                   si=cython.double, x=cython.double, d=cython.double, sg=cython.double, ja=cython.double,
                   last=cython.Py_ssize_t, h0=cython.Py_ssize_t, axes=cython.Py_ssize_t, bmin=tuple, budget_a=tuple,
                   budget_j=tuple, bm=cython.double, y=cython.double, s0=cython.double, s1=cython.double,
                   s2=cython.double, g0=cython.double, g1=cython.double, g2=cython.double, q0=cython.double,
                   q1=cython.double, q2=cython.double, cw=cython.Py_ssize_t, off=cython.Py_ssize_t,
                   oj=cython.Py_ssize_t, ob=cython.Py_ssize_t, o=cython.Py_ssize_t, x0=cython.double,
                   x1=cython.double, x2=cython.double, held=cython.bint)
    def _cap(self, m: int) -> float:
        """`window`'s cap from the junctions hist[m..last] (inf when there are none): per axis, the
        acceleration budget over the largest signed sum of any run of them that ends at J,
        the jerk budget over the smaller of their unsigned sum and twice that."""
        last, h0 = self._w_last, self._w_h0
        if m > last:
            return _INF
        # The running sums are rows of `_cs` (decision bench B189): J's (oj) and the one before the stretch (ob)
        # where it is within reach (held), else zeros; read as C doubles, the same differences as the tuples' were
        # (each item read into a C double before it meets another, decision bench B171; _INF a C constant, B134)
        cw, off = self._csw, self._cs_off
        oj = (last + off) * cw
        held = m > h0
        ob = (m - 1 + off) * cw if held else 0
        bmin, axes = self._w_bmin, self._axes
        c = _INF  # first from the unsigned sums: a lower bound of the signed cap
        if axes == 3:  # spelt out: ~3 calls a push (issue 17)
            x0 = self._cs[ob] if held else 0.0
            x1 = self._cs[ob + 1] if held else 0.0
            x2 = self._cs[ob + 2] if held else 0.0
            bm = bmin[0]
            si = self._cs[oj] - x0
            if si > 1e-12:
                c = bm / si
            bm = bmin[1]
            si = self._cs[oj + 1] - x1
            if si > 1e-12:
                x = bm / si
                if x < c:
                    c = x
            bm = bmin[2]
            si = self._cs[oj + 2] - x2
            if si > 1e-12:
                x = bm / si
                if x < c:
                    c = x
            if c >= self._w_v_hi:
                return c  # no junction of the stretch runs as fast: the signed sums change nothing
            g0, g1, g2 = self._cs[oj + 4], self._cs[oj + 5], self._cs[oj + 6]
            s0 = s1 = s2 = 0.0  # the largest |signed sum| per axis
            for k in range(m - 1, last):
                if k >= h0 and (k > m - 1 or m > h0):  # (k >= m - 1 throughout)
                    o = (k + off) * cw + 4
                    q0, q1, q2 = self._cs[o], self._cs[o + 1], self._cs[o + 2]
                else:
                    q0 = q1 = q2 = 0.0
                d = g0 - q0
                if d < 0.0:
                    d = -d
                if d > s0:
                    s0 = d
                d = g1 - q1
                if d < 0.0:
                    d = -d
                if d > s1:
                    s1 = d
                d = g2 - q2
                if d < 0.0:
                    d = -d
                if d > s2:
                    s2 = d
            budget_a, budget_j = self._w_ba, self._w_bj
            c = _INF
            for i in range(3):
                x = (x0 if i == 0 else (x1 if i == 1 else x2))
                si = self._cs[oj + i] - x
                if si > 1e-12:
                    c = _axis_cap(si, s0 if i == 0 else (s1 if i == 1 else s2), budget_j[i], budget_a[i], c)
            return c
        for i in range(axes):
            x = self._cs[ob + i] if held else 0.0
            si = self._cs[oj + i] - x
            if si > 1e-12:
                bm = bmin[i]
                x = bm / si
                if x < c:
                    c = x
        if c >= self._w_v_hi:
            return c  # no junction of the stretch runs as fast: the signed sums change nothing
        smax = [0.0] * axes
        for k in range(m - 1, last):
            if k >= h0 and (k > m - 1 or m > h0):  # (k >= m - 1 throughout)
                o = (k + off) * cw + axes + 1
                for i in range(axes):
                    x, y = self._cs[oj + axes + 1 + i], self._cs[o + i]
                    d = x - y
                    if d < 0.0:
                        d = -d
                    if d > smax[i]:
                        smax[i] = d
            else:
                for i in range(axes):
                    x, y = self._cs[oj + axes + 1 + i], 0.0
                    d = x - y
                    if d < 0.0:
                        d = -d
                    if d > smax[i]:
                        smax[i] = d
        budget_a, budget_j = self._w_ba, self._w_bj
        c = _INF
        for i in range(axes):
            x = self._cs[ob + i] if held else 0.0
            si = self._cs[oj + i] - x
            if si > 1e-12:
                c = _axis_cap(si, smax[i], budget_j[i], budget_a[i], c)
        return c

    @cython.locals(k=cython.Py_ssize_t, c=cython.double, d=cython.double, top=cython.double, t_w=cython.double)
    def _taken(self, k: int) -> bool:
        """Whether a window ending at J can reach back to junction k when the junctions after
        it run at no more than their common cap c: it covers no more path than J's speed
        plus what the acceleration adds going back, nor than the highest speed anywhere in
        the stretch (a block between junctions ≤ c reaches √(c² + 2·A·L)) allows in T. Keeps the cap in
        `_w_k1`/`_w_c1` as (k + 1, cap), the one before in `_w_k2`/`_w_c2` (valid while v_hi stays)."""
        c = self._cap(k + 1)
        self._w_k2, self._w_c2 = self._w_k1, self._w_c1
        self._w_k1, self._w_c1 = k + 1, c
        d = self._hist_s[k]  # (read into a C double first: a float object less, decision bench B188)
        d = self._w_s_j - d
        top, t_w = self._w_top, self.t_j
        if (c if c < top else top) * t_w + self._w_pad < d:
            return False
        return (c * c + self._w_two_al) * self._w_t_w2 >= d * d and self._w_v_hi * t_w >= d

    def _refine(self, hist: list["Block"], h0: int, last: int, c: float, top: float,
                budget_a: tuple[float, ...], budget_j: tuple[float, ...]) -> tuple[float, float]:
        """The highest speed ≤ top (above the safe cap c, else c) at which every filter window
        whose last junction is J meets the budgets, the windows taken at that speed: per axis
        the acceleration |Σ v_i·Δu_i|/T1 over a T1 window and the jerk over the difference of two
        such windows T2 apart, divided by T1·T2 (the two moving averages' derivatives, exactly, at
        constant speed), v_i the least of v and the junction's cap so far (vbase only ever falls).
        Second: the cap the budgets give with the windows taken at that speed, not held to top."""
        return _refined(self, hist, h0, last, c, top, budget_a, budget_j)

    @cython.locals(h0=cython.Py_ssize_t, last=cython.Py_ssize_t, s_j=cython.double, vt=cython.double,
                   half=cython.double, lo=cython.Py_ssize_t, k=cython.Py_ssize_t, x=cython.double, top=cython.double,
                   hs=list, vts=list, i=cython.Py_ssize_t, y=cython.double)
    def _reach_back(self, h0: int, last: int, s_j: float, vt: float, half: float) -> tuple[int, float]:
        """`_tolerance`'s reach behind J: the junction walk
            lo = last
            while lo > h0:
                b = hist[lo - 1]; vt = max(vt, b.vtop)
                if s_j - b.s_end > 3.0 * vt * half: break
                lo -= 1
        in stretches (issue 17: it walked ~100 junctions a call): the junctions that pass at the vt reached so far
        (a suffix: s_end only grows) are found by bisection on `_hist_s` and their vtops taken at once from `_vt`
        (the fields side by side), so (lo, vt) come out as the walk's."""
        hs, vts = self._hist_s, self._vt
        lo = last
        while lo > h0:
            x = 3.0 * vt * half
            k = _at_or_above(hs, s_j - x, h0, lo)  # about where the test turns; made exact below
            while k < lo and s_j - hs[k] > x:
                k += 1
            while k > h0 and not s_j - hs[k - 1] > x:
                k -= 1
            if k < lo:  # hist[k:lo] pass at vt, so with their own vtops too (the walk's vt only grows)
                top = vts[k]  # max(vts[k:lo]) as the builtin compares (item > the maximum so far), in C (B153)
                for i in range(k + 1, lo):
                    y = vts[i]
                    if y > top:
                        top = y
                if top > vt:
                    vt = top
                lo = k
                continue
            top = vts[lo - 1]  # the walk's next junction fails at vt: it is tested with its own vtop
            if top > vt:
                vt = top
            if s_j - hs[lo - 1] > 3.0 * vt * half:
                break
            lo -= 1
        return lo, vt

    @cython.locals(h0=cython.Py_ssize_t, last=cython.Py_ssize_t, s_j=cython.double, half=cython.double,
                   vt=cython.double, h=cython.double, k=cython.Py_ssize_t, axes=cython.Py_ssize_t,
                   sum_n=cython.double, lo=cython.Py_ssize_t, nseg=cython.Py_ssize_t, i=cython.Py_ssize_t,
                   i0=cython.Py_ssize_t, depth=cython.Py_ssize_t, lim=cython.double, c=cython.double, v=cython.double,
                   vt_i=cython.double, t2sum=cython.double, b=Block, nx=Block, bj=Block, hist=list, seg=list)
    def _tolerance(self, blocks: Sequence["Block"], v_hi: float) -> int:
        """Evaluate the deviation model (nc.motion.deviation) at the junctions within half a
        window (at the fastest speed nearby) behind the newest one J, with every junction known
        around them, and give each junction the least speed evaluated at any junction whose
        window holds it. Junctions further back keep what they had: their windows were complete
        before J came. Returns how many blocks from the tail need a new backward pass."""
        hist, h0 = self._hist, self._h0
        last = len(hist) - 1
        bj = hist[last]
        s_j = bj.s_end
        half = self._half
        nx = blocks[-1]
        vt = v_hi if v_hi > nx.vtop else nx.vtop
        h = vt * half
        # Cheap first: with G ≤ G(0) and unsigned steps, the deviation anywhere near J is at most
        # vt·G(0)·Σ|Δu| plus a braking term; within the tolerance and with no junction limited
        # within reach (whose caps would have to be lifted), nothing near J changes: the common
        # case on gentle curves, O(log n).
        if self._lim_s < s_j - 3.0 * h:
            k = _at_or_above(self._hist_s, s_j - 2.0 * h - 1e-12, h0, last + 1)
            axes = self._axes
            sum_n = self._cs[(last + self._cs_off) * self._csw + axes]  # J's Σ|Δu| norm (its cum[axes])
            if k > h0:
                sum_n = sum_n - self._cs[(k - 1 + self._cs_off) * self._csw + axes]
            # the braking term inline (`braking` without a jerk); _g0, _tol_v: kd.g0 and tol as C doubles (B153)
            if vt * self._g0 * sum_n + sum_n * self.amax * self.t2sum / 192.0 <= self._tol_v:
                return 0
        lo, vt = self._reach_back(h0, last, s_j, vt, half)
        if lo < self._sc_dirty:
            self._sc_dirty = lo  # vtol and vjunc change over hist[lo:] below
        return _held_caps(self, blocks, lo, last, s_j, vt, half)


def _held_caps(fc: FilterCorners, blocks: Sequence[Block], lo: int, last: int, s_j: float, vt: float,
               half: float) -> int:
    """`FilterCorners._tolerance`'s evaluation over the junctions hist[lo..last] (decision bench B133): the numpy
    form it had, one C loop an array (issue 17: ~60 numpy calls on arrays of ~50 ended in ~900k instructions a
    call). Each value is the same IEEE operation in the same order as the numpy form's elementwise one: np.interp's
    own arithmetic (slopes (g[j+1] − g[j]) / (y[j+1] − y[j]), then slope·(x − y[j]) + g[j]), np.minimum's and
    np.abs'. The product with the steps and its row norms are `_deviations`: compiled, C loops in the order numpy's
    BLAS sums them (decision bench B163); as Python, numpy's. `KernelDeviation.caps`' first pass tries the top speed
    at every junction with room; where that deviates too far somewhere, caps itself runs (it tries the same first).
    The arrays are FilterCorners' scratch (`_scratch`), sliced to the call's sizes; the types are in blending.pxd
    (memoryviews: nc.motion.cython_shadow has none). Returns how many blocks from the tail need a new backward
    pass."""
    hist, hs = fc._hist, fc._hist_s
    nseg = last + 1 - lo
    if nseg > fc._x_s.shape[0]:
        fc._scratch(2 * nseg, fc._x_w.shape[0], fc._x_w.shape[1])
    h = vt * half
    s = fc._x_s[:nseg]
    for i in range(nseg):
        s[i] = hs[lo + i]
    # The junctions near J and those evaluated: suffixes of hist[lo:] (s_end only grows)
    t_near = s_j - 2.0 * h - 1e-12
    t_ev = s_j - h - 1e-12
    n0 = nseg
    while n0 > 0 and s[n0 - 1] >= t_near:
        n0 -= 1
    e0 = nseg
    while e0 > 0 and s[e0 - 1] >= t_ev:
        e0 -= 1
    ne, nn, axes = nseg - e0, nseg - n0, fc._axes
    tol, t2sum = fc.tol, fc.t2sum
    room = fc._x_room[:ne]
    nl = 0  # junctions with room left
    for i in range(ne):
        b = hist[lo + e0 + i]
        nx = hist[lo + e0 + i + 1] if e0 + i + 1 < nseg else blocks[-1]
        rr = tol - b.du_n * (b.a if b.a > nx.a else nx.a) * t2sum / 192.0  # `braking` inline
        room[i] = rr
        if rr > 0.0:
            nl += 1
    fits = True
    if nl > 0:
        du = fc._x_du[:nn]
        vb = fc._x_vb[:nn]
        for k in range(nn):
            b = hist[lo + n0 + k]
            dv = b.dv
            for a in range(axes):
                du[k, a] = dv[a]
            vb[k] = b.vbase
        # KernelDeviation.deviation at the top speed for the junctions with room (se), their rooms (rm)
        se = fc._x_se[:nl]
        rm = fc._x_rm[:nl]
        r = 0
        for i in range(ne):
            if room[i] > 0.0:
                se[r] = s[e0 + i]
                rm[r] = room[i]
                r += 1
        if nl > fc._x_w.shape[0] or nn > fc._x_w.shape[1]:
            fc._x_w = np.empty((nl if nl > fc._x_w.shape[0] else fc._x_w.shape[0],
                                nn if nn > fc._x_w.shape[1] else fc._x_w.shape[1]))
        w = fc._x_w[:nl, :nn]  # (rows nl of a wider matrix: its inner dimension stays contiguous)
        _kernel_matrix(w, se, s[n0:], vb, vt, fc._x_gy, fc._x_gg, fc._x_gs)
        e = fc._x_e[:nl]
        _deviations(w, du, e)
        for r in range(nl):
            if e[r] > rm[r]:
                fits = False
                break
        if not fits:  # caps from its first pass on (rare: about never on the CAM program), on fresh arrays as before
            caps = fc.kd.caps(np.array(s[e0:]), np.array(room), vt, np.array(s[n0:]), np.array(du),
                              np.array(vb)).tolist()
    lim = vt * (1.0 - 1e-9)
    for i in range(ne):
        if fits:
            c = vt if room[i] > 0.0 else 0.0
        else:
            c = caps[i]
        b = hist[lo + e0 + i]
        if b.viso > c:
            c = b.viso  # alone in its windows at up to viso, which keeps N1.053 proved (decision motion 73)
        b.ctol = c
        if c < lim and b.s_end > fc._lim_s:
            fc._lim_s = b.s_end
    # Each junction near J: the least ctol of the junctions whose reach (min(ctol, vt)·half) holds it
    ct = fc._x_ct[:nseg]
    rc = fc._x_rc[:nseg]
    for k in range(nseg):
        b = hist[lo + k]  # (typed: ctol read as a Block's field, decision bench B163)
        c = b.ctol
        rc[k] = (c if c < vt or c != c else vt) * half + 1e-12
        ct[k] = c
    depth = 0
    i0 = nseg + 1 - len(blocks)  # hist[lo + i] is blocks[i - nseg - 1]: queued from i0 on
    far = vt * half + 1e-12  # no reach is longer (each rounding is monotonic): the junctions past it, on either
    # side (s sorted), are held by none
    held = fc._x_e[:nseg]  # (e's room: read no more)
    _least_held(s, ct, rc, n0, far, held)
    for u in range(n0, nseg):
        vt_i = held[u]
        b = hist[lo + u]
        b.vtol = vt_i
        if u >= i0:
            v = b.vbase if b.vbase < vt_i else vt_i
            if abs(v - b.vjunc) > 1e-9 * (1.0 if 1.0 > v else v):  # max(v, 1.0) spelt out
                b.vjunc = v
                k = nseg - u + 1  # hist[last] is blocks[-2]
                if k > depth:
                    depth = k
    return depth


@cython.boundscheck(False)
@cython.wraparound(False)
def _least_held(s: np.ndarray, ct: np.ndarray, rc: np.ndarray, n0: int, far: float, held: np.ndarray) -> int:
    """held[u] for u in n0..: the least ct[k] over the junctions k whose reach rc[k] holds s[u] (|s[u] − s[k]| ≤
    rc[k]; inf where none; nan kept), those further than `far` skipped (s sorted). No bounds checks compiled
    (decision bench B163): every index lies in 0..len(s)."""
    nseg = s.shape[0]
    if ct.shape[0] < nseg or rc.shape[0] < nseg or held.shape[0] < nseg or n0 < 0:
        raise ValueError("_least_held: ct, rc and held need a place per junction")
    inf = math.inf
    for u in range(n0, nseg):
        su = s[u]
        vt_i = inf
        k = u
        while k >= 0 and su - s[k] <= far:
            k -= 1
        for k in range(k + 1, nseg):
            x = su - s[k]
            if x < 0.0:
                x = -x
                if x > far:
                    break
            if x <= rc[k]:
                c = ct[k]
                if c < vt_i or c != c:
                    vt_i = c
        held[u] = vt_i
    return 0


# `_deviations`' summation orders (decision bench B163): which one numpy's BLAS uses here is probed at first use.
_ORDERS = ("numpy", "SkylakeX", "Haswell")  # index = the code `_dev_order` holds; 0: numpy is called
_dev_order = -1  # not probed yet


def _numpy_deviations(w: np.ndarray, du: np.ndarray) -> np.ndarray:
    """What `_deviations` must give: np.linalg.norm(w @ du, axis=1) on fresh C-contiguous arrays (the probe's
    reference; KernelDeviation.deviation computes the same)."""
    return np.linalg.norm(np.array(w) @ np.array(du), axis=1)


def _probe_cases() -> list:
    """A fixed set of (w, du) reaching each branch of the C orders: one row (steps in fours and a tail), one step,
    K = steps < 16, ≥ 16 with rows before and past the last group of four and a masked last group of eight, over 256
    and over 512 (OpenBLAS's K blocks on Haswell), 2 and 3 axes. Values spread over magnitudes, signed, some zero; in
    the one-row cases of one magnitude, the steps' signs alternating: their sums cancel, so that a product rounded
    before it is added (or not) shows in the last bits (tests/test_filter_deviations.py checks that every pair of
    orders differs on the set, in each branch)."""
    # Weyl sequences (fractional parts of multiples of irrationals): as spread as random draws in the last bits,
    # without numpy.random (its first generator costs ≈ 20 ms)
    i = np.arange(1.0, 1811.0)
    frac = (i * 0.6180339887498949) % 1.0
    spread = frac * 10.0 ** (np.floor((i * 0.4142135623730951) % 1.0 * 6.0) - 3.0)  # 10⁻³ to 10²
    spread_w = 3.0 * spread
    spread_w[(i * 0.7320508075688772) % 1.0 < 0.2] = 0.0
    cases = []
    for nl, nn, axes in ((1, 30, 3), (1, 22, 2), (1, 7, 3), (1, 13, 3), (4, 1, 3), (5, 9, 3), (3, 13, 2),
                         (6, 21, 3), (9, 40, 2), (5, 300, 3), (2, 600, 2)):
        if nl == 1:
            w = 1.0 + frac[nn:2 * nn]
            du = 0.5 + 0.5 * frac[nn + 7:nn + 7 + nn * axes]
        else:
            w = spread_w[:nl * nn]
            du = spread[7:7 + nn * axes].copy()
        du = du.reshape(nn, axes)
        du[1::2] = -du[1::2]
        cases.append((w.reshape(nl, nn), du))
    return cases


def _probe_order() -> int:
    """The first C order whose results on `_probe_cases` are `_numpy_deviations`' bit for bit, 0 (numpy) where none
    is or the module runs as Python (≈ 0.2 ms, once a process)."""
    if not cython.compiled:
        return 0
    cases = _probe_cases()
    for order in range(1, len(_ORDERS)):
        for w, du in cases:
            e = np.empty(w.shape[0])
            _c_deviations(w, du, e, order)
            if not np.array_equal(e.view(np.uint64), _numpy_deviations(w, du).view(np.uint64)):
                break
        else:
            return order
    return 0


def deviation_order() -> str:
    """The summation order `_deviations` takes in this process ("SkylakeX", "Haswell": its C loops; "numpy": numpy
    itself, as the Python build), probed at the first call (decision bench B163)."""
    global _dev_order
    if _dev_order < 0:
        _dev_order = _probe_order()
    return _ORDERS[_dev_order]


def _deviations(w: np.ndarray, du: np.ndarray, e: np.ndarray) -> int:
    """e[r] = np.linalg.norm(w @ du, axis=1)[r] bit for bit (decision bench B163): compiled, `_c_deviations`' C
    loops in the order numpy's BLAS sums here, where the probe (`deviation_order`) found one; else, as the Python
    build, numpy itself on fresh arrays. Sizes past a single-threaded BLAS call (a gemv of over 9,215 values, a gemm
    of over 262,144 products: OpenBLAS may split those between threads) and 1 or over 3 axes: numpy too."""
    nl, nn, axes = w.shape[0], w.shape[1], du.shape[1]
    if du.shape[0] != nn or e.shape[0] < nl:
        raise ValueError("_deviations: du must have a row per column of w, e a place per row")
    order = _dev_order
    if order < 0 and cython.compiled:
        deviation_order()
        order = _dev_order
    if (order <= 0 or axes < 2 or axes > 3 or (nl == 1 and axes * nn >= 9216)
            or (nl > 1 and axes * nl * nn > 262144)):
        out = _numpy_deviations(w, du)
        for r in range(nl):
            e[r] = out[r]
        return 0
    return _c_deviations(w, du, e, order)


@cython.boundscheck(False)
@cython.wraparound(False)
def _c_deviations(w: np.ndarray, du: np.ndarray, e: np.ndarray, order: int) -> int:
    """e[r] = the norm of row r of w @ du summed as numpy 2.4's matmul does through OpenBLAS 0.3.31 (compiled only;
    the sizes checked by `_deviations`), with M = axes, N = nl, K = nn in BLAS's terms, on its kernels for
    - order 1, SkylakeX (the bench machine's):
      one row: numpy's gemv, OpenBLAS's dgemv_n for 2 or 3 rows: per 4 steps t = t + fma(a_k, x_k, a_k+1·x_k+1)
      twice, then t = fma(a_k, x_k, t) for the rest;
      else cblas_dgemm's small-matrix kernel (dgemm_small_kernel_b0_nn): K < 16, one fused multiply-add chain over
      the steps in order; K ≥ 16, eight chains (step k into chain k mod 8, a last partial group of 8 adding +0 to
      the chains past it) summed ((0+1)+(2+3))+((4+5)+(6+7)) for the rows in groups of four (r < nl rounded down to
      4), ((0+4)+(2+6))+((1+5)+(3+7)) for the rest;
    - order 2, Haswell (Zen; valgrind's CPU, without AVX-512):
      one row: the same dgemv_n, built without fused multiply-adds: per 4 steps t = t + (a_k·x_k + a_k+1·x_k+1)
      twice, then t = t + a_k·x_k;
      else the packed gemm kernel: one fused multiply-add chain over the steps in order, in K blocks (K over 256:
      two halves, the first rounded up to 4, or blocks of 256 while K ≥ 512 is left), each added to the sum;
    - one step, either: numpy's own loop, 0 + w·du.
    The norm: squares summed (x0² + x1²) + x2², then the square root (numpy's add.reduce over 3 columns)."""
    nl, nn, axes = w.shape[0], w.shape[1], du.shape[1]
    n4 = nl - nl % 4
    for r in range(nl):
        q = 0.0
        for a in range(axes):
            if nn == 1:
                p = 0.0 + w[r, 0] * du[0, a]
            elif nl == 1 and order == 2:
                p = 0.0
                k = 0
                while k + 4 <= nn:
                    p = p + (du[k, a] * w[r, k] + du[k + 1, a] * w[r, k + 1])
                    p = p + (du[k + 2, a] * w[r, k + 2] + du[k + 3, a] * w[r, k + 3])
                    k += 4
                while k < nn:
                    p = p + du[k, a] * w[r, k]
                    k += 1
                p = 0.0 + p
            elif nl == 1:
                p = 0.0
                k = 0
                while k + 4 <= nn:
                    p = p + _fma(du[k, a], w[r, k], du[k + 1, a] * w[r, k + 1])
                    p = p + _fma(du[k + 2, a], w[r, k + 2], du[k + 3, a] * w[r, k + 3])
                    k += 4
                while k < nn:
                    p = _fma(du[k, a], w[r, k], p)
                    k += 1
                p = 0.0 + p
            elif order == 2:
                p = 0.0
                k0 = 0
                while k0 < nn:
                    kb = nn - k0  # the K block, as OpenBLAS's level-3 driver cuts it (GEMM_Q 256, unroll 4)
                    if kb >= 512:
                        kb = 256
                    elif kb > 256:
                        kb = (kb // 2 + 3) // 4 * 4
                    t = 0.0
                    for k in range(k0, k0 + kb):
                        t = _fma(du[k, a], w[r, k], t)
                    p = p + t
                    k0 += kb
            elif nn < 16:
                p = 0.0
                for k in range(nn):
                    p = _fma(du[k, a], w[r, k], p)
            else:
                l0 = l1 = l2 = l3 = l4 = l5 = l6 = l7 = 0.0
                k = 0
                while k + 8 <= nn:
                    l0 = _fma(du[k, a], w[r, k], l0)
                    l1 = _fma(du[k + 1, a], w[r, k + 1], l1)
                    l2 = _fma(du[k + 2, a], w[r, k + 2], l2)
                    l3 = _fma(du[k + 3, a], w[r, k + 3], l3)
                    l4 = _fma(du[k + 4, a], w[r, k + 4], l4)
                    l5 = _fma(du[k + 5, a], w[r, k + 5], l5)
                    l6 = _fma(du[k + 6, a], w[r, k + 6], l6)
                    l7 = _fma(du[k + 7, a], w[r, k + 7], l7)
                    k += 8
                if k < nn:  # the masked last group: the chains past the steps left add 0·0
                    l0 = _fma(du[k, a], w[r, k], l0)
                    l1 = _fma(du[k + 1, a], w[r, k + 1], l1) if k + 1 < nn else l1 + 0.0
                    l2 = _fma(du[k + 2, a], w[r, k + 2], l2) if k + 2 < nn else l2 + 0.0
                    l3 = _fma(du[k + 3, a], w[r, k + 3], l3) if k + 3 < nn else l3 + 0.0
                    l4 = _fma(du[k + 4, a], w[r, k + 4], l4) if k + 4 < nn else l4 + 0.0
                    l5 = _fma(du[k + 5, a], w[r, k + 5], l5) if k + 5 < nn else l5 + 0.0
                    l6 = _fma(du[k + 6, a], w[r, k + 6], l6) if k + 6 < nn else l6 + 0.0
                    l7 = l7 + 0.0
                if r < n4:
                    p = ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7))
                else:
                    p = ((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7))
            q = p * p if a == 0 else q + p * p
        e[r] = _c_sqrt(q)
    return 0


@cython.boundscheck(False)
@cython.wraparound(False)
def _kernel_matrix(w: np.ndarray, s_rows: np.ndarray, s_all: np.ndarray, vb: np.ndarray, c: float, gy: np.ndarray,
                   gg: np.ndarray, gs: np.ndarray) -> None:
    """Fill w (rows × junctions) with `KernelDeviation.deviation`'s weighted steps at the speed c for every row,
    G(|(s_all[k] − s_rows[r]) / c|)·min(vb[k], c), G the table (gy, gg) as np.interp(..., right=0.0) reads it, gs its
    slopes: the same IEEE operations as the numpy form, element by element (decision bench B133). No bounds checks
    compiled (decision bench B163): the sizes are checked once here."""
    ny = gy.shape[0]
    if (ny < 1 or gg.shape[0] < ny or gs.shape[0] < ny - 1 or s_rows.shape[0] < w.shape[0]
            or s_all.shape[0] < w.shape[1] or vb.shape[0] < w.shape[1]):
        raise ValueError("_kernel_matrix: a table or a vector is shorter than the matrix it fills")
    ymax = gy[ny - 1]
    inv = (ny - 1) / ymax  # G's table is evenly spaced: a first guess of the index, made exact below
    for r in range(w.shape[0]):
        sr = s_rows[r]
        for k in range(w.shape[1]):
            x = (s_all[k] - sr) / c
            if x < 0.0:
                x = -x
            if x != x:
                g = x  # np.interp: nan stays
            elif x > ymax:
                g = 0.0  # right=0.0
            elif x < gy[0]:
                g = gg[0]
            else:
                j0 = int(x * inv)  # then the last j with gy[j] <= x, as np.interp's search finds it
                if j0 > ny - 1:
                    j0 = ny - 1
                while j0 > 0 and gy[j0] > x:
                    j0 -= 1
                while j0 < ny - 1 and gy[j0 + 1] <= x:
                    j0 += 1
                if j0 == ny - 1 or gy[j0] == x:
                    g = gg[j0]
                else:
                    g = gs[j0] * (x - gy[j0]) + gg[j0]
                    if g != g:  # np.interp's other side
                        g = gs[j0] * (x - gy[j0 + 1]) + gg[j0 + 1]
                        if g != g and gg[j0] == gg[j0 + 1]:
                            g = gg[j0]
            v = vb[k]
            w[r, k] = g * (v if v < c or v != v else c)  # np.minimum(vb, c): nan propagates


def _refined(fc: FilterCorners, hist: list[Block], h0: int, last: int, c: float, top: float,
             budget_a: tuple[float, ...], budget_j: tuple[float, ...]) -> tuple[float, float]:
    """`FilterCorners._refine` in C loops (decision bench B133: it was numpy on the stretch's few hundred junctions,
    ~1.2M instructions a call): each value the same IEEE operation as its numpy form's, np.cumsum's running sums
    in their order, np.searchsorted(side="right") as the count of positions at or below, np.minimum's, np.maximum's
    and np.max's nan propagation. The arrays are FilterCorners' scratch (`_r_*`, grown as a call needs), sliced to
    the call's sizes (decision bench B187: nine numpy arrays made afresh a call were ≈ 30k instructions)."""
    t1, t2 = fc.t_a, fc.t_j - fc.t_a
    s_j = hist[last].s_end
    lo = last
    reach = top * fc.t_j * 2.0
    while lo > h0 and s_j - hist[lo - 1].s_end <= reach:
        lo -= 1
    n, axes = last + 1 - lo, fc._axes
    if n > fc._r_s.shape[0]:
        fc._r_scratch(2 * n)
    s, vb, du = fc._r_s[:n], fc._r_vb[:n], fc._r_du[:n]
    # The blocks between the stretch's junctions: on one of length L whose junctions are crossed at <= v the
    # profile reaches at most sqrt(v² + a·L) (speeding up from one, braking to the other), and its vtop
    al, vt = fc._r_al[:n - 1], fc._r_vt[:n - 1]
    for i in range(n):
        b = hist[lo + i]
        s[i] = b.s_end
        dv = b.dv
        for k in range(axes):
            du[i, k] = dv[k]
        # A junction's velocity step is its own speed times Δu: no more than the cap it already
        # has (vbase only ever falls), nor than the speed the windows are taken at.
        vb[i] = b.vbase
        if i > 0:
            al[i - 1] = b.a * b.length
            vt[i - 1] = b.vtop
    ba, bj = fc._r_ba, fc._r_bj
    for k in range(axes):
        ba[k] = budget_a[k]
        bj[k] = budget_j[k]
    pre, sums = fc._r_pre[:n + 1], fc._r_sums  # sums: sa, sd, then one window's pair
    best = c
    bud = nxt = _cap_at(c, t1, t2, s_j, s, vb, du, al, vt, ba, bj, pre, sums)
    v = top if top < nxt else nxt  # min(nxt, top)
    for _ in range(3):
        if v <= best * (1.0 + 1e-6):
            break
        nxt = _cap_at(v, t1, t2, s_j, s, vb, du, al, vt, ba, bj, pre, sums)
        if nxt >= v * (1.0 - 1e-9):  # v meets the budgets with its own windows
            best, bud = v, nxt
            v = top if top < nxt else nxt
        else:
            v = 0.5 * (best + v)
    return best, (best if best > bud else bud)  # max(bud, best)


def _cap_at(v: float, t1: float, t2: float, s_j: float, s: np.ndarray, vb: np.ndarray, du: np.ndarray,
            al: np.ndarray, vt: np.ndarray, ba: np.ndarray, bj: np.ndarray, pre: np.ndarray,
            sums: np.ndarray) -> float:
    """v scaled to the budgets (≥ v: v meets them with its own windows): per axis the budget over the largest
    |Σ v_i·Δu_i| over T1 windows (sums[0]) and over their differences (sums[1]), the windows taken at v and at up
    to the highest speed the profile may reach between the junctions (decision motion 82: two corners around a
    short block it speeds up on fell in one window pair), the sums there and halfway there counting too. (C's
    sqrt, inf and nan compiled: math's attribute and call a junction were ≈ 400 instructions, decision bench B187;
    sqrt is correctly rounded in both.)"""
    n, axes = du.shape[0], du.shape[1]
    for k in range(axes):  # pre: zeros, then the running sums of min(vb, v)·du (np.cumsum's order)
        pre[0, k] = 0.0
    for i in range(n):
        x = vb[i]
        m = x if x < v or x != x else v  # np.minimum(vb, v)
        for k in range(axes):
            pre[i + 1, k] = m * du[i, k] if i == 0 else pre[i, k] + m * du[i, k]
    _window_sums(v, t1, t2, s_j, s, pre, sums, 0)
    peak = v
    if al.shape[0] > 0:
        peak = -_INF
        for i in range(al.shape[0]):
            q = v * v + al[i]
            r = _c_sqrt(q) if q >= 0.0 else _NAN
            x = vt[i]
            r = x if x < r or x != x else r  # np.minimum(vt, ·)
            if r > peak or r != r:
                peak = r
            if peak != peak:
                break
    if peak > v * (1.0 + 1e-9):
        for vw in (0.5 * (v + peak), peak):
            _window_sums(vw, t1, t2, s_j, s, pre, sums, 2)
            for k in range(axes):  # np.maximum(sa, xa), np.maximum(sd, xd)
                for j in range(2):
                    x, r = sums[j, k], sums[j + 2, k]
                    sums[j, k] = x if x >= r or x != x else r
    ca, cd = _INF, _INF  # the least of where(sa > 1e-12, ba / sa, inf), np.min's nan kept; the same for sd
    for k in range(axes):
        x = sums[0, k]
        r = ba[k] / x if x > 1e-12 else _INF
        if r < ca or r != r:
            ca = r
        x = sums[1, k]
        r = bj[k] / x if x > 1e-12 else _INF
        if r < cd or r != r:
            cd = r
    return v * (cd if cd < ca else ca)  # min(ca, cd)


def _window_sums(vw: float, t1: float, t2: float, s_j: float, s: np.ndarray, pre: np.ndarray, sums: np.ndarray,
                 row: int) -> int:
    """sums[row] and sums[row + 1]: per axis the largest |Σ| over T1 windows (path vw·T1) ending at every
    position where a sum may change (J, each junction plus a window, and just before), within one window pair
    after J, and the largest |difference| of it and the T1 window T2 before.

    Each window's three ends are counted (np.searchsorted(side="right")) by stepping on from the count of the same
    end of the window before it in its series (decision bench B187: a bisection each, ≈ 360 instructions a
    window): the four series (s[i] + w1, that less 1e-9, that plus w2, that less 1e-9) and the ends they give
    (e, e − w1, e − w1 − w2) never fall as i grows (s sorted, each IEEE rounding monotonic), so the count steps
    only forward; J's own window is bisected."""
    w1, w2 = vw * t1, vw * t2
    top = s_j + w1 + w2
    for k in range(pre.shape[1]):
        sums[row, k] = -_INF
        sums[row + 1, k] = -_INF
    if s_j >= s_j and s_j <= top:  # the window ending at J (nan: none)
        x = s_j - w1
        _window_max(pre, sums, row, _count_at_or_below(s, s_j), _count_at_or_below(s, x),
                    _count_at_or_below(s, x - w2))
    ends = np.zeros(12, dtype=np.intp)  # each series' three counts so far (its own three slots)
    for i in range(s.shape[0]):
        e = s[i] + w1
        _series_window(e, s_j, top, w1, w2, s, pre, sums, row, ends, 0)
        _series_window(e - 1e-9, s_j, top, w1, w2, s, pre, sums, row, ends, 3)
        e = e + w2
        _series_window(e, s_j, top, w1, w2, s, pre, sums, row, ends, 6)
        _series_window(e - 1e-9, s_j, top, w1, w2, s, pre, sums, row, ends, 9)
    return 0


def _series_window(e: float, s_j: float, top: float, w1: float, w2: float, s: np.ndarray, pre: np.ndarray,
                   sums: np.ndarray, row: int, ends: np.ndarray, c: int) -> int:
    """The window ending at e (if within J's pair of windows) into the maxima, its three ends counted on from the
    series' counts ends[c], ends[c + 1], ends[c + 2] (`_window_sums`: they never fall along a series)."""
    if e >= s_j and e <= top:
        x = e - w1
        ends[c] = _count_from(s, e, ends[c])
        ends[c + 1] = _count_from(s, x, ends[c + 1])
        ends[c + 2] = _count_from(s, x - w2, ends[c + 2])
        _window_max(pre, sums, row, ends[c], ends[c + 1], ends[c + 2])
    return 0


def _window_max(pre: np.ndarray, sums: np.ndarray, row: int, i0: int, i1: int, i2: int) -> int:
    """The window whose ends hold i0, i1 and i2 junctions (its end, its T1 start, the start of the T1 window T2
    before) into the maxima sums[row], sums[row + 1]."""
    for k in range(pre.shape[1]):
        mid = pre[i1, k]
        a = pre[i0, k] - mid
        d = abs(a - (mid - pre[i2, k]))
        a = abs(a)
        q = sums[row, k]
        if q == q and (a > q or a != a):  # np.max: nan kept
            sums[row, k] = a
        q = sums[row + 1, k]
        if q == q and (d > q or d != d):
            sums[row + 1, k] = d
    return 0


def _count_from(s: np.ndarray, x: float, k: int) -> int:
    """`_count_at_or_below(s, x)` for s sorted, given that it is at least k: stepped on from k (the same test as
    the bisection's: nan counts every position)."""
    n = s.shape[0]
    while k < n and not x < s[k]:
        k += 1
    return k


def _count_at_or_below(s: np.ndarray, x: float) -> int:
    """np.searchsorted(s, x, side="right") for s sorted: the first index whose position is above x (nan: none)."""
    lo, hi = 0, s.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if x < s[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo
