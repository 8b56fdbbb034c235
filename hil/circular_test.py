"""ISO 230-4 circular test evaluation of a trace: when one program block commands a full circle
(a ballbar program's G02/G03 with I/J/K and no end point), the actual path of that block is
measured against the nominal circle as the standard defines it:

- circular deviation G: radial band of the actual path about its least-squares centre (max − min);
- radial deviation F: the actual path's largest and smallest radius minus the nominal radius,
  about the nominal (commanded) centre.
Circular hysteresis H needs the same circle run both ways and is left to the reader of two runs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class CircularTest:
    line: int  # program line of the circle
    centre: tuple[float, float]  # nominal centre (fit of the commanded points), mm
    radius: float  # nominal radius, mm
    G: float  # circular deviation, mm (ISO 230-4 3.1)
    F_max: float  # radial deviation, largest, mm
    F_min: float  # radial deviation, smallest, mm


def _fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares circle (algebraic fit): centre and radius."""
    a = np.column_stack([x, y, np.ones_like(x)])
    sol, *_ = np.linalg.lstsq(a, x * x + y * y, rcond=None)
    cx, cy = sol[0] / 2, sol[1] / 2
    return float(cx), float(cy), float(np.sqrt(sol[2] + cx * cx + cy * cy))


def full_circles(cols: dict[str, np.ndarray], plane: tuple[str, str]) -> list[CircularTest]:
    """Every program line whose commanded points lie on one circle over a full turn."""
    h, v = plane
    out: list[CircularTest] = []
    lines = cols["line"]
    for ln in np.unique(lines):
        sel = lines == ln
        ch, cv = cols[f"{h}_cmd"][sel], cols[f"{v}_cmd"][sel]
        if len(ch) < 16:
            continue
        cx, cy, r = _fit(ch, cv)
        if not np.isfinite(r) or r <= 1e-6:
            continue
        # the block's first and last cycles may still be a blend with its neighbours: trim, refit
        on = np.ones(len(ch), dtype=bool)
        for tol in (0.01 * r, max(1e-3, 1e-4 * r)):
            on &= np.abs(np.hypot(ch - cx, cv - cy) - r) < tol
            if on.mean() < 0.75:
                break
            cx, cy, r = _fit(ch[on], cv[on])
        if on.mean() < 0.75:
            continue  # commanded points are not one circle
        ch, cv = ch[on], cv[on]
        turn = np.sum(np.abs(np.diff(np.unwrap(np.arctan2(cv - cy, ch - cx)))))
        if turn < 2 * np.pi * 0.9:  # start and end blends are trimmed, as ISO 230-4 drops overshoot arcs
            continue
        ah, av = cols[f"{h}_act"][sel][on], cols[f"{v}_act"][sel][on]
        lx, ly, _ = _fit(ah, av)
        band = np.hypot(ah - lx, av - ly)
        radial = np.hypot(ah - cx, av - cy) - r
        out.append(CircularTest(int(ln), (cx, cy), r, float(band.max() - band.min()),
                                float(radial.max()), float(radial.min())))
    return out


def format_circular(tests: list[CircularTest]) -> str:
    return "\n".join(f"ISO 230-4 circular test, line {c.line}: R {c.radius:.4f} mm about "
                     f"({c.centre[0]:.4f}, {c.centre[1]:.4f}); circular deviation G {c.G * 1000:.2f} µm; "
                     f"radial deviation F {c.F_min * 1000:+.2f} … {c.F_max * 1000:+.2f} µm" for c in tests)
