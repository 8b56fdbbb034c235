"""A run of short lines fitted by one curvature-continuous curve within N1.053 (decision motion 49, issue 18).

Corner blends sized by the half rule hold CAM programs of 0.78 mm segments near 1.15-1.22x their
feed-limited time, whatever their speed planning (decision 47); one C2 curve fitted to the run lets the feed
hold (decision 48: 1.010-1.025x as a bound). This module holds that fit and its pieces as path segments:
`fit_run` fits smoothing splines x(u), y(u), z(u) (u the polyline's chord length; quintic, the penalty on
r''', decision 51) within the tolerance, `spans` cuts the curve at the polyline's vertices into
`SplineSpan`s (a `Segment` of kind "spline", parametrised by its own arc length), and `span_limits`
gives a span's speed cap and tangential acceleration and jerk from its per-axis curvature and jerk bounds.
The planner does not use them yet: `benchmarks/bench_spline_bound.py` does (decision 50).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps
from scipy.interpolate import BSpline, PPoly, make_smoothing_spline
from scipy.sparse.linalg import spsolve

from nc.motion.path import Segment

PER_SEG = 4  # polyline samples a segment the fit is made to
DEGREE = 5  # quintic, its r''' continuous (decision 51); 3: decisions 48-50's cubic smoothing spline
LAM = 0.01  # λ of the penalty ∫r'''² (mm⁵; of ∫r''² at DEGREE 3: 0.1 mm³); the weights then hold N1.053
NODES = 9  # arc-length table nodes a polynomial piece
CHEB = 9  # degree of a piece's position as a polynomial in its path length
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)


class FitError(RuntimeError):
    """No fit within the tolerance."""


def samples(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(chord-length parameter, points) of PER_SEG samples a segment, vertices included, and the
    vertices' chord lengths."""
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    f = np.arange(PER_SEG) / PER_SEG
    idx = np.repeat(np.arange(len(seg)), PER_SEG)
    ff = np.tile(f, len(seg))
    u = cum[idx] + ff * seg[idx]
    p = pts[idx] + ff[:, None] * (pts[idx + 1] - pts[idx])
    return np.append(u, cum[-1]), np.vstack([p, pts[-1]]), cum


def polyline_distance(curve: np.ndarray, cu: np.ndarray, pts: np.ndarray, cum: np.ndarray) -> np.ndarray:
    """Distance of each curve point (at chord parameter cu) from the polyline, over the segments within
    two of the one its parameter falls in."""
    k = np.clip(np.searchsorted(cum, cu) - 1, 0, len(pts) - 2)
    best = np.full(len(curve), np.inf)
    for off in (-2, -1, 0, 1, 2):
        i = np.clip(k + off, 0, len(pts) - 2)
        a, d = pts[i], pts[i + 1] - pts[i]
        t = np.clip(np.einsum("ij,ij->i", curve - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-30), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(curve - (a + t[:, None] * d), axis=1))
    return best


def fit_curve(pts: np.ndarray, lam: float = LAM, w: np.ndarray | None = None, degree: int = DEGREE) -> list[BSpline]:
    """Smoothing splines of the polyline's samples, one an axis, start and end pinned: quintic with the
    penalty ∫r'''², or cubic with ∫r''² (`degree` 3, scipy's make_smoothing_spline)."""
    u, p, _ = samples(pts)
    w = np.ones(len(u)) if w is None else w.copy()
    w[0] = w[-1] = 1e6
    if degree == 5:
        return quintic(u, p, w, lam)
    return [make_smoothing_spline(u, p[:, k], w=w, lam=lam) for k in range(pts.shape[1])]


