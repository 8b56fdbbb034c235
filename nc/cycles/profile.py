"""A finishing contour seen as a function depth = c(feed) in a normalised roughing frame.

G71 and G72 remove stock in layers. Both are computed in one frame (f, d): the cut runs toward
decreasing f, layers step toward decreasing d, the stock lies at d above the contour. G71 maps
(Z, X) → (±Z, ±X), G72 swaps the axes first. In that frame a valid contour is monotone in f
(type II, pockets allowed) and, for type I, also monotone in d (decisions A45).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.geometry import EPS, Pt, Seg

TOL = 1e-7


@dataclass
class Frame:
    """Map between plane coordinates (first, second) and the roughing frame (f, d)."""

    swap: bool  # True for G72 (facing): feed along the second plane axis
    s_first: float  # +1 / -1
    s_second: float

    def to_fd(self, p: Pt) -> Pt:
        a, b = p[0] * self.s_first, p[1] * self.s_second
        return (b, a) if self.swap else (a, b)

    def from_fd(self, q: Pt) -> Pt:
        a, b = (q[1], q[0]) if self.swap else (q[0], q[1])
        return (a * self.s_first, b * self.s_second)

    @property
    def flips(self) -> bool:
        det = self.s_first * self.s_second * (-1.0 if self.swap else 1.0)
        return det < 0

    def seg_to_fd(self, s: Seg) -> Seg:
        return s.mapped(self.to_fd, self.flips)


class Contour:
    """The finishing contour in the (f, d) frame, checked to be a function of f."""

    def __init__(self, segs: list[Seg], type_one: bool) -> None:
        self.segs = [s for s in segs if s.length() > EPS]
        if not self.segs:
            raise NcAlarm(0x0246, "the P–Q contour has no movement")
        self.f_start = self.segs[0].p0[0]
        self.f_end = self.segs[-1].p1[0]
        samples = [_sample_ds(s) for s in self.segs]  # once: the type I check and the depth range read them
        self._check(type_one, samples)
        ds = [d for sd in samples for d in sd]
        for s in self.segs:
            if s.is_arc:
                ds.extend(p[1] for p in self._arc_extremes(s))
        self.d_min = min(ds)
        self.d_max = max(ds)
        # an arc's start angle, sweep and radius, found once (crossings and depths ask them per layer)
        self._arcs = {id(s): (math.atan2(s.p0[1] - s.center[1], s.p0[0] - s.center[0]), s.sweep(), s.radius)
                      for s in self.segs if s.center is not None}
        # (f low, f high, element) of the elements not vertical in f, for `depth_at`
        self._spans = [(lo, hi, s) for s in self.segs
                       for lo, hi in [(min(s.p0[0], s.p1[0]), max(s.p0[0], s.p1[0]))] if hi - lo >= TOL]

    def _check(self, type_one: bool, samples: list[list[float]]) -> None:
        # Monotone along the cutting axis is judged on block end points. An arc may bulge past its end
        # point (the manual's own G72 example 1, E-L23: the R10 arc dips 0.08 mm under X20.): the
        # layers stop at the highest element over each f (`depth_at`), leaving the shadow under the
        # bulge to the profile pass / G70 (decisions A45).
        if self.f_end > self.f_start - TOL:
            raise NcAlarm(0x0246, "the P–Q contour does not advance in the cutting direction")
        last_d = self.segs[0].p0[1]
        for s, ds in zip(self.segs, samples):
            if s.p1[0] > s.p0[0] + TOL:
                raise NcAlarm(0x0246, "the P–Q contour turns back against the cutting direction "
                                      "(it must be monotone along the cutting axis)")
            if type_one:
                if any(b < a - TOL for a, b in zip([last_d] + ds, ds)):
                    raise NcAlarm(0x0246, "type I roughing needs a monotone contour; program X and Z in the "
                                          "P block for a type II (pocket) contour")
                last_d = ds[-1]

    @staticmethod
    def _arc_extremes(s: Seg) -> list[Pt]:
        c, r = s.center, s.radius
        assert c is not None
        return [(c[0] + r * math.cos(a), c[1] + r * math.sin(a)) for a in (math.pi / 2, -math.pi / 2)
                if s.contains_angle(a)]

    def depth_at(self, f: float) -> float:
        """c(f) on the non-vertical element spanning f (max over touching elements)."""
        best: float | None = None
        for lo, hi, s in self._spans:
            if not (lo - TOL <= f <= hi + TOL):
                continue
            if s.center is None:
                t = (f - s.p0[0]) / (s.p1[0] - s.p0[0])
                d = s.p0[1] + t * (s.p1[1] - s.p0[1])
            else:
                d = self._arc_depth(s, f)
            best = d if best is None else max(best, d)
        if best is None:
            raise NcAlarm(0x0246, f"the P–Q contour does not cover the cutting position {f:g}")
        return best

    def _contains(self, s: Seg, ang: float) -> bool:
        """`s.contains_angle(ang)` with the arc's start angle and sweep found once."""
        a0, sw, _ = self._arcs[id(s)]
        if sw >= 0:
            return 1e-9 < (ang - a0) % (2 * math.pi) < sw - 1e-9
        return 1e-9 < (a0 - ang) % (2 * math.pi) < -sw - 1e-9

    def _arc_depth(self, s: Seg, f: float) -> float:
        """Highest point of the arc over f: an arc that bulges past its end point along f covers
        that f twice, on both sides of its centre."""
        c, r = s.center, self._arcs[id(s)][2]
        assert c is not None
        h = math.sqrt(max(r * r - (f - c[0]) ** 2, 0.0))
        on_arc = [c[1] + sign * h for sign in (1.0, -1.0)
                  if self._contains(s, math.atan2(sign * h, f - c[0]))]
        ends = [p[1] for p in (s.p0, s.p1) if abs(p[0] - f) < 1e-9]
        if on_arc or ends:
            return max(on_arc + ends)
        mid = s.point(0.5)  # f at the very edge of the arc's span
        return c[1] + (h if mid[1] >= c[1] else -h)

    def crossings(self, level: float) -> list[float]:
        out: list[float] = []
        for s in self.segs:
            if not s.is_arc:
                d0, d1 = s.p0[1], s.p1[1]
                if abs(d1 - d0) < 1e-15:
                    continue
                t = (level - d0) / (d1 - d0)
                if -1e-12 <= t <= 1 + 1e-12:
                    out.append(s.p0[0] + t * (s.p1[0] - s.p0[0]))
            else:
                c, r = s.center, self._arcs[id(s)][2]
                assert c is not None
                sn = (level - c[1]) / r
                if abs(sn) > 1:
                    continue
                for a in (math.asin(sn), math.pi - math.asin(sn)):
                    p = (c[0] + r * math.cos(a), c[1] + r * math.sin(a))
                    if self._contains(s, a) or min(math.dist(p, s.p0), math.dist(p, s.p1)) < 1e-9:
                        out.append(p[0])
        return out

    def intervals(self, level: float, tol: float = 1e-7) -> list[tuple[float, float]]:
        """Spans (f_hi, f_lo) of f, in cutting order, where the contour lies below `level`."""
        cuts = sorted({self.f_start, self.f_end, *[f for f in self.crossings(level)
                                                    if self.f_end - TOL <= f <= self.f_start + TOL]},
                      reverse=True)
        spans: list[tuple[float, float]] = []
        for hi, lo in zip(cuts, cuts[1:]):
            if hi - lo < 1e-6:
                continue
            if self.depth_at((hi + lo) / 2) < level + tol:
                if spans and abs(spans[-1][1] - hi) < 1e-9:
                    spans[-1] = (spans[-1][0], lo)
                else:
                    spans.append((hi, lo))
        return spans


