"""Lathe imaginary tool tip numbers (decisions A52, Fanuc layout) and the offset data behind them.

The vector is from the nose centre to the imaginary tip, in the lathe plane (Z, X radius), for a
machine with +X away from the spindle centre line. Looking at the plane with +Z right, +X up::

    2  6  1
    7 0/9 5
    3  8  4

Tip 3 is the usual OD turning tool (touches the work on its −Z, −X side), tip 2 the usual boring bar.
"""

from __future__ import annotations

from nc.cycles.geometry import Pt

TIP_DIRECTIONS: dict[int, Pt] = {
    0: (0.0, 0.0), 9: (0.0, 0.0),
    1: (1.0, 1.0), 2: (-1.0, 1.0), 3: (-1.0, -1.0), 4: (1.0, -1.0),
    5: (1.0, 0.0), 6: (0.0, 1.0), 7: (-1.0, 0.0), 8: (0.0, -1.0),
}


def tip_vector(tip: int, radius: float) -> Pt:
    """Nose centre → imaginary tip, in (Z, X) plane coordinates; zero for an unknown number."""
    dz, dx = TIP_DIRECTIONS.get(int(tip), (0.0, 0.0))
    return (dz * radius, dx * radius)


def nose_radius(radius: float, wear: float) -> float:
    """Effective nose radius = geometry + wear (seed §5.1 [assumption], decisions A53)."""
    return radius + wear
