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
from bisect import bisect_left
from collections.abc import Sequence
from typing import TYPE_CHECKING

from nc.motion.limits import MotionConfig

if TYPE_CHECKING:
    from nc.motion.lookahead import Block


def _s_end(b: "Block") -> float:
    return b.s_end


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
        self._windows = [(self.t_a, self.budget_a, False), (self.t_j, self.budget_j, False)]
        if self.tol is not None:
            self._windows.append((self.t_j, (), True))
        # Junctions still inside some filter window, executed or not (for the sums).
        self._hist: list[Block] = []
        self._h0 = 0  # first entry of _hist still within reach of a window
        self._zero = (0.0,) * (len(self.budget_a) + 1)
        vmax = max(cfg.limit(a).max_velocity for a in cfg.axes)
        amax = max(cfg.limit(a).max_acceleration for a in cfg.axes)
        self.span_max = vmax * self.t_j + amax * self.t_j ** 2  # the longest any window can be

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
        """Cap the junctions within one filter window behind the newest junction (the end of
        blocks[-2]); returns how many blocks from the tail changed (for the backward pass).

        A window of duration T that ends at junction J (crossed at ≤ c) covers at most
        span(c) = c·T + a·T²/2 of path (speed falls by at most a·t going back in time), so
        every junction sharing a window with J lies within span(c) behind it. Going back
        junction by junction, the cap is budget/sum until the span that cap (or the fastest the
        blocks there can ever run, `vtop`) allows no longer reaches the next junction; every
        junction in that span gets the cap. Then for any window, with J its last junction:
        Σ v·|Δu| ≤ c_J · (the sum c_J was made from) ≤ budget. The spans shrink as the sums grow,
        so the junctions taken form a prefix, found by bisection on running sums. Junctions of
        blocks already executed still count (they stay in self._hist).
        """
        if len(blocks) < 2:
            return 0
        j_new = blocks[-2]
        hist = self._hist
        if j_new.du is None:
            # A stop: the planner waits there for the filter to settle, so no window holds
            # junctions from both sides of it.
            hist.clear()
            self._h0 = 0
            return 0
        prev = hist[-1].cum if len(hist) > self._h0 else self._zero
        j_new.cum = tuple(p + d for p, d in zip(prev, j_new.du + (j_new.du_n,)))
        hist.append(j_new)
        s_j = j_new.s_end
        h0 = self._h0
        while s_j - hist[h0].s_end > self.span_max:
            h0 += 1
        if h0 > 4096:
            del hist[:h0]
            h0 = 0
        self._h0 = h0
        last = len(hist) - 1
        tail = blocks[-1]
        acc = max(tail.a, j_new.a)
        top = max(tail.vtop, j_new.vtop)
        cum_j = j_new.cum
        axes = len(self.budget_a)

        def cap_from(m: int, budget: Sequence[float], norm: bool) -> float:
            """Cap from the junctions hist[m..last]."""
            base = hist[m - 1].cum if m > h0 else self._zero
            if norm:
                return self.tolerance_cap(j_new.du_n, cum_j[axes] - base[axes], acc)
            c = math.inf
            for i in range(axes):
                si = cum_j[i] - base[i]
                if si > 1e-12:
                    c = min(c, budget[i] / si)
            return c

        def first_taken(t_w: float, budget: Sequence[float], norm: bool) -> tuple[int, float]:
            pad = 0.5 * acc * t_w * t_w
            lo, hi = h0, last  # hist[hi] is taken; find the smallest taken index
            while lo < hi:
                mid = (lo + hi) // 2
                c = cap_from(mid + 1, budget, norm)
                if min(c, top) * t_w + pad >= s_j - hist[mid].s_end:
                    hi = mid
                else:
                    lo = mid + 1
            return lo, cap_from(lo, budget, norm)

        # Most junctions of gentle curves can never bind: even summed over the longest span any
        # window can have here, their caps stay above the fastest these blocks can run.
        if all(cap_from(bisect_left(hist, s_j - (top * t_w + 0.5 * acc * t_w * t_w), h0, last,
                                    key=_s_end), budget, norm) >= top
               for t_w, budget, norm in self._windows):
            return 0
        m_a, c_a = first_taken(self.t_a, self.budget_a, False)
        m_j, c_j = first_taken(self.t_j, self.budget_j, False)
        c_far = c_j
        m_far = m_j
        if self.tol is not None:
            m_t, c_t = first_taken(self.t_j, (), True)
            c_far = min(c_far, c_t)
            m_far = min(m_far, m_t)
        if min(c_a, c_far) == math.inf:
            return 0
        depth = 0
        k = 2
        idx = last
        it = reversed(blocks)
        next(it)
        for b in it:
            if idx < m_far and idx < m_a:
                break
            c = math.inf
            if idx >= m_a:
                c = c_a
            if idx >= m_j:
                c = min(c, c_j)
            if self.tol is not None and idx >= m_t:
                c = min(c, c_t)
            if b.vjunc > c:
                if b.vjunc > c * (1.0 + 1e-9):
                    depth = k  # float-noise changes need no new backward pass
                b.vjunc = c
            k += 1
            idx -= 1
        return depth