def quintic(x: np.ndarray, y: np.ndarray, w: np.ndarray, lam: float, k: int = 5, pen: int = 3) -> list[BSpline]:
    """Penalised B-splines of degree k with knots at x: Σ w·(y − f)² + λ·∫(f^(pen))² least
    (y: samples × axes), one banded sparse solve."""
    t = np.concatenate([[x[0]] * k, x, [x[-1]] * k])
    n = len(t) - k - 1
    gx, gw = np.polynomial.legendre.leggauss(4)
    h = np.diff(x) / 2.0
    at = (x[:-1, None] + h[:, None] * (gx[None, :] + 1.0)).ravel()
    m = sps.identity(n, format="csr")
    tt, kk = t, k
    for _ in range(pen):  # the coefficients of the derivative's B-splines
        nn = m.shape[0]
        den = tt[kk + 1: kk + nn] - tt[1: nn]
        den = np.where(den > 0.0, den, np.inf)
        m = sps.diags([-kk / den, kk / den], [0, 1], shape=(nn - 1, nn), format="csr") @ m
        tt, kk = tt[1:-1], kk - 1
    dk = BSpline.design_matrix(at, tt, kk) @ m
    b = BSpline.design_matrix(x, t, k)
    a = (b.T @ sps.diags(w) @ b + lam * (dk.T @ sps.diags((h[:, None] * gw[None, :]).ravel()) @ dk)).tocsc()
    c = spsolve(a, b.T @ (w[:, None] * y))
    return [BSpline(t, c[:, j], k) for j in range(y.shape[1])]


def fit_run(pts: np.ndarray, tol: float, lam: float = LAM, rounds: int = 60, step: float = 0.005,
            degree: int = DEGREE) -> tuple[list[BSpline], np.ndarray]:
    """A fit within tol (checked every `step` mm of chord length, and 40 times finer within a step of
    where it comes within 0.9·tol), smoothed locally as much as it allows:
    the samples' weights grow (× (dev / 0.9·tol)³, never shrink) where the curve strays beyond 0.9·tol.
    Returns the splines and the vertices' chord lengths."""
    pts = np.asarray(pts, dtype=float)
    u, _, cum = samples(pts)
    w = np.ones(len(u))
    uu = np.append(np.arange(0.0, cum[-1], step), cum[-1])
    j = np.clip(np.searchsorted(u, uu), 0, len(u) - 1)
    for _ in range(rounds):
        spl = fit_curve(pts, lam, w, degree)
        dist = polyline_distance(np.stack([s(uu) for s in spl], axis=1), uu, pts, cum)
        near = np.flatnonzero(dist > 0.9 * tol)
        if len(near):  # the distance peaks sharply near a vertex: 40 points a step around the close ones
            uf = np.clip((uu[near][:, None] + np.linspace(-step, step, 41)[None, :]).ravel(), 0.0, cum[-1])
            df = polyline_distance(np.stack([s(uf) for s in spl], axis=1), uf, pts, cum)
            dist[near] = np.maximum(dist[near], df.reshape(len(near), 41).max(axis=1))
        if dist.max() <= tol:
            return spl, cum
        dev = np.zeros(len(u))  # each sample: the largest distance next to it
        np.maximum.at(dev, j, dist)
        np.maximum.at(dev, np.maximum(j - 1, 0), dist)
        # bounded: no overflow where tol cannot be met
        w = np.minimum(w * np.clip(dev / (0.9 * tol), 1.0, 10.0) ** 3, 1e9)
    raise FitError(f"no fit within {tol} mm in {rounds} rounds (λ {lam:g})")


