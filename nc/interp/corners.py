"""`,C` chamfer and `,R` corner rounding between two motion blocks (N§3.3.2, L l.2388; decisions A32).

A block carrying ``,C`` or ``,R`` is held back until the next motion block is known; both lines are
trimmed and a chamfer line or a tangent arc is inserted.  ``,C`` is the leg length measured from
the virtual corner along each line; next to an arc (the lathe manual allows G01–G03) it is the
straight distance from the corner to the chamfer point on the arc.  ``,R`` next to an arc is the
circle tangent to both elements on the inside of the corner whose tangent points lie nearest the
corner.  A helical arc (a third axis moving) cannot be trimmed: 0x021D.
"""

from __future__ import annotations

import math
from itertools import chain
from collections.abc import Iterator
from typing import TYPE_CHECKING

from nc.alarms import NcAlarm
from nc.moves import Busy, Event, Move, MoveBatch, MoveList, ProgramEnd

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.host import InterpHost


_JOINABLE = ("line", "arc", "rapid", "thread")  # moves a ,C/,R joins, or that carry one


def expand_corners(interp: "InterpHost", events: Iterator[Event]) -> Iterator[Event]:
    pending: tuple[Move, str, float] | None = None
    held: list[Event] = []  # M/S/T or dwell events of the next block, issued after the corner
    events = iter(events)
    while True:
        if pending is None:
            # no corner waits (the usual state): every event passes as it is but a joinable move whose
            # block carries ,C/,R, which then waits (hot path: a for loop, a block without ,C/,R said
            # without a call, `corner_pending` said once)
            interp.corner_pending = False
            for ev in events:
                if ev is None:
                    break
                b = interp.block
                if b is not None and b.comma and isinstance(ev, Move) and ev.kind in _JOINABLE \
                        and (mark := _mark(interp, ev)) is not None:
                    pending = (ev, mark[0], mark[1])
                    break
                yield ev
            if pending is None:
                break  # the stream ended
            continue
        # while a corner waits for its motion block the interpreter reads block by block (no bulk run
        # reads past the block that joins it, or past its alarm): said before the next event is read
        interp.corner_pending = True
        ev = next(events, None)
        if ev is None:
            break
        if type(ev) is MoveList:  # a cycle's moves: one by one while a corner waits
            events = chain(ev.moves(), events)
            continue
        if type(ev) is MoveBatch:  # plain moves (no ,C/,R): the first joins the corner
            yield from _corners_of(interp, ev.moves(), pending, held)
            pending, held = None, []
            continue
        if isinstance(ev, Move) and ev.kind in _JOINABLE:
            b = interp.block
            mark = None if b is None or not b.comma else _mark(interp, ev)
            first, kind, value = pending
            pending = None
            yield from _join(interp, first, ev, kind, value)
            yield from held
            held = []
            if mark is not None:
                pending = (ev, mark[0], mark[1])
                continue
            yield ev
            continue
        if not isinstance(ev, Busy):  # a Busy mark passes at once
            if isinstance(ev, ProgramEnd):
                _fail(pending)
            held.append(ev)
            continue
        yield ev
    if pending is not None:
        _fail(pending)


def _corners_of(interp: "InterpHost", moves: list[Move], pending: tuple[Move, str, float],
                held: list[Event]) -> Iterator[Event]:
    """A batch's moves after a held ,C/,R block: the first is joined to it (`_join` trims it), then
    they pass as the block-by-block path passes them."""
    first, kind, value = pending
    yield from _join(interp, first, moves[0], kind, value)
    yield from held
    yield from moves


def _fail(pending: tuple[Move, str, float]) -> None:
    first = pending[0]
    raise NcAlarm(0x0207, f",{pending[1]} must be followed by a motion block", line=first.line,
                  block=first.block, program=first.program)


def _mark(interp: "InterpHost", mv: Move) -> tuple[str, float] | None:
    """The ,C / ,R request of the block that produced this move (only its last move carries it)."""
    b = interp.block
    if b is None or not b.comma or b.line != mv.line or b.text != mv.block or "G31" in mv.tags:
        return None
    if "C" in b.comma:
        return "C", b.comma["C"] * (25.4 if interp.state.inch else 1.0)
    if "R" in b.comma:
        return "R", b.comma["R"] * (25.4 if interp.state.inch else 1.0)
    return None


