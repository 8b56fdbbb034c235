"""Hole cycles: milling G73, G74, G76, G81–G89 and lathe G83–G85, G87–G89, in machine coordinates.

One hole = position (rapid) → drill axis rapid to R → the cycle's own motion → return to the
initial level (G98) or the R level (G99). Spindle changes go out as `Aux("M", …)` events so the MLC
sees them in order with the motion (decisions A50/A51).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.builder import PathBuilder


@dataclass
class Hole:
    kind: str  # drill | peck_full | peck_chip | tap | bore_feed | bore_stop | fine_bore | back_bore | manual
    code: str  # tag, e.g. "G81"
    axis: str  # drilling axis name
    position: dict[str, float]  # positioning axes (machine)
    r_level: float  # machine
    bottom: float  # machine
    initial: float  # machine
    return_r: bool  # G99
    peck: float = 0.0  # Q (peck depth), > 0 to peck
    clearance: float = 0.0  # d: chip-break retract (G73) / re-approach clearance (G83)
    dwell: float = 0.0  # seconds at the bottom
    shift: dict[str, float] | None = None  # G76/G87 tool shift (machine delta)
    spindle_dir: int = 1  # direction before the cycle (+1 M03, -1 M04, 0 stopped)
    reverse_tap: bool = False  # G74 left-hand tapping
    clamp_m: int | None = None  # lathe guide M_: this M at the hole position, M+1 back at R (C clamp / unclamp)


def _unclamp(b: PathBuilder, h: Hole, tag: tuple[str, ...]) -> None:
    """Lathe guide G83-G89 `M_`: back at R (rapid there if the tool is below it), M+1 before the top pause."""
    if h.clamp_m is None:
        return
    if b.position[h.axis] != h.r_level:
        b.rapid_axes({h.axis: h.r_level}, tag + ("return",))
    b.aux("M", h.clamp_m + 1)


def _return(b: PathBuilder, h: Hole, tag: tuple[str, ...], level: float) -> None:
    _unclamp(b, h, tag)
    if b.position[h.axis] != level:
        b.rapid_axes({h.axis: level}, tag + ("return",))


def _levels(start: float, end: float, step: float) -> Iterator[float]:
    """Peck bottoms from `start` to `end` every `step`, the last one `end`; lazy, so a 1 µm peck on a
    long stroke (legal, N§3.13.1) costs no memory (decisions B1)."""
    if step <= 0:
        yield end
        return
    sgn = 1.0 if end > start else -1.0
    n = max(1, math.ceil((abs(end - start) - 1e-9) / step))  # pecks, the last one clamped to `end`
    for k in range(1, n):
        yield start + sgn * k * step
    yield end


def _not_past(level: float, r_level: float, sgn: float) -> float:
    """A chip-break retract or re-approach level, clamped so it never lies beyond R (away from the hole)."""
    return min(level, r_level) if sgn > 0 else max(level, r_level)


def _spindle_code(direction: int) -> int:
    return {1: 3, -1: 4}.get(direction, 5)


def drill_hole(b: PathBuilder, h: Hole) -> Iterator[None]:
    """Add one hole's moves to `b`; yields after each peck so the caller can hand them on (lazy)."""
    ax = h.axis
    tag = (h.code,)
    b.rapid_axes(h.position, tag + ("position",))
    if h.clamp_m is not None:  # at the start point, before the drill axis moves (L§2.1 G83 "M_")
        b.aux("M", h.clamp_m)
    sgn = 1.0 if h.bottom < h.r_level else -1.0  # toward the workpiece is toward `bottom`
    ret_level = h.r_level if h.return_r else h.initial

    if h.kind == "back_bore":
        # G87: orient, shift, rapid to the R level below the hole, shift back, bore upward to Z
        b.aux("M", 19)
        b.rapid_axes({a: b.position[a] + v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.rapid_axes({ax: h.r_level}, tag + ("approach",))
        b.rapid_axes({a: b.position[a] - v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.aux("M", 3)
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        b.aux("M", 19)
        b.rapid_axes({a: b.position[a] + v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.rapid_axes({ax: h.initial}, tag + ("return",))
        b.rapid_axes({a: b.position[a] - v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.aux("M", _spindle_code(h.spindle_dir or 1))
        return

    b.rapid_axes({ax: h.r_level}, tag + ("approach",))
    if h.kind == "drill":
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        _return(b, h, tag, ret_level)
    elif h.kind in ("peck_full", "peck_chip"):
        prev = h.r_level
        for i, d in enumerate(_levels(h.r_level, h.bottom, h.peck), start=1):
            if h.kind == "peck_full" and i > 1:
                # re-approach rapidly to just above the previous bottom, never above R (a peck
                # shallower than d, e.g. `Q4` = 4 µm, would otherwise cut air from above R)
                b.rapid_axes({ax: _not_past(prev + sgn * h.clearance, h.r_level, sgn)}, tag + ("reapproach",))
            b.line_axes({ax: d}, tag + ("peck", str(i)))
            if d != h.bottom:
                if h.kind == "peck_full":
                    b.rapid_axes({ax: h.r_level}, tag + ("retract",))
                else:
                    b.rapid_axes({ax: _not_past(d + sgn * h.clearance, h.r_level, sgn)}, tag + ("retract",))
            prev = d
            yield
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        _return(b, h, tag, ret_level)
    elif h.kind == "tap":
        into = -1 if h.reverse_tap else 1
        if h.spindle_dir != into:
            b.aux("M", _spindle_code(into))
        for i, d in enumerate(_levels(h.r_level, h.bottom, h.peck), start=1):
            if i > 1:
                b.aux("M", _spindle_code(into))
            b.line_axes({ax: d}, tag + ("tap", str(i)))
            if h.dwell > 0 and d == h.bottom:
                b.dwell(h.dwell, tag + ("dwell",))
            b.aux("M", _spindle_code(-into))  # spindle reversal at the bottom of each peck
            b.line_axes({ax: h.r_level}, tag + ("tap_out", str(i)))
            yield
        _unclamp(b, h, tag)
        b.aux("M", _spindle_code(h.spindle_dir if h.spindle_dir else into))
        if not h.return_r:
            b.rapid_axes({ax: h.initial}, tag + ("return",))
    elif h.kind == "bore_feed":
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        b.line_axes({ax: h.r_level}, tag + ("cut_out",))
        _unclamp(b, h, tag)
        if not h.return_r:
            b.rapid_axes({ax: h.initial}, tag + ("return",))
    elif h.kind == "bore_stop":
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        b.aux("M", 5)
        b.rapid_axes({ax: ret_level}, tag + ("return",))
        b.aux("M", _spindle_code(h.spindle_dir or 1))
    elif h.kind == "fine_bore":
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        b.aux("M", 19)  # spindle orientation before the tool leaves the bore wall
        b.rapid_axes({a: b.position[a] + v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.rapid_axes({ax: ret_level}, tag + ("return",))
        b.rapid_axes({a: b.position[a] - v for a, v in (h.shift or {}).items()}, tag + ("shift",))
        b.aux("M", _spindle_code(h.spindle_dir or 1))
    elif h.kind == "manual":
        b.line_axes({ax: h.bottom}, tag + ("cut",))
        if h.dwell > 0:
            b.dwell(h.dwell, tag + ("dwell",))
        b.aux("M", 5)
        b.aux("M", 0)  # G88: the operator retracts by hand, then presses cycle start
        b.rapid_axes({ax: ret_level}, tag + ("return",))
        b.aux("M", _spindle_code(h.spindle_dir or 1))
    else:
        raise NcAlarm(0x021D, f"unknown hole cycle kind {h.kind}")
