"""Cutter / nose-centre offset geometry: one element's offset, the corner between two offset
elements (intersection at inner corners, arc insertion at outer corners) and interference checks.

`side` is +1 for G41 (tool left of the direction of travel), −1 for G42, in the plane frame
(first, second) of `Move.plane`. Alarms are the NC5 0x12xx interpolation codes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.geometry import Pt, Seg, circle_circle, cross, dist, dot, line_circle, unit

ANG_EPS = 1e-9


def left_normal(t: Pt) -> Pt:
    return (-t[1], t[0])


def offset_point(p: Pt, t: Pt, side: float, r: float) -> Pt:
    n = left_normal(t)
    return (p[0] + side * r * n[0], p[1] + side * r * n[1])


def offset_radius(s: Seg, side: float, r: float) -> float:
    """Radius of the offset arc: the tool is inside a CCW arc under G41."""
    inside = (not s.cw) if side > 0 else s.cw
    return s.radius - r if inside else s.radius + r


def _pair_code(a: Seg, b: Seg, interference: bool) -> int:
    if not a.is_arc and not b.is_arc:
        return 0x120B
    if a.is_arc and not b.is_arc:
        return 0x1205 if interference else 0x1204
    if not a.is_arc and b.is_arc:
        return 0x1208 if interference else 0x1209
    return 0x1207


@dataclass
class OffsetSeg:
    """An element of the offset (tool-centre) path."""

    seg: Seg  # geometry of the offset element (arc centre unchanged)
    prog: Seg  # the programmed element it belongs to
    corner: bool = False  # an arc inserted at an outer corner


def offset_seg(s: Seg, side: float, r: float) -> Seg:
    """The whole element offset by r (its start and end normal to itself)."""
    p0 = offset_point(s.p0, s.tangent(0.0), side, r)
    p1 = offset_point(s.p1, s.tangent(1.0), side, r)
    if s.is_arc and offset_radius(s, side, r) <= 1e-9:
        raise NcAlarm(0x120A, f"arc radius {s.radius:g} is smaller than the compensation radius {r:g}")
    return Seg(p0, p1, s.center, s.cw, s.rapid, s.src)  # not dataclasses.replace: its field look per call


def _intersections(a: Seg, b: Seg) -> list[Pt]:
    """Intersections of the carriers (infinite line / full circle) of two offset elements."""
    if not a.is_arc and not b.is_arc:
        da = (a.p1[0] - a.p0[0], a.p1[1] - a.p0[1])
        db = (b.p1[0] - b.p0[0], b.p1[1] - b.p0[1])
        den = cross(da, db)
        if abs(den) < 1e-14:
            return []
        t = cross((b.p0[0] - a.p0[0], b.p0[1] - a.p0[1]), db) / den
        return [(a.p0[0] + t * da[0], a.p0[1] + t * da[1])]
    if a.is_arc and b.is_arc:
        return circle_circle(a.center, dist(a.p0, a.center), b.center, dist(b.p0, b.center))
    ln, ar = (a, b) if not a.is_arc else (b, a)
    d = (ln.p1[0] - ln.p0[0], ln.p1[1] - ln.p0[1])
    ts = line_circle(ln.p0, d, ar.center, dist(ar.p0, ar.center))
    return [(ln.p0[0] + t * d[0], ln.p0[1] + t * d[1]) for t in ts]


def _progress(s: Seg, p: Pt) -> float:
    """How far along the element's carrier p lies, from p0, in the element's own direction
    (line: signed length; arc: angle in the travel direction in [0, 2π))."""
    if not s.is_arc:
        t = unit((s.p1[0] - s.p0[0], s.p1[1] - s.p0[1]))
        return dot((p[0] - s.p0[0], p[1] - s.p0[1]), t)
    c = s.center
    a0 = math.atan2(s.p0[1] - c[1], s.p0[0] - c[0])
    a = math.atan2(p[1] - c[1], p[0] - c[0])
    return ((a - a0) if not s.cw else (a0 - a)) % (2 * math.pi)


def _extent(s: Seg) -> float:
    if not s.is_arc:
        return dist(s.p0, s.p1)
    sw = abs(s.sweep())
    return sw if sw < 2 * math.pi - 1e-12 else 2 * math.pi


def corner(prev: Seg, nxt: Seg, prev_off: Seg, next_off: Seg, side: float, r: float) -> tuple[Pt, Pt, Seg | None]:
    """Join two offset elements at the programmed corner prev.p1 == nxt.p0.

    Returns (end of prev_off, start of next_off, inserted corner arc or None).
    """
    t0 = prev.tangent(1.0)
    t1 = nxt.tangent(0.0)
    a, b = prev_off.p1, next_off.p0
    if dist(a, b) < 1e-9:
        return a, b, None
    turn = cross(t0, t1)
    inner = (turn * side > 1e-12)
    if not inner:
        # outer corner (or a reversal): an arc of radius r around the programmed corner
        arc = Seg(a, b, prev.p1, side > 0, False, prev.src)
        return a, b, arc
    pts = _intersections(prev_off, next_off)
    if not pts:
        raise NcAlarm(_pair_code(prev, nxt, False), "no intersection of the compensated paths at an inner corner")
    p = min(pts, key=lambda q: dist(q, prev.p1))
    # interference: the trimmed elements must keep their direction of travel
    if _progress(prev_off, p) > _extent(prev_off) + 1e-7 or (not prev_off.is_arc and _progress(prev_off, p) < -1e-7):
        raise NcAlarm(_pair_code(prev, nxt, True), "compensation interference: the inner corner cuts past the "
                                                    "previous block (element shorter than the tool radius)")
    if not next_off.is_arc and _progress(next_off, p) > _extent(next_off) + 1e-7:
        raise NcAlarm(_pair_code(prev, nxt, True), "compensation interference: the inner corner cuts past the "
                                                    "next block (element shorter than the tool radius)")
    if next_off.is_arc and _extent(next_off) - _progress(next_off, p) < -1e-7:
        raise NcAlarm(_pair_code(prev, nxt, True), "compensation interference at an inner corner")
    return p, p, None


def check_trimmed(prog: Seg, start: Pt, end: Pt, off: Seg) -> None:
    """After both corners: the compensated element must still run the programmed way."""
    if not prog.is_arc:
        t = prog.tangent(0.0)
        if dot((end[0] - start[0], end[1] - start[1]), t) < -1e-7:
            raise NcAlarm(0x120B, "compensation interference: the compensated block runs backwards "
                                  "(block shorter than the tool radius)")
        return
    trimmed = Seg(start, end, off.center, off.cw, off.rapid, off.src)
    if dist(start, end) > 1e-9 and abs(trimmed.sweep()) > abs(off.sweep()) + 1e-6 and abs(off.sweep()) < 2 * math.pi - 1e-9:
        raise NcAlarm(0x1207, "compensation interference: the compensated arc runs backwards")
