"""A run of short lines fitted by one curvature-continuous curve within N1.053 (decision motion 49, issue 18).

Corner blends sized by the half rule hold CAM programs of 0.78 mm segments near 1.15-1.22x their
feed-limited time, whatever their speed planning (decision 47); one C2 curve fitted to the run lets the feed
hold (decision 48: 1.010-1.025x as a bound). This module holds that fit and its pieces as path segments:
`fit_run` (nc.motion.spline_fit, re-exported here) fits smoothing splines x(u), y(u), z(u) (u the
polyline's chord length; quintic, the penalty on r''', decision 51) within the tolerance, `spans` cuts the curve at the polyline's vertices into
`SplineSpan`s (a `Segment` of kind "spline", parametrised by its own arc length), and `span_limits`
gives a span's speed cap and tangential acceleration and jerk from its per-axis curvature and jerk bounds.
The planner does not use them yet: `benchmarks/bench_spline_bound.py` does (decision 50).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

from typing import TYPE_CHECKING

import numpy as np

from nc.motion.path import Segment
from nc.motion.spline_fit import (DEGREE, LAM, PER_SEG, Cost, FitError, fit_curve, fit_run, polyline_distance, quintic,
                                  samples)

if TYPE_CHECKING:  # scipy.interpolate is imported where a fit runs (nc.motion.spline_fit.load_scipy)
    from scipy.interpolate import BSpline

__all__ = ["DEGREE", "LAM", "PER_SEG", "Cost", "FitError", "fit_curve", "fit_run", "polyline_distance", "quintic", "samples",
           "SplineSpan", "spans", "span_limits"]

NODES = 9  # arc-length table nodes a polynomial piece
CHEB = 9  # degree of a piece's position as a polynomial in its path length


@cache
def _gl5() -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights for arc lengths (numpy.polynomial, loaded by the first span: B84)."""
    return np.polynomial.legendre.leggauss(5)


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
        return tuple(_poly(cd, w).T for cd in _soa(self.coef[piece]))

    def derivatives(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Position, dr/ds, d²r/ds² and d³r/ds³ at path lengths s."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        flat = self.s_tab.ravel()
        k = np.clip(np.searchsorted(flat, s, side="right") - 1, 0, len(flat) - 2)
        piece = np.minimum(k // NODES, len(self.coef) - 1)
        return _by_arc(self.coef[piece], np.diff(self.brk)[piece], self.s_tab[piece], k - piece * NODES, s)

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

    def _end(self, at_end: bool) -> tuple[np.ndarray, np.ndarray]:
        """(dr/ds, d²r/ds²) at an end, worked out once: the look-ahead asks for them at every junction check
        (≈ 16 times a span), and a span does not change once cut (each call was a Newton solve)."""
        memo = self.__dict__.setdefault("_ends", {})
        if at_end not in memo:
            d = self.derivatives(np.array([self.length if at_end else 0.0]))
            memo[at_end] = (d[1][0], d[2][0])
        return memo[at_end]

    def unit_tangent(self, at_end: bool) -> np.ndarray:
        return self._end(at_end)[0].copy()

    def curvature_vector(self, at_end: bool) -> np.ndarray:
        return self._end(at_end)[1].copy()

    def max_direction_cosines(self) -> np.ndarray:
        return self.dir_bound.copy()


def _soa(c: np.ndarray) -> tuple[np.ndarray, ...]:
    """Polynomials c (n × (degree + 1) × axes, highest power first) and their first three derivatives' as
    coefficient stacks ((degree + 1 − d) × axes × n), each coefficient a contiguous row: Horner on them is
    the same arithmetic as on c, a few times faster."""
    k = c.shape[1] - 1
    ct = np.ascontiguousarray(c.transpose(1, 2, 0))
    out = []
    for d in range(4):  # the coefficient of w^(k-i) differentiated d times
        f = np.array([float(np.prod(np.arange(k - i - d + 1, k - i + 1))) if d else 1.0 for i in range(k - d + 1)])
        out.append(ct[:k - d + 1] * f[:, None, None] if d else ct)
    return tuple(out)


def _take(soa: tuple[np.ndarray, ...], idx: np.ndarray) -> tuple[np.ndarray, ...]:
    """The stacks of pieces idx (one a point)."""
    return tuple(np.take(c, idx, axis=2) for c in soa)


def _poly(cd: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Polynomials cd (a stack of `_soa`) at w (n): axes × n."""
    acc = cd[0].copy()
    for c in cd[1:]:
        acc = acc * w + c
    return acc


def _speed(cd: np.ndarray, w: np.ndarray) -> np.ndarray:
    r = _poly(cd, w)
    return np.sqrt(np.einsum("ij,ij->j", r, r))


def _arc(c1: np.ndarray, w0: np.ndarray, w1: np.ndarray) -> np.ndarray:
    """Arc length from w0 to w1 of polynomials whose derivative's stack is c1 (5-point Gauss-Legendre)."""
    h = 0.5 * (w1 - w0)
    out = np.zeros(len(w0))
    for x, g in zip(*_gl5()):
        out += g * _speed(c1, w0 + h * (x + 1.0))
    return out * h


def _by_arc(c: np.ndarray, width: np.ndarray, tab: np.ndarray, node: np.ndarray,
            s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position, dr/ds, d²r/ds², d³r/ds³ (each n × axes) at path lengths s, each on its own piece:
    polynomials c (n × (degree + 1) × axes) of chord length `width`, arc-length table `tab` (NODES a
    piece), s at or past the table's `node`."""
    cs = _soa(c)
    return _in_s(cs, _newton(cs, width, tab, node, s))


def _newton(cs: tuple[np.ndarray, ...], width: np.ndarray, tab: np.ndarray, node: np.ndarray,
            s: np.ndarray) -> np.ndarray:
    """The chord parameter w at path length s of each piece (`_by_arc`'s), by three Newton steps on its arc
    length from the table's node."""
    h = width / (NODES - 1)
    w0 = node * h
    s0 = tab[np.arange(len(s)), node]
    w = w0 + (s - s0) / np.maximum(_speed(cs[1], w0), 1e-12)
    for _ in range(3):
        w = np.clip(w, 0.0, width)
        w = w - (s0 + _arc(cs[1], w0, w) - s) / _speed(cs[1], w)
    return np.clip(w, 0.0, width)


def _in_s(cs: tuple[np.ndarray, ...], w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position and its first three derivatives in path length (each n × axes) at chord parameters w."""
    r, d1, d2, d3 = (_poly(cd, w) for cd in cs)
    sig2 = np.einsum("ij,ij->j", d1, d1)
    sig = np.sqrt(sig2)
    q = np.einsum("ij,ij->j", d1, d2)
    qd = np.einsum("ij,ij->j", d2, d2) + np.einsum("ij,ij->j", d1, d3)
    rs = d1 / sig
    rss = d2 / sig2 - q * d1 / sig2 ** 2
    rsss = (d3 / sig2 - 3.0 * q * d2 / sig2 ** 2 - qd * d1 / sig2 ** 2 + 4.0 * q * q * d1 / sig2 ** 3) / sig
    return r.T, rs.T, rss.T, rsss.T


_CHEB_X = np.cos(np.pi * (np.arange(CHEB + 1) + 0.5) / (CHEB + 1))
_CHEB_VI = np.linalg.inv(np.vander(_CHEB_X, CHEB + 1))  # values at the nodes -> coefficients, highest first


def spans(spl: list[BSpline], cum: np.ndarray, axes: tuple[str, ...], margin: float = 1.01,
          cost: Cost | None = None) -> list[SplineSpan]:
    """The fitted curve cut at the polyline's vertices (chord lengths cum), one span a segment; each
    span's per-axis bounds sampled at 33 points a piece, times `margin`. All spans at once, the same
    arithmetic as one by one (decision 53): arc-length tables, r(s) at the Chebyshev nodes and the bounds'
    samples each one batch over every piece of the run."""
    cost = cost or Cost()
    t = cost.lap("", 0.0)
    from scipy.interpolate import PPoly

    pp = [PPoly.from_spline(s) for s in spl]
    x = pp[0].x
    keep = np.diff(x) > 0.0
    starts = x[:-1][keep]
    coef = np.stack([p.c[:, keep] for p in pp], axis=-1).transpose(1, 0, 2)  # pieces × (degree + 1) × axes
    first = np.searchsorted(starts, cum[:-1] - 1e-9 * max(cum[-1], 1.0))
    m, n = len(cum) - 1, len(starts)
    count = np.diff(np.append(first, n))
    span = np.repeat(np.arange(m), count)  # each piece's span
    local = np.arange(n) - first[span]  # its index within the span
    last = local == count[span] - 1
    # chord-length breakpoints from each span's start, as spans cut one by one had them
    lo = starts[first[span]]
    a = starts - lo
    b = np.where(last, cum[span + 1], np.append(starts[1:], cum[-1])) - lo
    width = b - a
    t = cost.lap("cut", t)
    # arc-length tables: NODES - 1 Gauss-Legendre intervals a piece
    hw = np.repeat(width / (NODES - 1), NODES - 1)
    w0 = np.tile(np.arange(NODES - 1), n) * hw
    soa = _soa(coef)  # every piece's stacks once; each batch takes its columns
    seg_s = _arc(_take(soa, np.repeat(np.arange(n), NODES - 1))[1], w0, w0 + hw).reshape(n, NODES - 1)
    tab = np.concatenate([np.zeros((n, 1)), np.cumsum(seg_s, axis=1)], axis=1)
    off = np.zeros(n)
    for q in range(1, int(count.max())):  # each span's running sum, in its own order
        at = np.flatnonzero(local == q)
        off[at] = off[at - 1] + tab[at - 1, -1]
    s_tab = tab + off[:, None]
    length = s_tab[last, -1]
    t = cost.lap("tables", t)
    # r(s) on each piece at the Chebyshev nodes, then the polynomials through them
    sa, sb = s_tab[:, 0], s_tab[:, -1]
    sc = (0.5 * (sa[:, None] + sb[:, None]) + 0.5 * (sb - sa)[:, None] * _CHEB_X[None, :]).ravel()
    pc = np.repeat(np.arange(n), CHEB + 1)
    node = np.maximum((s_tab[pc, :NODES - 1] <= sc[:, None]).sum(axis=1) - 1, 0)
    cs = _take(soa, pc)
    wc = _newton(cs, width[pc], s_tab[pc], node, sc)
    r = _in_s(cs, wc)[0].reshape(n, CHEB + 1, -1)
    # r(s) and w(s) a piece as polynomials through them (w(s) is what the bounds' samples are read at)
    both = np.concatenate([r, wc.reshape(n, CHEB + 1, 1)], axis=2)
    both = np.einsum("ij,pjk->pik", _CHEB_VI, both)
    s_poly, w_poly = both[:, :, :-1], both[:, :, -1]
    t = cost.lap("chebyshev", t)
    # the bounds: 33 points a piece along each span's length, its ends first and last
    ns = 33 * count
    ss = np.repeat(np.arange(m), ns)
    j = np.arange(len(ss)) - np.repeat(np.cumsum(ns) - ns, ns)
    sv = np.where(j == ns[ss] - 1, length[ss], j * (length[ss] / (ns[ss] - 1)))
    pb = first[ss].copy()
    for q in range(1, int(count.max())):  # the piece each sample falls in (the table's last at its end)
        more = (q < count[ss]) & (s_tab[np.minimum(first[ss] + q, n - 1), 0] <= sv)
        pb[more] = first[ss][more] + q
    # w at each sample from its piece's w(s) (within 1e-13 of the Newton steps, a tenth of their time)
    x = (2.0 * sv - sa[pb] - sb[pb]) / (sb[pb] - sa[pb])
    wb = w_poly[pb, 0]
    for i in range(1, CHEB + 1):
        wb = wb * x + w_poly[pb, i]
    r, rs, rss, rsss = _in_s(_take(soa, pb), np.clip(wb, 0.0, width[pb]))
    edge = np.cumsum(ns) - ns
    dir_b = np.minimum(np.maximum.reduceat(np.abs(rs), edge) * margin, 1.0)
    acc_b = np.maximum.reduceat(np.abs(rss), edge) * margin
    jerk_b = np.maximum.reduceat(np.abs(rsss), edge) * margin
    t = cost.lap("bounds", t)
    out = []
    for i in range(m):
        k0, k1 = first[i], first[i] + count[i]
        out.append(SplineSpan(axes, r[edge[i]], r[edge[i] + ns[i] - 1], float(length[i]), "spline",
                              coef=coef[k0:k1], brk=np.append(a[k0:k1], b[k1 - 1]), s_tab=s_tab[k0:k1],
                              acc_bound=acc_b[i], jerk_bound=jerk_b[i], dir_bound=dir_b[i],
                              s_poly=s_poly[k0:k1]))
    # every span's end tangents and curvatures at once, as `SplineSpan._end` works them out one by one (the same
    # pieces, nodes and Newton steps; numpy's batched sums differ from one-by-one by an ulp at most: the traces of
    # the bench_vs_linuxcnc CAM programs, 400 and 2,000 segments, are byte-identical with either)
    ends = [(first, np.zeros(m, dtype=int), np.zeros(m)), (first + count - 1, np.full(m, NODES - 2), length)]
    for at_end, (pe, node, s_end) in enumerate(ends):
        _, d1, d2, _ = _by_arc(coef[pe], width[pe], s_tab[pe], node, s_end)
        for i, sp in enumerate(out):
            sp.__dict__.setdefault("_ends", {})[bool(at_end)] = (d1[i], d2[i])
    cost.lap("objects", t)
    return out


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