def _unit(a: tuple[float, float], b: tuple[float, float]) -> tuple[tuple[float, float], float]:
    dx, dy = b[0] - a[0], b[1] - a[1]
    d = math.hypot(dx, dy)
    if d < 1e-12:
        raise NcAlarm(0x0207, "chamfer/corner next to a zero-length move")
    return (dx / d, dy / d), d


def _join(interp: "InterpHost", m1: Move, m2: Move, kind: str, value: float) -> list[Move]:
    if m1.kind not in ("line", "rapid", "arc") or m2.kind not in ("line", "rapid", "arc"):
        raise NcAlarm(0x021D, f",{kind} is supported between lines and arcs (G00–G03)", line=m1.line,
                      block=m1.block, program=m1.program)
    if m1.kind == "arc" or m2.kind == "arc":
        return _join_curved(interp, m1, m2, kind, value)
    a1, a2 = m1.plane
    p0 = (m1.start[a1], m1.start[a2])
    pc = (m1.end[a1], m1.end[a2])
    p2 = (m2.end[a1], m2.end[a2])
    d1, l1 = _unit(p0, pc)
    d2, l2 = _unit(pc, p2)
    cross = d1[0] * d2[1] - d1[1] * d2[0]
    dot = max(-1.0, min(1.0, d1[0] * d2[0] + d1[1] * d2[1]))
    if abs(cross) < 1e-12:
        raise NcAlarm(0x0207, f",{kind} between two parallel moves", line=m1.line, block=m1.block, program=m1.program)
    if kind == "C":
        t = value
    else:
        phi = math.acos(dot)  # turning angle
        t = value * math.tan(phi / 2.0)
    if t > l1 + 1e-9 or t > l2 + 1e-9:
        raise NcAlarm(0x0207, f",{kind}{value:g} is longer than an adjacent move", line=m1.line, block=m1.block,
                      program=m1.program)
    pa = (pc[0] - d1[0] * t, pc[1] - d1[1] * t)
    pb = (pc[0] + d2[0] * t, pc[1] + d2[1] * t)

    def at(m: Move, pt: tuple[float, float]) -> dict[str, float]:
        d = dict(m.end)
        d[a1], d[a2] = pt
        return d

    end1 = at(m1, pa)
    m1.end = end1
    m1.work = interp.to_work(end1)
    corner_start = dict(end1)
    corner_end = at(m1, pb)
    # keep the other axes of the second move's start (helix / third axis untouched)
    if kind == "C":
        mid = Move("line", m2.line if False else m1.line, m1.block, corner_start, corner_end,
                   interp.to_work(corner_end), feed=m1.feed if m1.kind == "line" else m2.feed,
                   per_rev=m1.per_rev, plane=m1.plane, program=m1.program, tags=m1.tags + (",C",),
                   comp=m1.comp, comp_radius=m1.comp_radius, tip=m1.tip, css=m1.css)
    else:
        n = (-d1[1], d1[0]) if cross > 0 else (d1[1], -d1[0])
        c = (pa[0] + n[0] * value, pa[1] + n[1] * value)
        centre = at(m1, c)
        mid = Move("arc", m1.line, m1.block, corner_start, corner_end, interp.to_work(corner_end),
                   center=centre, dir="ccw" if cross > 0 else "cw", feed=m1.feed if m1.kind == "line" else m2.feed,
                   per_rev=m1.per_rev, plane=m1.plane, program=m1.program, tags=m1.tags + (",R",),
                   comp=m1.comp, comp_radius=m1.comp_radius, tip=m1.tip, css=m1.css)
    m2.start = dict(corner_end)
    if mid.feed is None:
        mid.kind = "line" if kind == "C" else mid.kind
    return [m1, mid]


# ---- corners next to arcs ---------------------------------------------------------------------
Pt = tuple[float, float]


