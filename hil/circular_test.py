"""ISO 230-4 circular test evaluation of a trace: when one program block commands a full circle
(a ballbar program's G02/G03 with I/J/K and no end point), the actual path of that block is
measured against the nominal circle as the standard defines it:

- circular deviation G: radial band of the actual path about its least-squares centre (max − min);
- radial deviation F: the actual path's largest and smallest radius minus the nominal radius,
  about the nominal (commanded) centre.
- circular hysteresis H, where the program runs the same circle both ways (a G02 and a G03 full
  circle about the same centre with the same radius): the largest difference of the two actual
  paths' radii at the same angle. With one direction only, no H is given."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class CircularTest:
    line: int  # program line of the circle
    centre: tuple[float, float]  # nominal centre (fit of the commanded points), mm
    radius: float  # nominal radius, mm
    G: float  # circular deviation, mm (ISO 230-4 3.1)
    F_max: float  # radial deviation, largest, mm
    F_min: float  # radial deviation, smallest, mm
    direction: int = 0  # +1 counter-clockwise (G03 in XY), -1 clockwise
    profile: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)  # angle, actual radius


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
        steps = np.diff(np.unwrap(np.arctan2(cv - cy, ch - cx)))
        turn = np.sum(np.abs(steps))
        if turn < 2 * np.pi * 0.9:  # start and end blends are trimmed, as ISO 230-4 drops overshoot arcs
            continue
        ah, av = cols[f"{h}_act"][sel][on], cols[f"{v}_act"][sel][on]
        lx, ly, _ = _fit(ah, av)
        band = np.hypot(ah - lx, av - ly)
        radial = np.hypot(ah - cx, av - cy) - r
        angle = np.mod(np.arctan2(av - cy, ah - cx), 2 * np.pi)
        out.append(CircularTest(int(ln), (cx, cy), r, float(band.max() - band.min()),
                                float(radial.max()), float(radial.min()), int(np.sign(np.sum(steps))),
                                (angle, radial + r)))
    return out


def hysteresis(tests: list[CircularTest], tol: float = 1e-3) -> list[tuple[int, int, float]]:
    """(line, line, H in mm) for each pair of circles run both ways about the same centre and radius
    (within `tol` mm): the largest difference of the actual radii at the same angle (1° grid)."""
    out = []
    grid = np.radians(np.arange(0.0, 360.0, 1.0))
    for i, a in enumerate(tests):
        for b in tests[i + 1:]:
            same = (abs(a.radius - b.radius) < tol and np.hypot(a.centre[0] - b.centre[0],
                                                                  a.centre[1] - b.centre[1]) < tol)
            if not same or a.direction * b.direction >= 0 or a.profile is None or b.profile is None:
                continue
            ra, rb = (np.interp(grid, *_sorted(t.profile), period=2 * np.pi) for t in (a, b))
            out.append((a.line, b.line, float(np.max(np.abs(ra - rb)))))
    return out


def _sorted(profile: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(profile[0])
    return profile[0][order], profile[1][order]


def format_circular(tests: list[CircularTest]) -> str:
    lines = [f"ISO 230-4 circular hysteresis, lines {a} and {b}: H {h * 1000:.2f} µm"
             for a, b, h in hysteresis(tests)]
    return "\n".join([f"ISO 230-4 circular test, line {c.line}: R {c.radius:.4f} mm about "
                     f"({c.centre[0]:.4f}, {c.centre[1]:.4f}); circular deviation G {c.G * 1000:.2f} µm; "
                     f"radial deviation F {c.F_min * 1000:+.2f} … {c.F_max * 1000:+.2f} µm" for c in tests] + lines)
