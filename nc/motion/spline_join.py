"""The joint of two fitted windows (decision motion 57): a window's first spans shifted onto the last span of the
window before (`JoinedSpan`, `join`). Split from nc.motion.spline_feed so that the planner does not import the
fit with it: a run with no run to fit never loads nc.motion.spline_runs (bench decision B91)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from nc.motion.spline_runs import SplineSpan

JOIN = 2.0  # mm of path over which a window's first spans are shifted onto the span before them


def _fade(x: np.ndarray, d: int) -> np.ndarray:
    """d-th derivative of q(x) = 1 - smoothstep5(x) on [0, 1] (0 beyond): 1 at 0, 0 at 1, C2 at both ends."""
    x = np.clip(x, 0.0, 1.0)
    c = np.array([1.0, 0.0, 0.0, -10.0, 15.0, -6.0])
    for _ in range(d):
        c = np.polynomial.polynomial.polyder(c)
    return np.polynomial.polynomial.polyval(x, c)


@dataclass
class JoinedSpan(SplineSpan):
    """A span near the joint of two windows, shifted onto the span before it (decision motion 57): the two fits
    differ there by up to 2e-4 mm, a step one cycle turns into 2x the axis jerk. Shift(σ) = (dp + dv·σ)·q(σ/JOIN),
    σ the path length from the joint (`s0` at this span's start): position and direction meet the span before,
    and the shift fades out C2 within JOIN mm (its curvature about 3e-4 /mm, its third derivative about
    1e-3 /mm², within the span's 1 % bounds margin)."""

    dp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dv: np.ndarray = field(default_factory=lambda: np.zeros(0))
    s0: float = 0.0

    def _shift(self, s: np.ndarray, d: int) -> np.ndarray:
        sig = self.s0 + np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        x = sig / JOIN
        p = self.dp[None, :] + sig[:, None] * self.dv[None, :]
        out = p * (_fade(x, d) / JOIN ** d)[:, None]
        if d:  # Leibniz: p' = dv, p'' = 0
            out = out + d * self.dv[None, :] * (_fade(x, d - 1) / JOIN ** (d - 1))[:, None]
        return np.where((sig < JOIN)[:, None], out, 0.0)

    def points(self, s: np.ndarray) -> np.ndarray:
        return SplineSpan.points(self, s) + self._shift(s, 0)

    def derivatives(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r = SplineSpan.derivatives(self, s)
        return tuple(x + self._shift(s, d) for d, x in enumerate(r))  # type: ignore[return-value]


def join(tail: SplineSpan, cut: list[SplineSpan]) -> list[SplineSpan]:
    """The spans of a new window, the first of them shifted onto `tail` (the last span of the window before)."""
    a = tail.derivatives(np.array([tail.length]))
    b = cut[0].derivatives(np.array([0.0]))
    dp, dv = a[0][0] - b[0][0], a[1][0] - b[1][0]
    out, s0 = [], 0.0
    for sp in cut:
        if s0 < JOIN:
            sp = JoinedSpan(**{f.name: getattr(sp, f.name) for f in fields(sp)}, dp=dp, dv=dv, s0=s0)
            ends = sp.points(np.array([0.0, sp.length]))
            sp.start, sp.end = ends[0], ends[1]
        out.append(sp)
        s0 += sp.length
    return out