class _Elem:
    """One move in the plane: a line p0→p1 or an arc p0→p1 about c (sweep signed, CCW > 0)."""

    def __init__(self, m: Move, a1: str, a2: str) -> None:
        self.p0: Pt = (m.start[a1], m.start[a2])
        self.p1: Pt = (m.end[a1], m.end[a2])
        self.arc = m.kind == "arc"
        if self.arc:
            from nc.interp.arcs import sweep

            assert m.center is not None
            self.c: Pt = (m.center[a1], m.center[a2])
            self.r = math.hypot(self.p0[0] - self.c[0], self.p0[1] - self.c[1])
            self.sw = sweep(self.p0, self.p1, self.c, m.dir == "cw")
            self.a0 = math.atan2(self.p0[1] - self.c[1], self.p0[0] - self.c[0])
        else:
            (self.d, self.length) = _unit(self.p0, self.p1)

    def length_along(self) -> float:
        return abs(self.sw) * self.r if self.arc else self.length

    def param(self, p: Pt) -> float | None:
        """Distance along the element from p0 to p (p on the element's line/circle), None if outside."""
        if self.arc:
            a = math.atan2(p[1] - self.c[1], p[0] - self.c[0]) - self.a0
            a = a % (2 * math.pi) if self.sw > 0 else -((-a) % (2 * math.pi))
            if abs(a) > abs(self.sw) + 1e-9 and abs(a) < 2 * math.pi - 1e-9:
                return None
            return abs(a) * self.r if abs(a) <= abs(self.sw) + 1e-9 else 0.0
        t = (p[0] - self.p0[0]) * self.d[0] + (p[1] - self.p0[1]) * self.d[1]
        return t if -1e-9 <= t <= self.length + 1e-9 else None

    def tangent(self, p: Pt) -> Pt:
        if not self.arc:
            return self.d
        k = 1.0 if self.sw > 0 else -1.0
        return (-(p[1] - self.c[1]) / self.r * k, (p[0] - self.c[0]) / self.r * k)

    def at_chord_from(self, corner: Pt, dist: float, from_end: bool) -> Pt | None:
        """The point of the element at straight distance `dist` from the corner (its end or start)."""
        if not self.arc:
            sgn = -1.0 if from_end else 1.0
            return (corner[0] + sgn * self.d[0] * dist, corner[1] + sgn * self.d[1] * dist)
        if dist > 2 * self.r:
            return None
        ang = 2 * math.asin(dist / (2 * self.r))
        if ang > abs(self.sw) + 1e-9:
            return None
        k = 1.0 if self.sw > 0 else -1.0
        base = math.atan2(corner[1] - self.c[1], corner[0] - self.c[0])
        a = base - k * ang if from_end else base + k * ang
        return (self.c[0] + self.r * math.cos(a), self.c[1] + self.r * math.sin(a))

    def offsets(self, rad: float) -> list[tuple[str, tuple]]:
        """The element's curves at distance rad (two lines or two circles)."""
        if not self.arc:
            n = (-self.d[1], self.d[0])
            return [("line", ((self.p0[0] + s * n[0] * rad, self.p0[1] + s * n[1] * rad), self.d)) for s in (1, -1)]
        return [("circle", (self.c, rr)) for rr in (self.r + rad, self.r - rad) if rr > 1e-9]


def _intersections(g1: tuple[str, tuple], g2: tuple[str, tuple]) -> list[Pt]:
    if g1[0] == "circle" and g2[0] == "line":
        g1, g2 = g2, g1
    if g1[0] == "line" and g2[0] == "line":
        (p, d), (q, e) = g1[1], g2[1]
        den = d[0] * e[1] - d[1] * e[0]
        if abs(den) < 1e-12:
            return []
        t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / den
        return [(p[0] + d[0] * t, p[1] + d[1] * t)]
    if g1[0] == "line":
        (p, d), (c, r) = g1[1], g2[1]
        fx, fy = p[0] - c[0], p[1] - c[1]
        b = fx * d[0] + fy * d[1]
        disc = b * b - (fx * fx + fy * fy - r * r)
        if disc < -1e-12:
            return []
        sq = math.sqrt(max(disc, 0.0))
        return [(p[0] + d[0] * t, p[1] + d[1] * t) for t in (-b - sq, -b + sq)]
    (c1, r1), (c2, r2) = g1[1], g2[1]
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    dd = math.hypot(dx, dy)
    if dd < 1e-12 or dd > r1 + r2 + 1e-12 or dd < abs(r1 - r2) - 1e-12:
        return []
    a = (r1 * r1 - r2 * r2 + dd * dd) / (2 * dd)
    h = math.sqrt(max(r1 * r1 - a * a, 0.0))
    mx, my = c1[0] + a * dx / dd, c1[1] + a * dy / dd
    return [(mx - h * dy / dd, my + h * dx / dd), (mx + h * dy / dd, my - h * dx / dd)]


