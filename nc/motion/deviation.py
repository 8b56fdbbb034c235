"""How far the position filter (nc.motion.smoothing) pulls the path off the polyline: a model
made from the filter's own kernel, on the *signed* tangent steps (issue 18).

At constant speed v a polyline is p(t) = linear + Σ v·Δu_i·ramp(t − t_i), Δu_i the signed tangent
step at junction i. The two moving averages are one discrete kernel k_m (the convolution of the
boxes) around its centre d; the filtered point minus the path point d earlier is then exactly

    e(t) = v · Σ_i Δu_i · G(t − d − t_i),     G(x) = Σ_m k_m · (z_m − |x|)⁺,   z_m = m·T − d,

G even, zero beyond the half window, G(0) = E|z|/2. One corner: e = v·|Δu|·G(0). A smooth curve of
radius R sampled by chords: Σ Δu_i ≈ v·dt/R, so e ≈ v²/R · ∫G = v²·σ²/(2R) with σ² the kernel's
variance ((T1² + T2²)/12): the arc formula. Zig-zag tangent jumps from rounded coordinates cancel
in the signed sum, as they do in the filter. |e| bounds the distance to the path.

`caps` solves, per evaluation junction K, the highest speed c whose deviation at K stays within
the room left of the tolerance, with the junctions around K at that speed (time = path / c).
"""

from __future__ import annotations

import bisect
import math

import numpy as np


class KernelDeviation:
    def __init__(self, n1: int, n2: int, cycle: float) -> None:
        k = np.convolve(np.full(n1, 1.0 / n1), np.full(n2, 1.0 / n2))
        z = (np.arange(len(k)) - (len(k) - 1) / 2.0) * cycle
        self.half = float(z.max())  # G vanishes beyond it (s)
        self._y = np.linspace(0.0, max(self.half, 1e-12), 97)
        self._g = np.array([float(np.sum(k * np.maximum(z - y, 0.0))) for y in self._y])
        self.g0 = float(self._g[0])
        self._k, self._z = k, np.abs(z)

    def speed_up(self, a: float, j: float) -> float:
        """Half the kernel-weighted path a jerk-limited speed change (limits a, j, from zero
        acceleration at the corner) adds around a corner: Σ k_m·D(|z_m|)/2, D(τ) = jτ³/6 up to
        τ = a/j, then with the acceleration a (the braking term's shape, per unit |Δu|)."""
        z, ta = self._z, a / j
        d = np.where(z <= ta, j * z ** 3 / 6.0,
                     j * ta ** 3 / 6.0 + j * ta * ta / 2.0 * (z - ta) + a * (z - ta) ** 2 / 2.0)
        return float(np.sum(self._k * d)) / 2.0

    def weights(self, x: np.ndarray) -> np.ndarray:
        """G(x) for time offsets x (s)."""
        return np.interp(np.abs(x), self._y, self._g, right=0.0)

    def deviation(self, c: np.ndarray, s_eval: np.ndarray, s_all: np.ndarray, du: np.ndarray,
                  vb: np.ndarray | None = None) -> np.ndarray:
        """|e| at each evaluation junction (path positions s_eval, speeds c) from the signed steps
        du (n × axes) at path positions s_all, each crossed at min(c, vb) (vb: a cap the junction
        can never exceed; a slow corner's step is its own speed times Δu, not c's)."""
        w = self.weights((s_all[None, :] - s_eval[:, None]) / c[:, None])
        if vb is None:
            return c * np.linalg.norm(w @ du, axis=1)
        return np.linalg.norm((w * np.minimum(vb[None, :], c[:, None])) @ du, axis=1)

    def caps(self, s_eval: np.ndarray, room: np.ndarray, top: float, s_all: np.ndarray,
             du: np.ndarray, vb: np.ndarray | None = None) -> np.ndarray:
        """Highest speeds (≤ top) whose deviation at each evaluation junction stays within room.

        The deviation grows with the speed about as c^p, 1 ≤ p ≤ 2 (a corner: p = 1; a curve:
        p = 2), so a step down by room/e lands at or below the room and a step up by √(room/e)
        does not pass it. Where cancelling steps make it grow slower, a step may miss: the last
        passes only step down, and every speed returned was evaluated within the room. Steps
        held below c by vb grow slower still (only through the time offsets, (s_i − s_K)/c):
        what the steps leave unmet is bisected.
        """
        c = np.where(room > 0.0, float(top), 0.0)
        live = np.nonzero(room > 0.0)[0]
        if len(live) == 0:
            return c
        cc, rr, se = c[live], room[live], s_eval[live]
        reduced = np.zeros(len(cc), dtype=bool)
        for it in range(12):
            e = self.deviation(cc, se, s_all, du, vb)
            bad = e > rr
            if not bad.any() and (it >= 4 or not reduced.any()):
                break
            step = np.ones(len(cc))
            step[bad] = np.minimum(rr[bad] / e[bad], 0.98)
            if it < 4:
                up = reduced & ~bad & (e < 0.98 * rr)
                step[up] = np.sqrt(rr[up] / np.maximum(e[up], 1e-300))
            reduced |= bad
            cc = np.minimum(np.maximum(cc * step, 1e-6), top)
        else:
            bad = self.deviation(cc, se, s_all, du, vb) > rr
            if bad.any():
                lo, hi = np.zeros(int(bad.sum())), cc[bad]
                for _ in range(24):
                    mid = 0.5 * (lo + hi)
                    ok = self.deviation(np.maximum(mid, 1e-9), se[bad], s_all, du, vb) <= rr[bad]
                    lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
                cc[bad] = lo  # evaluated within the room (0: never met, stop there)
        c[live] = cc
        return c


