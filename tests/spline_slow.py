"""The spline fit and its spans as decision motion 51 left them (one sparse solve a round, every point of the
check's finer look, spans cut one by one with Newton steps on each): the slow reference that
tests/test_spline_runs.py pins the fast path of nc.motion.spline_fit / spline_runs against (decision 53)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from scipy.interpolate import BSpline, PPoly
from scipy.sparse.linalg import spsolve

from nc.motion.spline_fit import LAM, samples

NODES, CHEB = 9, 9
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)


def distance(curve, cu, pts, cum):
    k = np.clip(np.searchsorted(cum, cu) - 1, 0, len(pts) - 2)
    best = np.full(len(curve), np.inf)
    for off in (-2, -1, 0, 1, 2):
        i = np.clip(k + off, 0, len(pts) - 2)
        a, d = pts[i], pts[i + 1] - pts[i]
        t = np.clip(np.einsum("ij,ij->i", curve - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-30), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(curve - (a + t[:, None] * d), axis=1))
    return best


def penalty_parts(x, k=5, pen=3):
    """Knots t (at x, ends k + 1 fold), the samples' B-spline rows, the pen-th derivative's rows at 4
    Gauss-Legendre points a knot interval and those points' quadrature weights: ∫(f^(pen))² = cᵀ·dkᵀ·Q·dk·c."""
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
    dk = sps.csr_array(BSpline.design_matrix(at, tt, kk) @ m)
    return t, BSpline.design_matrix(x, t, k), dk, (h[:, None] * gw[None, :]).ravel()


def quintic(x, y, w, lam, k=5, pen=3):
    t, b, dk, gq = penalty_parts(x, k, pen)
    a = (b.T @ sps.diags(w) @ b + lam * (dk.T @ sps.diags(gq) @ dk)).tocsc()
    c = spsolve(a, b.T @ (w[:, None] * y))
    return [BSpline(t, c[:, j], k) for j in range(y.shape[1])]


def fit_run(pts, tol, lam=LAM, rounds=60, step=0.005):
    """Returns (splines, vertices' chord lengths, rounds taken)."""
    u, p, cum = samples(pts)
    w = np.ones(len(u))
    uu = np.append(np.arange(0.0, cum[-1], step), cum[-1])
    j = np.clip(np.searchsorted(u, uu), 0, len(u) - 1)
    for n in range(1, rounds + 1):
        ww = w.copy()
        ww[0] = ww[-1] = 1e6
        spl = quintic(u, p, ww, lam)
        dist = distance(np.stack([s(uu) for s in spl], axis=1), uu, pts, cum)
        near = np.flatnonzero(dist > 0.9 * tol)
        if len(near):
            uf = np.clip((uu[near][:, None] + np.linspace(-step, step, 41)[None, :]).ravel(), 0.0, cum[-1])
            df = distance(np.stack([s(uf) for s in spl], axis=1), uf, pts, cum)
            dist[near] = np.maximum(dist[near], df.reshape(len(near), 41).max(axis=1))
        if dist.max() <= tol:
            return spl, cum, n
        dev = np.zeros(len(u))
        np.maximum.at(dev, j, dist)
        np.maximum.at(dev, np.maximum(j - 1, 0), dist)
        w = np.minimum(w * np.clip(dev / (0.9 * tol), 1.0, 10.0) ** 3, 1e9)
    raise RuntimeError("no fit")