def _sample_ds(s: Seg) -> list[float]:
    """The second coordinates of `s.samples(8)`. A line's come from its two ends alone when they do not
    fall: p0 + (p1 - p0)·t with correctly rounded - and · never decreases in t then, so the samples
    between add no extreme and no drop (issue 16: the roughing cycles sampled every line)."""
    if s.center is None:
        y0 = s.p0[1]
        dy = s.p1[1] - y0
        if dy >= 0:
            return [y0 + dy * 0.0, y0 + dy * 1.0]
    return [p[1] for p in s.samples(8)]


def segs_from_moves(moves: list, plane: tuple[str, str]) -> list[Seg]:
    """Moves of a P–Q contour → plane elements (rapid ones marked)."""
    out: list[Seg] = []
    a1, a2 = plane
    for m in moves:
        if m.kind not in ("rapid", "line", "arc"):
            continue
        p0 = (m.start[a1], m.start[a2])
        p1 = (m.end[a1], m.end[a2])
        if m.kind == "arc" and m.center is not None:
            out.append(Seg(p0, p1, (m.center[a1], m.center[a2]), m.dir == "cw", False, m))
        else:
            out.append(Seg(p0, p1, None, False, m.kind == "rapid", m))
    return out


def shifted(segs: list[Seg], dx: float, dy: float) -> list[Seg]:
    def fn(p: Pt) -> Pt:
        return (p[0] + dx, p[1] + dy)
    return [s.mapped(fn, False) for s in segs]


MapFn = Callable[[Pt], Pt]
