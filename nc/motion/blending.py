"""Corner speeds under the post-interpolation filter (nc.motion.smoothing).

With the filter, a tangent jump Δu crossed at speed v is a velocity step v·Δu_i on each axis,
which the two moving averages (T1, T2) turn into an acceleration ≤ v·Δu_i/T1 and a jerk
≤ v·Δu_i/(T1·T2). Junctions that follow each other closely add up inside the filter windows, so
the limit is on sums: over any stretch the path covers in T1 (acceleration) or T1+T2 (jerk),
    max speed there · Σ|Δu_i| ≤ share_corner · a_i · T1     and     ≤ share_corner · j_i · T1 · T2.
The filter also rounds the corner: the output passes the corner point at a distance of
about v·|Σ Δu|·(T1+T2)/8 (the kernel's mean |t| is at most (T1+T2)/4), which must stay within the
G64 path tolerance.

Every new junction J caps the junctions within one window behind it (J included) by
budget / (sum over that stretch). For any time window W, the fastest junction m of W lies within
one window behind W's last junction, whose cap was computed over a sum that holds all of W, so
Σ_W v·|Δu| ≤ v_m·Σ_W |Δu| ≤ budget.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from typing import TYPE_CHECKING

from nc.motion.limits import MotionConfig

if TYPE_CHECKING:
    from nc.motion.lookahead import Block


def _push_max(q: deque[tuple[int, float]], seq: int, value: float) -> None:
    """Append to a sliding maximum (a deque of decreasing values; the front is the maximum)."""
    while q and q[-1][1] <= value:
        q.pop()
    q.append((seq, value))


def _push_front_max(q: deque[tuple[int, float]], seq: int, value: float) -> None:
    """Extend a sliding maximum backwards by an entry older than all it holds."""
    if not q or value > q[0][1]:
        q.appendleft((seq, value))


def _drop_before(q: deque[tuple[int, float]], seq: int) -> None:
    while q[0][0] < seq:
        q.popleft()


class FilterCorners:
    def __init__(self, cfg: MotionConfig, acc: Sequence[float], jerk: Sequence[float]) -> None:
        n1, n2 = cfg.filter_cycles()
        t1, t2 = n1 * cfg.cycle, n2 * cfg.cycle
        self.t_a = t1  # window of the acceleration sum (s)
        self.t_j = t1 + t2  # window of the jerk sum (s)
        sc = cfg.share_corner
        self.budget_a = tuple(sc * a * t1 for a in acc)
        self.budget_j = tuple(sc * j * t1 * t2 for j in jerk)
        self.tol = cfg.path_tolerance
        self.dev = (t1 + t2) / 8.0  # corner deviation per unit of v·|ΣΔu|
        self.t2sum = t1 * t1 + t2 * t2
        # One window of T1+T2 for both sums: a T1 window lies inside it.
        self.budget = tuple(min(ba, bj) for ba, bj in zip(self.budget_a, self.budget_j))
        self._axes = len(self.budget)
        self._zero = (0.0,) * (self._axes + 1)
        # Junctions still inside some filter window, executed or not (for the sums).
        self._hist: list[Block] = []
        self._clear()
        # The longest any window can be: no path speed or acceleration exceeds the norm of the
        # axis limits (a path direction can use every axis at once).
        vmax = math.sqrt(sum(cfg.limit(a).max_velocity ** 2 for a in cfg.axes))
        amax = math.sqrt(sum(cfg.limit(a).max_acceleration ** 2 for a in cfg.axes))
        self.span_max = vmax * self.t_j + amax * self.t_j ** 2

    def _clear(self) -> None:
        self._hist.clear()
        self._h0 = 0  # first entry of _hist still within reach of a window
        self._m = 0  # where the last search for the first junction taken ended
        self._seq0 = 0  # junctions dropped from the front of _hist so far
        # Sliding maxima over _hist[_m:] as (sequence number, value) of the blocks' tangential
        # acceleration, vtop and length.
        self._maxima: tuple[deque[tuple[int, float]], ...] = (deque(), deque(), deque())

    def corner(self, du: Sequence[float], acc: float) -> float:
        """Speed cap of one isolated tangent jump (|Δu| per axis) between blocks whose path
        acceleration reaches `acc`."""
        v = math.inf
        for d, ba, bj in zip(du, self.budget_a, self.budget_j):
            if d > 1e-12:
                v = min(v, ba / d, bj / d)
        if self.tol is not None:
            n = math.sqrt(sum(d * d for d in du))
            if n > 1e-12:
                v = min(v, self.tolerance_cap(n, n, acc))
        return v

    def tolerance_cap(self, du_n: float, sum_n: float, acc: float) -> float:
        """Highest corner speed whose rounding stays within the tolerance. Braking into and
        speeding out of the corner inside the filter window cuts it too, by about
        |Δu|·a·(T1²+T2²)/192 (measured on 90° corners: 1/240); when that alone exceeds the
        tolerance the corner is an exact stop (0), which the filter then passes exactly."""
        floor = du_n * acc * self.t2sum / 192.0
        if floor >= self.tol:
            return 0.0
        if sum_n <= 1e-12:
            return math.inf
        return (self.tol - floor) / (self.dev * sum_n)

    def arc_speed(self, radius: float) -> float:
        """Highest speed on an arc whose filtered radius shrinks by no more than the tolerance.

        Two moving averages shrink a circle by about r·ω²·(T1² + T2²)/24 with ω = v/r; bounded
        here with (T1+T2)² ≥ T1² + T2².
        """
        if self.tol is None or radius <= 0.0:
            return math.inf
        return math.sqrt(24.0 * self.tol * radius) / self.t_j

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
        hist = self._hist
        if j_new.du is None:
            # A stop: the planner waits there for the filter to settle, so no window holds
            # junctions from both sides of it.
            self._clear()
            return 0
        h0 = self._h0
        last = len(hist)
        prev = hist[-1].cum if last > h0 else self._zero
        du = j_new.du
        if self._axes == 3:  # the common case spelt out (this runs once per pushed block)
            cum_j = (prev[0] + du[0], prev[1] + du[1], prev[2] + du[2], prev[3] + j_new.du_n)
        else:
            cum_j = tuple(p + d for p, d in zip(prev, du + (j_new.du_n,)))
        j_new.cum = cum_j
        hist.append(j_new)
        s_j = j_new.s_end
        span_max = self.span_max
        while s_j - hist[h0].s_end > span_max:
            h0 += 1
        if h0 > 4096:
            del hist[:h0]
            self._seq0 += h0
            self._m -= h0
            h0 = 0
        self._h0 = h0
        # The search starts where the previous junction's ended; the maxima of tangential
        # acceleration and vtop are kept over hist[m..last] for that m.
        m = self._m
        if m < h0:
            m = h0
        maxima = self._maxima
        for q, x in zip(maxima, (j_new.a, j_new.vtop, j_new.length)):
            _push_max(q, self._seq0 + last, x)
            _drop_before(q, self._seq0 + m)
        acc_q, top_q, len_q = maxima
        tail = blocks[-1]
        t_w = self.t_j
        # J is crossed no faster than either block beside it can run.
        top = tail.vtop if tail.vtop < j_new.vtop else j_new.vtop
        t_w2 = t_w * t_w
        # Going back in time from J the speed rises by at most the tangential acceleration.
        pad = 0.5 * acc_q[0][1] * t_w2
        two_al = 2.0 * acc_q[0][1] * len_q[0][1]
        v_hi = top_q[0][1]
        budget = self.budget
        axes = self._axes
        tol = self.tol
        zero = self._zero
        if tol is not None:
            acc = tail.a if tail.a > j_new.a else j_new.a
            room = tol - j_new.du_n * acc * self.t2sum / 192.0  # after J's own braking term
            dev = self.dev

        def cap(m: int) -> float:
            """Cap from the junctions hist[m..last] (inf when there are none)."""
            if m > last:
                return math.inf
            base = hist[m - 1].cum if m > h0 else zero
            c = math.inf
            for i in range(axes):
                si = cum_j[i] - base[i]
                if si > 1e-12:
                    x = budget[i] / si
                    if x < c:
                        c = x
            if tol is not None:
                if room <= 0.0:
                    return 0.0
                sn = cum_j[axes] - base[axes]
                if sn > 1e-12:
                    x = room / (dev * sn)
                    if x < c:
                        c = x
            return c

        def taken(k: int) -> bool:
            """Whether a window ending at J can reach back to junction k when the junctions after
            it run at no more than their common cap c: it covers no more path than J's speed
            plus what the acceleration adds going back, nor than the highest speed anywhere in
            the stretch (a block between junctions ≤ c reaches √(c² + 2·A·L)) allows in T."""
            c = cap(k + 1)
            d = s_j - hist[k].s_end
            if (c if c < top else top) * t_w + pad < d:
                return False
            return (c * c + two_al) * t_w2 >= d * d and v_hi * t_w >= d

        m0 = m
        if taken(m):
            while m > h0 and taken(m - 1):
                m -= 1
            while m < m0:
                # The stretch grew backwards past the maxima's start: take its blocks into them;
                # a higher acceleration widens the span, which may take more junctions still.
                for k in range(m0 - 1, m - 1, -1):
                    b = hist[k]
                    for q, x in zip(maxima, (b.a, b.vtop, b.length)):
                        _push_front_max(q, self._seq0 + k, x)
                m0 = m
                pad = 0.5 * acc_q[0][1] * t_w2
                two_al = 2.0 * acc_q[0][1] * len_q[0][1]
                v_hi = top_q[0][1]
                while m > h0 and taken(m - 1):
                    m -= 1
        else:
            m += 1
            while not taken(m):
                m += 1
            for q in maxima:
                _drop_before(q, self._seq0 + m)
        self._m = m
        c = cap(m)
        if c >= top_q[0][1]:
            return 0  # no junction of the stretch can run as fast as this cap
        depth = 0
        k = 2
        idx = last
        it = reversed(blocks)
        next(it)
        for b in it:
            if idx < m:
                break
            if b.vjunc > c:
                b.vjunc = c
                # Lowering a junction below its planned speed needs a new backward pass down to
                # it; above it nothing changes (float noise included).
                if c < b.vend * (1.0 - 1e-9):
                    depth = k
            k += 1
            idx -= 1
        return depth
