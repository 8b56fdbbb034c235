"""Plane geometry for cycles and compensation: line and arc elements in a 2-D plane.

Coordinates are (first, second) axes of the plane as in `Move.plane` — (Z, X radius) on a lathe,
(X, Y) on a mill under G17 — a right-handed frame, so CCW is positive rotation (``cw=False``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

EPS = 1e-9
Pt = tuple[float, float]


@dataclass(frozen=True, init=False)  # its own __init__ below (no generated one compiled at start-up)
class Seg:
    """A straight line (``center is None``) or a circular arc from p0 to p1."""

    p0: Pt
    p1: Pt
    center: Pt | None = None
    cw: bool = False
    rapid: bool = False
    src: object = None  # the Move this element came from (feed, line, block, comp)

    def __init__(self, p0: Pt, p1: Pt, center: Pt | None = None, cw: bool = False, rapid: bool = False,
                 src: object = None) -> None:
        # the fields written straight into the instance dict: the frozen dataclass's own __init__ goes
        # through object.__setattr__ per field, a third of the cost of every element (issue 16: cycles and
        # compensation make thousands); assignment afterwards still raises FrozenInstanceError
        d = self.__dict__
        d["p0"], d["p1"], d["center"], d["cw"], d["rapid"], d["src"] = p0, p1, center, cw, rapid, src
        d["is_arc"] = center is not None  # not a field: read often, kept beside them (not a property)

    is_arc: ClassVar[bool]  # set per instance by __init__: the element is an arc (it has a centre)

    @property
    def radius(self) -> float:
        assert self.center is not None
        return math.hypot(self.p0[0] - self.center[0], self.p0[1] - self.center[1])

    def sweep(self) -> float:
        """Signed swept angle (rad), CCW positive; a closed arc is a full circle."""
        c = self.center
        assert c is not None
        a0 = math.atan2(self.p0[1] - c[1], self.p0[0] - c[0])
        a1 = math.atan2(self.p1[1] - c[1], self.p1[0] - c[0])
        ccw = (a1 - a0) % (2 * math.pi)
        if dist(self.p0, self.p1) < 1e-9:
            ccw = 0.0
        if self.cw:
            return ccw - 2 * math.pi if ccw > 1e-12 else -2 * math.pi
        return ccw if ccw > 1e-12 else 2 * math.pi

    def length(self) -> float:
        if not self.is_arc:
            return dist(self.p0, self.p1)
        return abs(self.sweep()) * self.radius

    def point(self, t: float) -> Pt:
        """Point at parameter t in [0, 1] along the element."""
        if not self.is_arc:
            return (self.p0[0] + (self.p1[0] - self.p0[0]) * t, self.p0[1] + (self.p1[1] - self.p0[1]) * t)
        c = self.center
        assert c is not None
        a0 = math.atan2(self.p0[1] - c[1], self.p0[0] - c[0])
        a = a0 + self.sweep() * t
        r = self.radius
        return (c[0] + r * math.cos(a), c[1] + r * math.sin(a))

    def tangent(self, t: float) -> Pt:
        """Unit direction of travel at parameter t. A line's is found once and kept beside the fields
        (compensation asks each element several times, issue 16; the fields never change)."""
        if not self.is_arc:
            d = self.__dict__
            u = d.get("_direction")
            if u is None:
                u = d["_direction"] = unit((self.p1[0] - self.p0[0], self.p1[1] - self.p0[1]))
            return u
        p = self.point(t)
        c = self.center
        assert c is not None
        rx, ry = p[0] - c[0], p[1] - c[1]
        d = unit((-ry, rx))  # CCW tangent
        return (-d[0], -d[1]) if self.cw else d

    def samples(self, n: int = 16) -> list[Pt]:
        """`point(i / n)` for i = 0 … n, the arc's start angle and sweep computed once (the same
        expressions as `point`, so the same values)."""
        c = self.center
        if c is None:
            (x0, y0), (x1, y1) = self.p0, self.p1
            dx, dy = x1 - x0, y1 - y0
            return [(x0 + dx * t, y0 + dy * t) for t in [i / n for i in range(n + 1)]]
        a0 = math.atan2(self.p0[1] - c[1], self.p0[0] - c[0])
        sw = self.sweep()
        r = self.radius
        return [(c[0] + r * math.cos(a), c[1] + r * math.sin(a)) for a in [a0 + sw * (i / n) for i in range(n + 1)]]

    def reversed(self) -> "Seg":
        return Seg(self.p1, self.p0, self.center, not self.cw if self.is_arc else self.cw, self.rapid, self.src)

    def mapped(self, fn, flips: bool) -> "Seg":
        """Image under a point map; ``flips`` says the map reverses orientation (a reflection).
        Built directly: dataclasses.replace looks at the fields on every call (issue 16)."""
        c = self.center
        return Seg(fn(self.p0), fn(self.p1), fn(c) if c else None, (not self.cw) if (flips and c is not None) else self.cw,
                   self.rapid, self.src)

    def contains_angle(self, ang: float) -> bool:
        """Does the arc sweep pass the polar angle `ang` (strictly inside)?"""
        c = self.center
        assert c is not None
        a0 = math.atan2(self.p0[1] - c[1], self.p0[0] - c[0])
        sw = self.sweep()
        rel = (ang - a0) % (2 * math.pi)
        if sw >= 0:
            return 1e-9 < rel < sw - 1e-9
        rel = (a0 - ang) % (2 * math.pi)
        return 1e-9 < rel < -sw - 1e-9


def dist(a: Pt, b: Pt) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


def unit(v: Pt) -> Pt:
    n = math.hypot(v[0], v[1])
    if n < 1e-15:
        return (0.0, 0.0)
    return (v[0] / n, v[1] / n)


def cross(a: Pt, b: Pt) -> float:
    return a[0] * b[1] - a[1] * b[0]


def dot(a: Pt, b: Pt) -> float:
    return a[0] * b[0] + a[1] * b[1]


def point_seg_distance(p: Pt, s: Seg) -> float:
    """Shortest distance from p to the element (exact for lines and arcs)."""
    if not s.is_arc:
        ax, ay = s.p0
        bx, by = s.p1
        vx, vy = bx - ax, by - ay
        L2 = vx * vx + vy * vy
        if L2 < 1e-24:
            return dist(p, s.p0)
        t = max(0.0, min(1.0, ((p[0] - ax) * vx + (p[1] - ay) * vy) / L2))
        return math.hypot(p[0] - ax - t * vx, p[1] - ay - t * vy)
    c = s.center
    assert c is not None
    ang = math.atan2(p[1] - c[1], p[0] - c[0])
    if s.contains_angle(ang) or dist(p, c) < 1e-12:
        return abs(dist(p, c) - s.radius)
    return min(dist(p, s.p0), dist(p, s.p1))


def line_circle(p: Pt, d: Pt, c: Pt, r: float) -> list[float]:
    """Parameters t where p + t·d meets the circle (d need not be unit)."""
    fx, fy = p[0] - c[0], p[1] - c[1]
    a = d[0] * d[0] + d[1] * d[1]
    b = 2 * (fx * d[0] + fy * d[1])
    cc = fx * fx + fy * fy - r * r
    disc = b * b - 4 * a * cc
    if a < 1e-24:
        return []
    if disc < -1e-12:
        return []
    disc = max(disc, 0.0)
    sq = math.sqrt(disc)
    return sorted({(-b - sq) / (2 * a), (-b + sq) / (2 * a)})


def circle_circle(c0: Pt, r0: float, c1: Pt, r1: float) -> list[Pt]:
    d = dist(c0, c1)
    if d < 1e-12 or d > r0 + r1 + 1e-9 or d < abs(r0 - r1) - 1e-9:
        return []
    a = (r0 * r0 - r1 * r1 + d * d) / (2 * d)
    h = math.sqrt(max(r0 * r0 - a * a, 0.0))
    ux, uy = (c1[0] - c0[0]) / d, (c1[1] - c0[1]) / d
    mx, my = c0[0] + a * ux, c0[1] + a * uy
    if h < 1e-12:
        return [(mx, my)]
    return [(mx - h * uy, my + h * ux), (mx + h * uy, my - h * ux)]
