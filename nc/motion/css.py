"""Constant surface speed (G96): the spindle speed that keeps V m/min at the tool's diameter.

n = 1000·V / (π·D), D the current X diameter in the work system (machine X is a radius; the
move's own machine/work pair gives the offset between them), clamped by the G50/G92 S limit.
The bench's maximum spindle speed is applied where the speed reaches the drive (the runner).
"""

from __future__ import annotations

import math

import numpy as np

from nc.moves import Move

MIN_DIAMETER = 1e-3  # mm: at the centre the speed is the clamp, never a division by zero


def css_rpm(move: Move, positions: np.ndarray, axes: tuple[str, ...], surface: float,
            limit: float | None, x_axis: str = "X") -> float:
    """Spindle speed (rpm, ≥ 0) for surface speed `surface` (m/min) at the setpoint `positions`."""
    if x_axis not in axes:
        return 0.0
    x = float(positions[axes.index(x_axis)])
    offset = move.end.get(x_axis, 0.0) - move.work.get(x_axis, 0.0) / 2.0
    d = max(abs(2.0 * (x - offset)), MIN_DIAMETER)
    rpm = 1000.0 * surface / (math.pi * d)
    if limit is not None and limit > 0.0:
        rpm = min(rpm, limit)
    return rpm