def _foot(e: _Elem, fc: Pt) -> Pt:
    """Tangent point of a circle centred fc on the element's line or circle."""
    if not e.arc:
        t = (fc[0] - e.p0[0]) * e.d[0] + (fc[1] - e.p0[1]) * e.d[1]
        return (e.p0[0] + e.d[0] * t, e.p0[1] + e.d[1] * t)
    ux, uy = fc[0] - e.c[0], fc[1] - e.c[1]
    u = math.hypot(ux, uy)
    return (e.c[0] + e.r * ux / u, e.c[1] + e.r * uy / u)


def _join_curved(interp: "InterpHost", m1: Move, m2: Move, kind: str, value: float) -> list[Move]:
    def fail(msg: str) -> NcAlarm:
        return NcAlarm(0x0207, msg, line=m1.line, block=m1.block, program=m1.program)

    a1, a2 = m1.plane
    if m2.plane != m1.plane:
        raise fail(f",{kind} between moves in different planes")
    for m in (m1, m2):
        if m.kind == "arc" and any(abs(m.end[a] - m.start[a]) > 1e-9 for a in m.end if a not in (a1, a2)):
            raise NcAlarm(0x021D, f",{kind} next to a helical arc", line=m1.line, block=m1.block, program=m1.program)
    e1, e2 = _Elem(m1, a1, a2), _Elem(m2, a1, a2)
    corner = e1.p1
    if value <= 0:
        raise fail(f",{kind} must be positive")
    if kind == "C":
        pa = e1.at_chord_from(corner, value, from_end=True)
        pb = e2.at_chord_from(corner, value, from_end=False)
        if pa is None or pb is None or (not e1.arc and value > e1.length + 1e-9) \
                or (not e2.arc and value > e2.length + 1e-9):
            raise fail(f",C{value:g} is longer than an adjacent move")
        centre = None
        cw = False
    else:
        best: tuple[float, Pt, Pt, Pt] | None = None
        for g1 in e1.offsets(value):
            for g2 in e2.offsets(value):
                for fc in _intersections(g1, g2):
                    ta, tb = _foot(e1, fc), _foot(e2, fc)
                    s1, s2 = e1.param(ta), e2.param(tb)
                    if s1 is None or s2 is None:
                        continue
                    # the fillet must leave e1 and join e2 in their directions of travel
                    t1, t2 = e1.tangent(ta), e2.tangent(tb)
                    left = t1[0] * (fc[1] - ta[1]) - t1[1] * (fc[0] - ta[0]) > 0
                    k = 1.0 if left else -1.0
                    ft = (-(tb[1] - fc[1]) / value * k, (tb[0] - fc[0]) / value * k)
                    if ft[0] * t2[0] + ft[1] * t2[1] < 1.0 - 1e-6:
                        continue
                    cost = (e1.length_along() - s1) + s2
                    if best is None or cost < best[0]:
                        best = (cost, fc, ta, tb)
        if best is None:
            raise fail(f",R{value:g} does not fit between these moves")
        _, fc, pa, pb = best
        t1 = e1.tangent(pa)
        cw = t1[0] * (fc[1] - pa[1]) - t1[1] * (fc[0] - pa[0]) < 0
        centre = fc

    def at(m: Move, pt: Pt) -> dict[str, float]:
        d = dict(m.end)
        d[a1], d[a2] = pt
        return d

    end1 = at(m1, pa)
    m1.end = end1
    m1.work = interp.to_work(end1)
    corner_end = at(m1, pb)
    feed = m1.feed if m1.kind != "rapid" else m2.feed
    common = dict(per_rev=m1.per_rev, plane=m1.plane, program=m1.program, comp=m1.comp,
                  comp_radius=m1.comp_radius, tip=m1.tip, css=m1.css)
    if centre is None:
        mid = Move("line", m1.line, m1.block, dict(end1), corner_end, interp.to_work(corner_end), feed=feed,
                   tags=m1.tags + (",C",), **common)
    else:
        mid = Move("arc", m1.line, m1.block, dict(end1), corner_end, interp.to_work(corner_end),
                   center=at(m1, centre), dir="cw" if cw else "ccw", feed=feed, tags=m1.tags + (",R",), **common)
    m2.start = dict(corner_end)
    if math.hypot(pb[0] - pa[0], pb[1] - pa[1]) < 1e-9:
        return [m1]  # a tangent join: nothing to round
    return [m1, mid]
