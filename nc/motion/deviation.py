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
