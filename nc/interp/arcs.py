"""Arc centre geometry for G02/G03 in any plane (R or I/J/K form)."""

from __future__ import annotations

import math

from nc.alarms import NcAlarm


def center_from_radius(s: tuple[float, float], e: tuple[float, float], r: float, cw: bool,
                       tol: float) -> tuple[float, float]:
    """Centre of the arc from s to e with signed radius R (R > 0: ≤ 180°, R < 0: > 180°; decisions A28).

    Coordinates are (first, second) plane axes in a right-handed frame, so CCW is positive rotation.
    """
    dx, dy = e[0] - s[0], e[1] - s[1]
    d = math.hypot(dx, dy)
    if d < 1e-12:
        raise NcAlarm(0x0259, "R-form arc with coincident start and end points (a full circle needs I/J/K)")
    half = d / 2.0
    rr = abs(r)
    if rr < half:
        if half - rr > tol:
            raise NcAlarm(0x0259, f"arc radius {rr:g} is smaller than half the chord {half:g}")
        rr = half
    h = math.sqrt(max(rr * rr - half * half, 0.0))
    mx, my = (s[0] + e[0]) / 2.0, (s[1] + e[1]) / 2.0
    # unit normal to the left of the chord direction
    nx, ny = -dy / d, dx / d
    # CCW small arc: centre left of the chord; CW small arc: right; R < 0 flips
    side = (1.0 if not cw else -1.0) * (1.0 if r > 0 else -1.0)
    return mx + side * h * nx, my + side * h * ny


def check_center(s: tuple[float, float], e: tuple[float, float], c: tuple[float, float], tol: float) -> None:
    r0 = math.hypot(s[0] - c[0], s[1] - c[1])
    r1 = math.hypot(e[0] - c[0], e[1] - c[1])
    if r0 < 1e-9:
        raise NcAlarm(0x025A, "arc centre coincides with the start point")
    if abs(r1 - r0) > tol:
        raise NcAlarm(0x025A, f"arc end point is not on the circle: start radius {r0:.4f}, end radius {r1:.4f}")


def sweep(s: tuple[float, float], e: tuple[float, float], c: tuple[float, float], cw: bool) -> float:
    """Signed swept angle (radians), CCW positive; coincident start and end mean a full circle."""
    a0 = math.atan2(s[1] - c[1], s[0] - c[0])
    a1 = math.atan2(e[1] - c[1], e[0] - c[0])
    ccw = (a1 - a0) % (2 * math.pi)
    if math.hypot(e[0] - s[0], e[1] - s[1]) < 1e-9:
        ccw = 0.0
    if cw:
        return ccw - 2 * math.pi if ccw > 0 else -2 * math.pi
    return ccw if ccw > 0 else 2 * math.pi
