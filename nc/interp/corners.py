"""`,C` chamfer and `,R` corner rounding between two motion blocks (N§3.3.2, L l.2388; decisions A32).

A block carrying ``,C`` or ``,R`` is held back until the next motion block is known; both lines are
trimmed and a chamfer line or a tangent arc is inserted.  ``,C`` is the leg length measured from
the virtual corner along each line; both blocks must be straight lines in the active plane.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import TYPE_CHECKING

from nc.alarms import NcAlarm
from nc.moves import Event, Move, ProgramEnd

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.interpreter import Interpreter


def expand_corners(interp: "Interpreter", events: Iterator[Event]) -> Iterator[Event]:
    pending: tuple[Move, str, float] | None = None
    held: list[Event] = []  # M/S/T or dwell events of the next block, issued after the corner
    for ev in events:
        if isinstance(ev, Move) and ev.kind in ("line", "arc", "rapid", "thread"):
            mark = _mark(interp, ev)
            if pending is not None:
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
        if pending is not None:
            if isinstance(ev, ProgramEnd):
                _fail(pending)
            held.append(ev)
            continue
        yield ev
    if pending is not None:
        _fail(pending)


def _fail(pending: tuple[Move, str, float]) -> None:
    first = pending[0]
    raise NcAlarm(0x0207, f",{pending[1]} must be followed by a motion block", line=first.line,
                  block=first.block, program=first.program)


def _mark(interp: "Interpreter", mv: Move) -> tuple[str, float] | None:
    """The ,C / ,R request of the block that produced this move (only its last move carries it)."""
    b = interp.block
    if b is None or b.line != mv.line or b.text != mv.block or "G31" in mv.tags:
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


def _join(interp: "Interpreter", m1: Move, m2: Move, kind: str, value: float) -> list[Move]:
    if m1.kind != "line" and m1.kind != "rapid" or m2.kind not in ("line", "rapid"):
        raise NcAlarm(0x021D, f",{kind} is supported between two straight moves", line=m1.line, block=m1.block,
                      program=m1.program)
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
