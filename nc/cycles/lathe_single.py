"""Lathe single cycles G90 (OD/ID turning) and G94 (face), and G74/G75 peck grooving.

Plane (Z, X radius), machine coordinates. Decisions A47/A48: G90/G94 step 3 is a cutting move,
R is the taper (start − end, radius) at the start side; G74/G75 end at their start point.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.cycles.builder import PathBuilder
from nc.cycles.geometry import Pt


def g90(b: PathBuilder, end: Pt, taper: float, code: str = "G90") -> None:
    za, xa = b.here
    ze, xe = end
    b.rapid((za, xe + taper), (code, "approach"))
    b.feed_to((ze, xe), (code, "cut"))
    b.feed_to((ze, xa), (code, "cut"))
    b.rapid((za, xa), (code, "return"))


def g94(b: PathBuilder, end: Pt, taper: float, code: str = "G94") -> None:
    za, xa = b.here
    ze, xe = end
    b.rapid((ze + taper, xa), (code, "approach"))
    b.feed_to((ze, xe), (code, "cut"))
    b.feed_to((za, xe), (code, "cut"))
    b.rapid((za, xa), (code, "return"))


def _steps(a: float, b: float, step: float) -> Iterator[float]:
    """Positions from a to b (inclusive) every `step`, the last one clamped to b; lazy, so P1 Q1
    (1 µm) on a long stroke, legal if huge, costs no memory (decisions B1)."""
    if abs(b - a) < 1e-9:
        yield a
        return
    if step <= 0:
        raise NcAlarm(0x0246, "peck/shift amount must be positive")
    n = math.ceil(abs(b - a) / step - 1e-9)
    sgn = 1.0 if b > a else -1.0
    for i in range(n):
        yield a + sgn * i * step
    yield b  # exactly: callers recognise the last position by it


def peck_groove(b: PathBuilder, end: Pt, shift: float, peck: float, escape: float, retract: float,
                face: bool, code: str) -> Iterator[None]:
    """G74 (face = True: peck in Z, shift in X) and G75 (peck in X, shift in Z).

    Per position: feed one peck, rapid back `retract`, feed on, to the bottom; escape `escape` at the
    bottom away from the shift direction, rapid back to the start level, shift to the next position.
    Yields after each peck so the caller hands the moves on as they are made.
    """
    za, xa = b.here
    ze, xe = end
    # work in (peck axis, shift axis) coordinates
    if face:
        p_start, p_end, s_start, s_end = za, ze, xa, xe
    else:
        p_start, p_end, s_start, s_end = xa, xe, za, ze

    def pt(p: float, s: float) -> Pt:
        return (p, s) if face else (s, p)

    if peck <= 0 and abs(p_end - p_start) > 1e-9:
        raise NcAlarm(0x0246, f"{code} peck amount must be positive")
    positions = _steps(s_start, s_end, shift) if abs(s_end - s_start) > 1e-9 else [s_start]
    pdir = 1.0 if p_end > p_start else -1.0
    sdir = 1.0 if s_end > s_start else -1.0
    for j, s in enumerate(positions, start=1):
        b.rapid(pt(p_start, s), (code, "shift"))
        if abs(p_end - p_start) > 1e-9:
            depths = _steps(p_start, p_end, peck)
            next(depths)  # the start level itself
            for d in depths:
                b.feed_to(pt(d, s), (code, "peck", str(j)))
                if d != p_end and retract > 0:
                    back = d - pdir * min(retract, abs(d - p_start))
                    b.rapid(pt(back, s), (code, "retract"))
                yield
        if escape > 1e-12 and j > 1:
            b.feed_to(pt(p_end, s - sdir * escape), (code, "escape"))
        b.rapid(pt(p_start, b.here[1] if face else b.here[0]), (code, "return"))
    b.rapid(pt(p_start, s_start), (code, "return"))