def gained_path(x: float, v: float, a0: float, acc: float, jerk: float) -> float:
    """Upper bound of the path covered in x ≥ 0 seconds from speed v and acceleration a0 (toward gaining), the
    acceleration at most acc and changing at most jerk per second: the speed v + ∫ min(acc, a0 + jerk·u) du."""
    ta = (acc - a0) / jerk if a0 < acc else 0.0  # until the acceleration reaches acc
    xa = x if x < ta else ta
    xb = x - xa
    return (v * x + a0 * xa * xa / 2.0 + jerk * xa ** 3 / 6.0 + (a0 * ta + jerk * ta * ta / 2.0) * xb
            + acc * xb * xb / 2.0)


class CornerBound:
    """A proved bound of how far the filter's output leaves the legs of an isolated line-line corner (decision
    motion 73), whatever the raw profile does inside the window: crossed at speed v, any acceleration there.

    Near a lone corner C (directions u1 → u2, turn θ) the output at time t_c − τ is C − u1·m1 + u2·m2 with
    m1 = Σ_{z<τ} k_z·P1(τ − z), m2 = Σ_{z>τ} k_z·P2(z − τ) (P1, P2 the path covered in that time before and
    after the crossing), and its distance from the legs is at most min(m1, m2)·sin θ (the foot on the longer
    side's leg, within it when m·(1 + |cos θ|) is shorter than the leg). With the acceleration a0 at the
    crossing, each side covers at most `gained_path(x, v, ∓a0, acc, jerk)` (U1, U2 in place of m1, m2);
    a0² ≤ 2·jerk·v, or the speed on the other side would have to fall below zero. U1 rises and U2 falls with τ,
    so their crossing, bisected to [lo, hi], bounds min(U1, U2) at every τ by min(U1(hi), U2(lo)); on an a0
    interval [a_k, a_k+1] U1 takes −a_k and U2 a_k+1: the largest over the intervals bounds the deviation
    (per unit sin θ) from above.

    Everything scales with acc (v, a0, acc and jerk times λ: the path times λ), so one grid over u = v/acc per
    jerk/acc ratio (rounded up: more jerk, more path) serves every corner, its bounds found when first asked;
    a cap is a grid point.
    """

    U0, U_STEP, U_N = 1e-5, 1.01, 1050  # u = v/acc grid (s): 10 µs … 0.35 s
    A_N, BISECT = 32, 32  # a0 intervals, bisection steps of the crossing
    RATIO_STEPS = 16  # jerk/acc ratios rounded up to 2^(1/16)

    def __init__(self, kd: KernelDeviation) -> None:
        self._k = kd._k
        n = len(kd._k)
        self._z = (np.arange(n) - (n - 1) / 2.0) * (2.0 * kd.half / max(n - 1, 1))
        self.span = 2.0 * kd.half  # a window containing the crossing holds samples up to this far in time from it
        self._u = (self.U0 * self.U_STEP ** np.arange(self.U_N)).tolist()
        self._w: dict[tuple[int, int], float] = {}  # (ratio key, u index): the bound, found when first asked

    @staticmethod
    def _path(x: np.ndarray, v: float, a0: np.ndarray, jerk: float) -> np.ndarray:
        """gained_path for acc = 1, elementwise (broadcast), x ≥ 0."""
        ta = np.maximum((1.0 - a0) / jerk, 0.0)
        xa = np.minimum(x, ta)
        xb = x - xa
        return v * x + a0 * xa * xa / 2.0 + jerk * xa ** 3 / 6.0 + (a0 * ta + jerk * ta * ta / 2.0) * xb + xb * xb / 2.0

    def bound(self, u: float, jerk: float) -> float:
        """The deviation bound per unit sin θ for acc = 1 at speed u (s) and this jerk (1/s)."""
        k, z = self._k, self._z
        am = min(1.0, math.sqrt(2.0 * jerk * u))
        ag = np.linspace(-am, am, self.A_N + 1)[:, None]
        g1, g2 = -ag[:-1], ag[1:]  # for a0 in [a_k, a_k+1]: the before side gains from −a0 ≤ −a_k, the after side
        # from a0 ≤ a_k+1

        def u1(tau: np.ndarray) -> np.ndarray:
            d = tau - z
            return (np.where(d > 0.0, self._path(np.maximum(d, 0.0), u, g1, jerk), 0.0) * k).sum(axis=1)

        def u2(tau: np.ndarray) -> np.ndarray:
            d = z - tau
            return (np.where(d > 0.0, self._path(np.maximum(d, 0.0), u, g2, jerk), 0.0) * k).sum(axis=1)

        # U1 rises and U2 falls with τ: their crossing is bisected, and min(U1(hi), U2(lo)) bounds min(U1, U2) at
        # every τ (left of lo: U1(τ) ≤ U1(lo) < U2(lo), U1(lo) ≤ U1(hi); right of hi: U2(τ) ≤ U2(hi) ≤ U1(hi),
        # U2(hi) ≤ U2(lo); between them U1 ≤ U1(hi), U2 ≤ U2(lo))
        lo, hi = np.full((self.A_N, 1), z[0]), np.full((self.A_N, 1), z[-1])
        for _ in range(self.BISECT):
            mid = 0.5 * (lo + hi)
            left = (u1(mid) < u2(mid))[:, None]
            lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
        return float(np.minimum(u1(hi), u2(lo)).max())

    def cap(self, tol: float, du_n: float, acc: float, jerk: float, len1: float, len2: float,
            top1: float, top2: float) -> float:
        """The highest grid speed at which the line-line corner of tangent step du_n (between legs of len1, len2
        mm, their blocks never faster than top1, top2) stays within tol from its legs and alone in every filter
        window that holds it, for any raw profile with tangential acceleration ≤ acc and jerk ≤ jerk; 0 when the
        corner cannot be shown alone in its windows."""
        if acc <= 0.0 or jerk <= 0.0 or du_n <= 1e-9 or du_n >= 2.0:
            return 0.0
        cos_t = 1.0 - du_n * du_n / 2.0
        sin_t = du_n * math.sqrt(1.0 - du_n * du_n / 4.0)  # sin θ = 2 sin(θ/2) cos(θ/2)
        leg = len1 if len1 < len2 else len2
        span = self.span
        # Cheap test first: from standstill at zero acceleration a window already reaches this far.
        if min(max(top1, top2) * span, gained_path(span, 0.0, 0.0, acc, jerk)) >= leg:
            return 0.0
        key = math.ceil(math.log2(jerk / acc) * self.RATIO_STEPS - 1e-9)
        jr = 2.0 ** (key / self.RATIO_STEPS)  # ≥ jerk / acc
        room = tol / (acc * sin_t)
        alone = top1 * span < len1 and top2 * span < len2  # no window holding it reaches a neighbour at any speed
        foot = leg / ((1.0 + abs(cos_t)) * acc)
        us, memo = self._u, self._w

        def ok(i: int) -> bool:
            """Speed acc·u_i keeps the corner within tol and alone (each test true for every lower speed too)."""
            u = us[i]
            am = min(1.0, math.sqrt(2.0 * jr * u))
            if not alone and gained_path(span, u, am, 1.0, jr) >= leg / acc:
                return False  # a neighbouring junction may share a window with it
            if float(np.sum(self._k * self._path(self._z[-1] - self._z, u, np.array(am), jr))) >= foot:
                return False  # the output's foot may fall beyond the leg
            w = memo.get((key, i))
            if w is None:
                w = memo[(key, i)] = self.bound(u, jr)
            return w <= room

        if not ok(0):
            return 0.0
        lo, hi = 0, len(us)  # ok(lo); hi: not known to be ok
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if ok(mid):
                lo = mid
            else:
                hi = mid
        # every test holds at u_lo and, the true quantities rising with the speed, below it
        return acc * us[lo]