class Span:
    """One span, cut alone: its pieces in w, its arc-length table, points and derivatives by Newton steps."""

    def __init__(self, coef, brk):
        self.coef, self.brk = coef, brk
        piece = np.repeat(np.arange(len(coef)), NODES - 1)
        hw = np.repeat(np.diff(brk) / (NODES - 1), NODES - 1)
        w0 = np.tile(np.arange(NODES - 1), len(coef)) * hw
        seg_s = self._arc(piece, w0, w0 + hw).reshape(len(coef), NODES - 1)
        tab = np.concatenate([np.zeros((len(coef), 1)), np.cumsum(seg_s, axis=1)], axis=1)
        off = np.concatenate([[0.0], np.cumsum(tab[:, -1])[:-1]])
        self.s_tab = tab + off[:, None]
        self.length = float(off[-1] + tab[-1, -1])

    def _derivs(self, piece, w):
        c, w, k = self.coef[piece], w[:, None], self.coef.shape[1] - 1
        out = []
        for d in range(4):
            acc = np.zeros((len(c), c.shape[2]))
            for i in range(k - d + 1):
                f = float(np.prod(np.arange(k - i - d + 1, k - i + 1))) if d else 1.0
                acc = acc * w + f * c[:, i]
            out.append(acc)
        return out

    def _arc(self, piece, w0, w1):
        h = 0.5 * (w1 - w0)
        out = np.zeros(len(piece))
        for x, g in zip(_GL_X, _GL_W):
            out += g * np.linalg.norm(self._derivs(piece, w0 + h * (x + 1.0))[1], axis=1)
        return out * h

    def derivatives(self, s):
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        flat = self.s_tab.ravel()
        k = np.clip(np.searchsorted(flat, s, side="right") - 1, 0, len(flat) - 2)
        piece = np.minimum(k // NODES, len(self.coef) - 1)
        width = np.diff(self.brk)[piece]
        w0 = (k - piece * NODES) * width / (NODES - 1)
        s0 = self.s_tab[piece, k - piece * NODES]
        w = w0 + (s - s0) / np.maximum(np.linalg.norm(self._derivs(piece, w0)[1], axis=1), 1e-12)
        for _ in range(3):
            w = np.clip(w, 0.0, width)
            w = w - (s0 + self._arc(piece, w0, w) - s) / np.linalg.norm(self._derivs(piece, w)[1], axis=1)
        r, d1, d2, d3 = self._derivs(piece, np.clip(w, 0.0, width))
        sig2 = np.einsum("ij,ij->i", d1, d1)[:, None]
        sig = np.sqrt(sig2)
        q = np.einsum("ij,ij->i", d1, d2)[:, None]
        qd = np.einsum("ij,ij->i", d2, d2)[:, None] + np.einsum("ij,ij->i", d1, d3)[:, None]
        rss = d2 / sig2 - q * d1 / sig2 ** 2
        rsss = (d3 / sig2 - 3.0 * q * d2 / sig2 ** 2 - qd * d1 / sig2 ** 2 + 4.0 * q * q * d1 / sig2 ** 3) / sig
        return r, d1 / sig, rss, rsss

    def bounds(self, margin=1.01):
        _, rs, rss, rsss = self.derivatives(np.linspace(0.0, self.length, 33 * len(self.coef)))
        return (np.minimum(np.abs(rs).max(axis=0) * margin, 1.0), np.abs(rss).max(axis=0) * margin,
                np.abs(rsss).max(axis=0) * margin)

    def s_poly(self):
        sa, sb = self.s_tab[:, 0], self.s_tab[:, -1]
        x = np.cos(np.pi * (np.arange(CHEB + 1) + 0.5) / (CHEB + 1))
        s = (0.5 * (sa[:, None] + sb[:, None]) + 0.5 * (sb - sa)[:, None] * x[None, :]).ravel()
        r = self.derivatives(s)[0].reshape(len(sa), CHEB + 1, -1)
        return np.stack([np.linalg.solve(np.vander(x, CHEB + 1), r[i]) for i in range(len(sa))])


def spans(spl, cum):
    pp = [PPoly.from_spline(s) for s in spl]
    keep = np.diff(pp[0].x) > 0.0
    starts = pp[0].x[:-1][keep]
    coef = np.stack([p.c[:, keep] for p in pp], axis=-1).transpose(1, 0, 2)
    first = np.searchsorted(starts, cum[:-1] - 1e-9 * max(cum[-1], 1.0))
    out = []
    for i in range(len(cum) - 1):
        lo, hi = first[i], first[i + 1] if i + 1 < len(first) else len(starts)
        out.append(Span(coef[lo:hi], np.append(starts[lo:hi], cum[i + 1]) - starts[lo]))
    return out
