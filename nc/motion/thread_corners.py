"""Corners inside a spindle-locked thread chain (a thread and its chamfer pull-out, say).

The major axis is locked to the spindle, so the chain cannot slow down at a corner: taken as
programmed, the cross axis (X at a G76/G92 chamfer) would step from rest to the chamfer's speed in
one cycle. A lathe's post-interpolation acc/dec rounds that corner; here the rounding is explicit
and the same on every pass. Along the major-axis travel u the piecewise-linear chain P(u) is
smoothed at each corner by a triangular kernel of half-width w (two moving averages of width w):

    P̃(u) = P(u) + ΔK · δ(u − u_c),   δ(t) = (w − |t|)³ / (6 w²) for |t| < w, else 0,

where ΔK is the change of the axes' slope dP/du at the corner. At the locked speed v along u, an
axis then sees acceleration ≤ v²·|ΔK|/w and jerk ≤ v³·|ΔK|/w², so w is the least width that keeps
both inside the axis limits. The corner is passed at w/6·|ΔK| from its vertex (decision A42b in
docs/decisions/cycles.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Share of each axis' acceleration and jerk a corner may use: the spindle's measured speed
# wanders a little around its command while the chain is locked.
SHARE = 0.9


@dataclass(frozen=True)
class ThreadCorner:
    u: float  # major-axis travel at the corner
    dk: np.ndarray  # change of dP/du per axis
    w: float  # kernel half-width along u


def corner_width(dk: np.ndarray, v: float, acc: np.ndarray, jerk: np.ndarray) -> float:
    """Least half-width w that keeps every axis within SHARE of its acceleration and jerk."""
    d = np.abs(dk)
    w_a = float(np.max(v * v * d / (SHARE * acc)))
    w_j = float(np.max(np.sqrt(v ** 3 * d / (SHARE * jerk))))
    return max(w_a, w_j)


def make_corner(u_c: float, k0: np.ndarray, k1: np.ndarray, v: float, acc: np.ndarray, jerk: np.ndarray,
                room: float) -> ThreadCorner | None:
    """The corner between slopes k0 → k1 at u_c; `room` is the most w may take (half the shorter
    neighbouring block, so corners never overlap and a block's end point stays exact)."""
    dk = k1 - k0
    if float(np.max(np.abs(dk))) < 1e-12 or room <= 0.0:
        return None
    return ThreadCorner(u_c, dk, min(corner_width(dk, v, acc, jerk), room))


def corner_offset(corners: list[ThreadCorner], u: float) -> np.ndarray | None:
    """The smoothing offset to add to the chain's programmed point at travel u (None: none)."""
    out = None
    for c in corners:
        t = abs(u - c.u)
        if t < c.w:
            d = c.dk * ((c.w - t) ** 3 / (6.0 * c.w * c.w))
            out = d if out is None else out + d
    return out

