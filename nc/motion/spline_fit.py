"""The smoothing-spline fit of a CAM run within N1.053 (decisions motion 48, 49, 51; its cost: 53).

`fit_run` fits x(u), y(u), z(u) (u the polyline's chord length) by a quintic penalised B-spline with knots at
PER_SEG samples a segment, the penalty λ·∫r'''², reweighted until every point of the curve is within the
tolerance. Everything that depends on the knots only (the samples' B-spline rows, the penalty's band, the
check grid's B-spline rows and its nearest segments) is built once a run (`_Problem`); a round then costs
one weighted band (np.bincount), one banded Cholesky solve (LAPACK dpbsv) and a sparse
product for the curve on the grid (decision 53). nc.motion.spline_runs re-exports these names.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cache
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # scipy's interpolate, sparse and linalg take ≈ 0.17 s to import: only a spline fit needs them
    import scipy.sparse as sps
    from scipy.interpolate import BSpline

PER_SEG = 4  # polyline samples a segment the fit is made to
DEGREE = 5  # quintic, its r''' continuous (decision 51); 3: decisions 48-50's cubic smoothing spline
LAM = 0.01  # λ of the penalty ∫r'''² (mm⁵; of ∫r''² at DEGREE 3: 0.1 mm³); the weights then hold N1.053
FINE = 20  # the check's finer look: FINE points a grid step (decision 51: 40 over the two steps around)
_OFFSETS = (-2, -1, 0, 1, 2)  # the segments a curve point is measured against, around its own


@cache
def _gl4() -> tuple[np.ndarray, np.ndarray]:
    """The penalty's quadrature a knot interval (numpy.polynomial, 4-8 ms to import, loaded by the first fit: a
    run that never fits does without it, B84)."""
    return np.polynomial.legendre.leggauss(4)


_TRIU = {w: np.triu_indices(w) for w in range(1, 8)}  # a band's pairs of a row's entries


def load_scipy() -> None:
    """Import the scipy parts a fit uses (each function imports what it calls when it runs): `hil`'s runner does
    it before paced cycles or a real bus, where an import's ≈ 0.17 s inside a cycle would overrun it."""
    import scipy.interpolate  # noqa: F401
    import scipy.linalg.lapack  # noqa: F401
    import scipy.sparse  # noqa: F401

    _gl4()  # (numpy.polynomial with it)


class FitError(RuntimeError):
    """No fit within the tolerance."""


@dataclass
class Cost:
    """CPU seconds by part, when asked for (`benchmarks/bench_spline_bound.py --cost`); the default
    times nothing."""

    parts: dict[str, float] | None = None  # None: not timed
    rounds: int = 0

    def lap(self, part: str, since: float) -> float:
        """Charge the time since `since` to `part` and return now (0.0 when not timing)."""
        if self.parts is None:
            return 0.0
        now = time.process_time()
        if part:
            self.parts[part] = self.parts.get(part, 0.0) + now - since
        return now


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