@dataclass
class SplineSpan(Segment):
    """The fitted curve between two vertices: polynomial pieces r(w) = Σ c_k·w^(3−k) (w from each piece's
    start, `brk` its chord-length breakpoints from the span's start), evaluated by arc length s."""

    coef: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 0)))  # pieces × (degree + 1) × axes
    brk: np.ndarray = field(default_factory=lambda: np.zeros(0))
    s_tab: np.ndarray = field(default_factory=lambda: np.zeros((0, NODES)))  # arc length at the nodes
    acc_bound: np.ndarray = field(default_factory=lambda: np.zeros(0))  # max |d²r/ds²| per axis
    jerk_bound: np.ndarray = field(default_factory=lambda: np.zeros(0))  # max |d³r/ds³| per axis
    dir_bound: np.ndarray = field(default_factory=lambda: np.zeros(0))  # max |dr/ds| per axis
    # r(s) itself on each piece: polynomials in x = (2·s − s_a − s_b)/(s_b − s_a), highest power first,
    # interpolated at Chebyshev nodes when cut (`spans`), so that points() needs no Newton steps
    s_poly: np.ndarray = field(default_factory=lambda: np.zeros((0, CHEB + 1, 0)))

    def _derivs(self, piece: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, ...]:
        """r and its first three derivatives in w (Horner on the pieces' coefficients, highest first)."""
        c = self.coef[piece]  # n × (degree + 1) × axes
        w = w[:, None]
        k = c.shape[1] - 1
        out = []
        for d in range(4):
            acc = np.zeros((len(c), c.shape[2]))
            for i in range(k - d + 1):  # coefficient of w^(k-i) differentiated d times
                f = float(np.prod(np.arange(k - i - d + 1, k - i + 1))) if d else 1.0
                acc = acc * w + f * c[:, i]
            out.append(acc)
        return tuple(out)

    def _arc(self, piece: np.ndarray, w0: np.ndarray, w1: np.ndarray) -> np.ndarray:
        """Arc length from w0 to w1 within each piece (5-point Gauss-Legendre)."""
        h = 0.5 * (w1 - w0)
        out = np.zeros(len(piece))
        for x, g in zip(_GL_X, _GL_W):
            out += g * np.linalg.norm(self._derivs(piece, w0 + h * (x + 1.0))[1], axis=1)
        return out * h

    def derivatives(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Position, dr/ds, d²r/ds² and d³r/ds³ at path lengths s."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        flat = self.s_tab.ravel()
        k = np.clip(np.searchsorted(flat, s, side="right") - 1, 0, len(flat) - 2)
        piece = np.minimum(k // NODES, len(self.coef) - 1)
        node = k - piece * NODES
        h = np.diff(self.brk)[piece] / (NODES - 1)
        w0 = node * h
        s0 = self.s_tab[piece, node]
        w = w0 + (s - s0) / np.maximum(np.linalg.norm(self._derivs(piece, w0)[1], axis=1), 1e-12)
        for _ in range(3):  # Newton on the arc length from the node
            w = np.clip(w, 0.0, np.diff(self.brk)[piece])
            w = w - (s0 + self._arc(piece, w0, w) - s) / np.linalg.norm(self._derivs(piece, w)[1], axis=1)
        r, d1, d2, d3 = self._derivs(piece, np.clip(w, 0.0, np.diff(self.brk)[piece]))
        sig2 = np.einsum("ij,ij->i", d1, d1)[:, None]
        sig = np.sqrt(sig2)
        q = np.einsum("ij,ij->i", d1, d2)[:, None]
        qd = np.einsum("ij,ij->i", d2, d2)[:, None] + np.einsum("ij,ij->i", d1, d3)[:, None]
        rs = d1 / sig
        rss = d2 / sig2 - q * d1 / sig2 ** 2
        rsss = (d3 / sig2 - 3.0 * q * d2 / sig2 ** 2 - qd * d1 / sig2 ** 2 + 4.0 * q * q * d1 / sig2 ** 3) / sig
        return r, rs, rss, rsss

    def points(self, s: np.ndarray) -> np.ndarray:
        """Positions at path lengths s from the pieces' polynomials in s (within 1e-9 mm of derivatives())."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        if not len(self.s_poly):
            return self.derivatives(s)[0]
        sa, sb = self.s_tab[:, 0], self.s_tab[:, -1]
        piece = np.clip(np.searchsorted(sa, s, side="right") - 1, 0, len(sa) - 1)
        x = ((2.0 * s - sa[piece] - sb[piece]) / (sb[piece] - sa[piece]))[:, None]
        c = self.s_poly[piece]
        out = c[:, 0]
        for i in range(1, c.shape[1]):
            out = out * x + c[:, i]
        return out

    def unit_tangent(self, at_end: bool) -> np.ndarray:
        return self.derivatives(np.array([self.length if at_end else 0.0]))[1][0]

    def curvature_vector(self, at_end: bool) -> np.ndarray:
        return self.derivatives(np.array([self.length if at_end else 0.0]))[2][0]

    def max_direction_cosines(self) -> np.ndarray:
        return self.dir_bound.copy()


def spans(spl: list[BSpline], cum: np.ndarray, axes: tuple[str, ...], margin: float = 1.01) -> list[SplineSpan]:
    """The fitted curve cut at the polyline's vertices (chord lengths cum), one span a segment; each
    span's per-axis bounds sampled at 33 points a piece, times `margin`."""
    pp = [PPoly.from_spline(s) for s in spl]
    x = pp[0].x
    keep = np.diff(x) > 0.0
    starts = x[:-1][keep]
    coef = np.stack([p.c[:, keep] for p in pp], axis=-1).transpose(1, 0, 2)  # pieces × (degree + 1) × axes
    first = np.searchsorted(starts, cum[:-1] - 1e-9 * max(cum[-1], 1.0))
    out = []
    for i in range(len(cum) - 1):
        lo, hi = first[i], first[i + 1] if i + 1 < len(first) else len(starts)
        c = coef[lo:hi]
        brk = np.append(starts[lo:hi], cum[i + 1]) - starts[lo]
        sp = SplineSpan(axes, np.zeros(len(axes)), np.zeros(len(axes)), 0.0, "spline", coef=c, brk=brk)
        piece = np.repeat(np.arange(len(c)), NODES - 1)
        hw = np.repeat(np.diff(brk) / (NODES - 1), NODES - 1)
        w0 = np.tile(np.arange(NODES - 1), len(c)) * hw
        seg_s = sp._arc(piece, w0, w0 + hw).reshape(len(c), NODES - 1)
        tab = np.concatenate([np.zeros((len(c), 1)), np.cumsum(seg_s, axis=1)], axis=1)
        off = np.concatenate([[0.0], np.cumsum(tab[:, -1])[:-1]])
        sp.s_tab = tab + off[:, None]
        sp.length = float(off[-1] + tab[-1, -1])
        sp.s_poly = _in_s(sp)
        ends = sp.derivatives(np.array([0.0, sp.length]))[0]
        sp.start, sp.end = ends[0], ends[1]
        _, rs, rss, rsss = sp.derivatives(np.linspace(0.0, sp.length, 33 * len(c)))
        sp.dir_bound = np.minimum(np.abs(rs).max(axis=0) * margin, 1.0)
        sp.acc_bound = np.abs(rss).max(axis=0) * margin
        sp.jerk_bound = np.abs(rsss).max(axis=0) * margin
        out.append(sp)
    return out


def _in_s(sp: SplineSpan) -> np.ndarray:
    """Each piece's r(s) as a polynomial of degree CHEB in its normalised path length (Chebyshev nodes)."""
    sa, sb = sp.s_tab[:, 0], sp.s_tab[:, -1]
    x = np.cos(np.pi * (np.arange(CHEB + 1) + 0.5) / (CHEB + 1))
    s = (0.5 * (sa[:, None] + sb[:, None]) + 0.5 * (sb - sa)[:, None] * x[None, :]).ravel()
    r = sp.derivatives(s)[0].reshape(len(sa), CHEB + 1, -1)
    v = np.vander(x, CHEB + 1)  # highest power first
    return np.stack([np.linalg.solve(v, r[i]) for i in range(len(sa))])


# Of each axis' limits on a span: the curvature term v²·r'' takes ≤ 0.6 of the acceleration, v³·r''' ≤ 0.75
# of the jerk and the coupling 3·v·a_t·r'' ≤ 0.15; the tangential profile gets what is left (decisions 49, 50).
SPAN_ACC, SPAN_JERK, SPAN_COUPLING = 0.6, 0.75, 0.15


def span_limits(sp: SplineSpan, vel: np.ndarray, acc: np.ndarray, jerk: np.ndarray) -> tuple[float, float, float]:
    """(speed cap, tangential acceleration, tangential jerk) of a span. Per axis the acceleration is
    a_t·r' + v²·r'' and the jerk j_t·r' + 3·v·a_t·r'' + v³·r''' (r' = dr/ds ...): each term bounded by
    its largest value over the span, so any v ≤ the cap with |a_t| ≤ a and |j_t| ≤ j keeps every axis
    within its limits."""
    d, k2, k3 = sp.dir_bound, sp.acc_bound, sp.jerk_bound
    with np.errstate(divide="ignore"):
        v = float(min(np.min(vel / d), np.min(np.sqrt(SPAN_ACC * acc / k2)), np.min(np.cbrt(SPAN_JERK * jerk / k3))))
        v3 = v ** 3
        a = float(min(np.min((acc - v * v * k2) / d), np.min(SPAN_COUPLING * jerk / (3.0 * v * k2))))
        j = float(np.min((jerk - v3 * k3 - 3.0 * v * a * k2) / d))
    return v, a, j
