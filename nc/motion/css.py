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


def x_origin(move: Move, x_axis: str = "X", diameter: bool = True) -> float:
    """Machine X (radius) of the work centre line the move is programmed from: its end less its
    work X, which is a diameter when the profile programs X in diameter (N2.001 Bit10 = 0)."""
    work = move.work.get(x_axis, 0.0)
    return move.end.get(x_axis, 0.0) - (work / 2.0 if diameter else work)


def css_rpm_at(x: float, origin: float, surface: float, limit: float | None) -> float:
    """Spindle speed (rpm, ≥ 0) for `surface` m/min with the tool at machine X `x` (radius) and the
    work centre at `origin`, clamped by the G50/G92 S `limit`."""
    d = max(abs(2.0 * (x - origin)), MIN_DIAMETER)
    rpm = 1000.0 * surface / (math.pi * d)
    if limit is not None and limit > 0.0:
        rpm = min(rpm, limit)
    return rpm


def css_rpm(move: Move, positions: np.ndarray, axes: tuple[str, ...], surface: float,
            limit: float | None, x_axis: str = "X", diameter: bool = True) -> float:
    """Spindle speed (rpm, ≥ 0) for surface speed `surface` (m/min) at the setpoint `positions`."""
    if x_axis not in axes:
        return 0.0
    x = float(positions[axes.index(x_axis)])
    return css_rpm_at(x, x_origin(move, x_axis, diameter), surface, limit)


def spindle_speed(rpm: float, css: float | None, clamp: float | None, max_rpm: float,
                  override: float = 1.0) -> float:
    """The signed speed the first spindle's drive is given for the MLC's `rpm` (its sign is the
    direction; its size the S or D2x024 speed before the override): the G96 speed `css` while
    constant surface speed is on, else `rpm`, times the spindle `override` (D2x026; the caller
    forces 1.0 in threads), then within the G50/G92 S `clamp`, which holds under G97 too (decisions
    A39), and within `max_rpm` (motion decisions 30, 32). The runner commands it and the NC's
    "speed reached" (M3x704) compares the drive with it."""
    if not rpm:
        return 0.0
    out = (abs(rpm) if css is None else css) * max(override, 0.0)
    if clamp is not None and (clamp > 0.0 or css is None):
        out = min(out, clamp)
    return min(out, max_rpm) * (1.0 if rpm > 0 else -1.0)