@dataclass
class _Segs:
    """The polyline's segments: starts, vectors and squared lengths, and how far each is at least from the
    segments two before and two after it."""

    a: np.ndarray
    d: np.ndarray
    dd: np.ndarray
    apart: np.ndarray  # 2 × segments: from the one two before / after (inf: none, or one of the nearer)

    @classmethod
    def of(cls, pts: np.ndarray) -> "_Segs":
        d = np.diff(pts, axis=0)
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-30)
        # bounding spheres: two segments are at least their centres' distance less their half lengths apart
        c, half = pts[:-1] + 0.5 * d, 0.5 * np.sqrt(dd)
        gap = np.linalg.norm(c[2:] - c[:-2], axis=1) - half[2:] - half[:-2]
        apart = np.full((2, len(d)), np.inf)
        apart[0, 2:], apart[1, :-2] = gap, gap
        return cls(pts[:-1], d, dd, apart)

    def to(self, curve: np.ndarray, i: np.ndarray) -> np.ndarray:
        """Squared distance of points (points × axes) from segments i (one a point, or candidates × points)."""
        pa = curve - self.a[i]
        d = self.d[i]
        t = np.clip(np.einsum("...j,...j->...", pa, d) / self.dd[i], 0.0, 1.0)
        r = pa - t[..., None] * d
        return np.einsum("...j,...j->...", r, r)

    def distance(self, curve: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each point's distance from the segments within two of its own (k) and the nearest of them (the
        first of equals in the order k − 2 … k + 2). The ones two away are measured only where they could be
        nearer: a point at D from its own segment is at least `apart` − D from them."""
        i = np.clip(k[None, :] + np.array((-1, 0, 1))[:, None], 0, len(self.a) - 1)
        q = self.to(curve[None, :, :], i)
        near = np.argmin(q, axis=0)
        cols = np.arange(len(k))
        dist, seg = np.sqrt(q[near, cols]), i[near, cols]
        far = np.flatnonzero(np.min(self.apart[:, k], axis=0) - np.sqrt(q[1]) <= dist)
        if len(far):
            i = np.clip(k[None, far] + np.array(_OFFSETS)[:, None], 0, len(self.a) - 1)
            q = self.to(curve[None, far, :], i)
            near = np.argmin(q, axis=0)
            cols = np.arange(len(far))
            dist[far], seg[far] = np.sqrt(q[near, cols]), i[near, cols]
        return dist, seg


def _segment_of(cu: np.ndarray, cum: np.ndarray) -> np.ndarray:
    return np.clip(np.searchsorted(cum, cu) - 1, 0, len(cum) - 2)


@dataclass
class _Check:
    """The distance of a fitted curve from the polyline where it can matter for the reweighting: on a grid of
    chord-length steps, exactly wherever it may exceed 0.9·tol, and finer (FINE points a step) in every step
    next to such a point where the nearest segment changes, where the distance peaks (decisions 51, 53)."""

    uu: np.ndarray
    segs: _Segs
    cum: np.ndarray
    tol: float
    k: np.ndarray  # each grid point's own segment
    own: tuple[np.ndarray, np.ndarray, np.ndarray]  # that segment's start and vector (axes × points), 1/|d|²

    @classmethod
    def of(cls, uu: np.ndarray, pts: np.ndarray, cum: np.ndarray, tol: float) -> "_Check":
        segs, k = _Segs.of(pts), _segment_of(uu, cum)
        own = (np.take(segs.a.T, k, axis=1), np.take(segs.d.T, k, axis=1), 1.0 / segs.dd[k])
        return cls(uu, segs, cum, tol, k, own)

    def distance(self, curve: np.ndarray, evaluate) -> np.ndarray:
        """`curve` on the grid (axes × points); `evaluate(u)` the curve at other chord lengths (points × axes)."""
        lim = 0.9 * self.tol
        a, d, inv = self.own  # each point against its own segment first: an upper bound of its distance
        pa = curve - a
        t = np.clip(np.einsum("ij,ij->j", pa, d) * inv, 0.0, 1.0)
        pa -= t * d
        dist = np.sqrt(np.einsum("ij,ij->j", pa, pa))
        seg = self.k.copy()
        over = dist > lim  # the others are within lim whatever their nearest segment: no weight changes there
        over[1:] |= over[:-1]
        over[:-1] |= over[1:]
        at = np.flatnonzero(over)
        if not len(at):
            return dist
        dist[at], seg[at] = self.segs.distance(curve[:, at].T, self.k[at])
        close = np.flatnonzero(dist > lim)
        if not len(close):
            return dist
        last = len(self.uu) - 2  # the last step
        side = np.zeros(last + 1, dtype=bool)
        side[np.maximum(close - 1, 0)] = True
        side[np.minimum(close, last)] = True
        steps = np.flatnonzero(side & ((seg[:-1] != seg[1:]) | (self.k[:-1] != self.k[1:])))
        fine = np.zeros(last + 1)
        if len(steps):
            frac = np.arange(1, FINE) / FINE
            h = np.diff(self.uu)[steps]
            uf = (self.uu[steps][:, None] + h[:, None] * frac[None, :]).ravel()
            cf = evaluate(uf)
            at = np.repeat(steps, FINE - 1)
            # the nearer of the step's ends' nearest segments bounds a fine point's distance; it counts
            # only above both of the step's ends (each close point's window holds them)
            df = np.sqrt(np.minimum(self.segs.to(cf, seg[at]), self.segs.to(cf, seg[at + 1])))
            look = np.flatnonzero(df > np.maximum(dist[at], dist[at + 1]))
            df[look] = self.segs.distance(cf[look], _segment_of(uf[look], self.cum))[0]
            fine[steps] = df.reshape(len(steps), FINE - 1).max(axis=1)
        lo, hi = np.maximum(close - 1, 0), np.minimum(close + 1, last + 1)
        around = np.maximum.reduce([dist[lo], dist[hi], fine[lo], fine[np.minimum(close, last)]])
        dist[close] = np.maximum(dist[close], around)
        return dist


def polyline_distance(curve: np.ndarray, cu: np.ndarray, pts: np.ndarray, cum: np.ndarray) -> np.ndarray:
    """Distance of each curve point (at chord parameter cu) from the polyline, over the segments within
    two of the one its parameter falls in."""
    return _Segs.of(pts).distance(curve, _segment_of(cu, cum))[0]


def fit_curve(pts: np.ndarray, lam: float = LAM, w: np.ndarray | None = None, degree: int = DEGREE) -> list[BSpline]:
    """Smoothing splines of the polyline's samples, one an axis, start and end pinned: quintic with the
    penalty ∫r'''², or cubic with ∫r''² (`degree` 3, scipy's make_smoothing_spline)."""
    u, p, _ = samples(pts)
    w = np.ones(len(u)) if w is None else w.copy()
    w[0] = w[-1] = 1e6
    if degree == 5:
        return quintic(u, p, w, lam)
    from scipy.interpolate import make_smoothing_spline

    return [make_smoothing_spline(u, p[:, k], w=w, lam=lam) for k in range(pts.shape[1])]


@dataclass
class _Band:
    """Σ_rows q·v vᵀ of rows v with `width` consecutive entries, as the upper band LAPACK's dpbsv takes:
    fixed indices, one np.bincount for new row weights q."""

    n: int
    width: int
    idx: np.ndarray  # rows × pairs: flat index into the (width × n) band
    prod: np.ndarray  # rows × pairs: v_a·v_b

    @classmethod
    def of(cls, first: np.ndarray, vals: np.ndarray, n: int) -> "_Band":
        width = vals.shape[1]
        ia, ib = _TRIU[width]
        idx = (width - 1 + ia - ib)[None, :] * n + first[:, None] + ib[None, :]
        return cls(n, width, idx, vals[:, ia] * vals[:, ib])

    def band(self, q: np.ndarray) -> np.ndarray:
        flat = np.bincount(self.idx.ravel(), (q[:, None] * self.prod).ravel(), minlength=self.width * self.n)
        return flat.reshape(self.width, self.n)


def _banded_rows(m: sps.csr_array, width: int) -> tuple[np.ndarray, np.ndarray]:
    """A B-spline design matrix's rows (each `width` consecutive columns, as scipy builds them):
    (first column, values) a row."""
    return m.indices[::width].astype(np.int64), m.data.reshape(-1, width)


def _penalty_rows(x: np.ndarray, t: np.ndarray, k: int, pen: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pen-th derivative's B-spline rows at 4 Gauss-Legendre points a knot interval (first column and
    k + 1 values a row) and the points' quadrature weights, ∫(f^(pen))² = Σ weight·(row·c)²: the
    derivative's coefficients as a band (row r from column r), then the degree k − pen B-splines' rows at
    the Gauss points times it (decision 51 built the same with scipy.sparse products)."""
    n = len(t) - k - 1
    gx, gw = _gl4()
    h = np.diff(x) / 2.0
    at = (x[:-1, None] + h[:, None] * (gx[None, :] + 1.0)).ravel()
    m = np.ones((n, 1))
    tt, kk = t, k
    for _ in range(pen):  # row r of the derivative map: kk/den_r·(c_{r+1} − c_r)
        nn = len(m)
        den = tt[kk + 1: kk + nn] - tt[1: nn]
        a = (kk / np.where(den > 0.0, den, np.inf))[:, None]
        nxt = np.zeros((nn - 1, m.shape[1] + 1))
        nxt[:, :-1] -= a * m[:-1]
        nxt[:, 1:] += a * m[1:]
        m, tt, kk = nxt, tt[1:-1], kk - 1
    from scipy.interpolate import BSpline

    first, d = _banded_rows(BSpline.design_matrix(at, tt, kk, extrapolate=True), kk + 1)
    vals = np.zeros((len(at), k + 1))
    for i in range(kk + 1):
        vals[:, i:i + pen + 1] += d[:, i:i + 1] * m[first + i]
    return first, vals, (h[:, None] * gw[None, :]).ravel()


@dataclass
class _Problem:
    """The penalised B-splines of degree k with knots at x (decision 51), all that depends on x alone:
    Σ w·(y − f)² + λ·∫(f^(pen))² least for any weights w, one banded Cholesky solve."""

    t: np.ndarray
    k: int
    design_t: sps.csc_array  # coefficients × samples
    fit: _Band  # the samples' part of the normal matrix
    pen: np.ndarray  # λ·∫(f^(pen))², banded

    @classmethod
    def of(cls, x: np.ndarray, lam: float, k: int = 5, pen: int = 3) -> "_Problem":
        t = np.concatenate([[x[0]] * k, x, [x[-1]] * k])
        n = len(t) - k - 1
        from scipy.interpolate import BSpline

        b = BSpline.design_matrix(x, t, k, extrapolate=True)
        first, vals, gq = _penalty_rows(x, t, k, pen)
        return cls(t, k, b.T, _Band.of(*_banded_rows(b, k + 1), n),
                   lam * _Band.of(first, vals, n).band(gq))

    def solve(self, y: np.ndarray, w: np.ndarray) -> np.ndarray:
        """The coefficients (coefficients × axes) for samples y (samples × axes) with weights w."""
        from scipy.linalg.lapack import dpbsv

        _, c, info = dpbsv(self.fit.band(w) + self.pen, self.design_t @ (w[:, None] * y), lower=0)
        if info:
            raise FitError(f"the fit's normal matrix is not positive definite ({info})")
        return c


def quintic(x: np.ndarray, y: np.ndarray, w: np.ndarray, lam: float, k: int = 5, pen: int = 3) -> list[BSpline]:
    """Penalised B-splines of degree k with knots at x: Σ w·(y − f)² + λ·∫(f^(pen))² least
    (y: samples × axes), one banded solve."""
    prob = _Problem.of(x, lam, k, pen)
    c = prob.solve(y, w)
    from scipy.interpolate import BSpline

    return [BSpline(prob.t, c[:, j], k) for j in range(y.shape[1])]


def fit_run(pts: np.ndarray, tol: float, lam: float = LAM, rounds: int = 60, step: float = 0.005,
            degree: int = DEGREE, cost: Cost | None = None) -> tuple[list[BSpline], np.ndarray]:
    """A fit within tol (checked every `step` mm of chord length, and FINE times finer within a step of
    where it comes within 0.9·tol), smoothed locally as much as it allows:
    the samples' weights grow (× (dev / 0.9·tol)³, never shrink) where the curve strays beyond 0.9·tol.
    Returns the splines and the vertices' chord lengths; `cost` gets the CPU time by part if given."""
    cost = cost or Cost()
    tc = cost.lap("", 0.0)
    pts = np.asarray(pts, dtype=float)
    if pts.ndim != 2 or len(pts) < 2 or not np.isfinite(pts).all():
        raise FitError(f"no fit of {len(pts)} points: two finite vertices or more")
    u, p, cum = samples(pts)
    if np.diff(cum).min() <= 1e-9:  # a vertex twice: no span between (its knots would coincide)
        raise FitError("no fit of a run with a segment of no length")
    w = np.ones(len(u))
    uu = np.append(np.arange(0.0, cum[-1], step), cum[-1])
    j = np.clip(np.searchsorted(u, uu), 0, len(u) - 1)
    starts = np.flatnonzero(np.diff(j, prepend=-1))  # j rises with uu: where each sample's points begin
    check = _Check.of(uu, pts, cum, tol)
    from scipy.interpolate import BSpline

    if degree == 5:
        prob = _Problem.of(u, lam)
        grid = BSpline.design_matrix(uu, prob.t, prob.k, extrapolate=True)  # no bounds check in Python
    tc = cost.lap("setup", tc)
    for _ in range(rounds):
        cost.rounds += 1
        w[0] = w[-1] = 1e6  # start and end pinned
        if degree == 5:
            c = prob.solve(p, w)
            tc = cost.lap("solve", tc)
            dist = check.distance((grid @ c).T, BSpline.construct_fast(prob.t, c, prob.k))
        else:
            spl = fit_curve(pts, lam, w, degree)
            dist = check.distance(np.stack([s(uu) for s in spl]),
                                  lambda uf: np.stack([s(uf) for s in spl], axis=1))
        tc = cost.lap("check", tc)
        if dist.max() <= tol:
            if degree == 5:
                spl = [BSpline(prob.t, c[:, a], prob.k) for a in range(p.shape[1])]
            return spl, cum
        dev = np.zeros(len(u))  # each sample: the largest distance next to it
        part = np.maximum.reduceat(dist, starts)  # the grid points of each sample's step, at once
        np.maximum.at(dev, j[starts], part)
        np.maximum.at(dev, np.maximum(j[starts] - 1, 0), part)
        # bounded: no overflow where tol cannot be met
        w = np.minimum(w * np.clip(dev / (0.9 * tol), 1.0, 10.0) ** 3, 1e9)
        tc = cost.lap("weights", tc)
    raise FitError(f"no fit within {tol} mm in {rounds} rounds (λ {lam:g})")
