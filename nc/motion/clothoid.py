"""Corner blends between two lines: a symmetric clothoid pair (decision motion 40, built in 41).

The pair's curvature rises linearly over a length L to θ/L and falls back over another L, so the
path stays curvature-continuous (G2) and the axis jerk bounded: at speed v the normal acceleration
is v²·κ ≤ v²·θ/L and its rate v³·dκ/ds = v³·θ/L². It is sized as LinuxCNC's tp sizes its blend arcs
(tc/blendmath.c): its deviation from the corner within the tolerance, and no more than half of
either line. `ClothoidBlend` is a path segment like `nc.motion.path.Segment` (points(s), tangents,
curvature at its ends, direction cosines), so the planner samples it as any other block.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from dataclasses import dataclass, field
from importlib.machinery import EXTENSION_SUFFIXES
from pathlib import Path
from typing import Callable

import numpy as np

from nc.motion.path import Segment

MAX_TURN = math.radians(135.0)  # sharper corners are not blended: they stop nearly anyway
MIN_TURN = 1e-6  # below this a junction counts as tangent
_UFUNCS = "scipy.special._special_ufuncs"  # the extension module whose ufunc scipy.special.fresnel is


def _load_fresnel() -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """scipy.special.fresnel, without importing the scipy.special package (bench decision B47): its __init__ costs
    ≈ 0.17 s (the array-API back-end support pulls array_api_compat, numpy.testing and numpy.f2py), a sixth of
    `hil run`'s whole process (issue 17), while the ufunc's own extension module loads in ≈ 1 ms. It is the very
    same ufunc object (a single-phase extension: scipy.special, imported later, gets the same one), so the values
    are scipy's. Any surprise in scipy's layout (the module moved or renamed in a later scipy): the public import."""
    if "scipy.special" in sys.modules or _UFUNCS in sys.modules:  # imported already: nothing to save
        from scipy.special import fresnel

        return fresnel
    try:
        scipy_spec = importlib.util.find_spec("scipy")  # found, not imported (a top-level name)
        assert scipy_spec is not None and scipy_spec.origin is not None
        files = (Path(scipy_spec.origin).parent / "special" / f"_special_ufuncs{suffix}" for suffix in EXTENSION_SUFFIXES)
        path = next(f for f in files if f.is_file())
        spec = importlib.util.spec_from_file_location(_UFUNCS, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules.pop(_UFUNCS, None)  # out again: a later `import scipy.special` loads it as its own submodule
        fresnel = module.fresnel
        if not isinstance(fresnel, np.ufunc) or fresnel.nin != 1 or fresnel.nout != 2:
            raise ImportError(f"{_UFUNCS}.fresnel is not the (S, C) ufunc")
        return fresnel
    except Exception:  # noqa: BLE001 - any failure of the short way: the public one
        from scipy.special import fresnel

        return fresnel


fresnel = _load_fresnel()


def unit_clothoid(theta: float, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) at s (0 … 1) of the unit-length clothoid of a pair turning by theta, heading 0 at s = 0."""
    a = math.sqrt(1.0 / theta)  # s²/(2A²) = theta/2 at s = 1: A² = 1/theta
    sf, cf = fresnel(np.asarray(s, dtype=float) / (a * math.sqrt(math.pi)))  # scipy returns (S, C)
    return a * math.sqrt(math.pi) * cf, a * math.sqrt(math.pi) * sf


def clothoid_pair(theta: float) -> tuple[float, float]:
    """(tangent length, deviation from the corner) of a symmetric clothoid pair turning by theta,
    each clothoid of unit length: both scale with the length L."""
    x, y = (float(c) for c in unit_clothoid(theta, 1.0))
    h = theta / 2.0
    t = x + y * math.tan(h)  # the pair's middle lies on the corner's axis of symmetry
    dev = math.hypot(x - t, y) * math.cos(h)  # distance of that middle from each leg
    return t, dev


def pair_length(theta: float, tol: float, len1: float, len2: float) -> tuple[float, float]:
    """(L, tangent length) of the pair at a corner of turn theta between lines of lengths len1 and
    len2: the deviation within tol, the tangent length within half of either line."""
    t1, dev1 = clothoid_pair(theta)
    half = min(tol / dev1, 0.5 * min(len1, len2) / t1)
    return half, t1 * half


@dataclass
class ClothoidBlend(Segment):
    """The pair from q0 (on the first line, heading u1) to q1 (on the second, heading u2)."""

    turn: float = 0.0  # θ, rad
    half: float = 0.0  # L: each clothoid's length (the pair's is 2L)
    tlen: float = 0.0  # tangent length: distance of q0 and q1 from the corner
    u1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n1: np.ndarray = field(default_factory=lambda: np.zeros(0))
    u2: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n2: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def kappa_max(self) -> float:
        return self.turn / self.half

    @property
    def dkappa(self) -> float:
        """|dκ/ds| on both clothoids."""
        return self.turn / (self.half * self.half)

    @property
    def deviation(self) -> float:
        return clothoid_pair(self.turn)[1] * self.half

    def points(self, s: np.ndarray) -> np.ndarray:
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        L = self.half
        first = s <= L
        out = np.empty((len(s), len(self.axes)))
        if first.any():  # the first clothoid from its start
            cx, cy = unit_clothoid(self.turn, s[first] / L)
            out[first] = self.start + (L * cx)[:, None] * self.u1 + (L * cy)[:, None] * self.n1
        if (~first).any():  # the second back from its end
            cx, cy = unit_clothoid(self.turn, (self.length - s[~first]) / L)
            out[~first] = self.end - (L * cx)[:, None] * self.u2 + (L * cy)[:, None] * self.n2
        return out

    def unit_tangent(self, at_end: bool) -> np.ndarray:
        return (self.u2 if at_end else self.u1).copy()

    def curvature_vector(self, at_end: bool) -> np.ndarray:
        return np.zeros(len(self.axes))  # a clothoid pair starts and ends straight

    def max_direction_cosines(self) -> np.ndarray:
        """Largest |d axis / d s| while the heading turns from u1 (φ = 0) to u2 (φ = θ) in their
        plane: the component cos φ·u1 + sin φ·n1 peaks at φ* = atan2(n1, u1) (mod π)."""
        amp = np.hypot(self.u1, self.n1)
        peak = np.mod(np.arctan2(self.n1, self.u1), math.pi)
        ends = np.maximum(np.abs(self.u1), np.abs(self.u2))
        return np.where(peak <= self.turn, amp, ends)

    def normal_amplitude(self) -> np.ndarray:
        """Largest share of the normal direction (−sin φ·u1 + cos φ·n1) on each axis."""
        return np.hypot(self.u1, self.n1)


def corner_blend(s1: Segment, s2: Segment, tol: float, len1: float, len2: float) -> ClothoidBlend | None:
    """The pair at the corner s1 → s2 (two lines meeting at s1.end), or None when the junction is
    tangent or sharper than MAX_TURN. len1/len2: the lines' programmed lengths (the half rule)."""
    u1 = np.asarray(s1.tangent(True), dtype=float)
    u2 = np.asarray(s2.tangent(False), dtype=float)
    c = float(np.clip(u1 @ u2, -1.0, 1.0))
    theta = math.acos(c)
    if theta < MIN_TURN or theta > MAX_TURN or tol <= 0.0:
        return None
    half, t = pair_length(theta, tol, len1, len2)
    if half <= 1e-9:
        return None
    vx = s1.end
    n1 = u2 - c * u1  # towards the turn, normal to each leg
    n2 = c * u2 - u1
    n1 /= np.linalg.norm(n1)
    n2 /= np.linalg.norm(n2)
    return ClothoidBlend(s1.axes, vx - u1 * t, vx + u2 * t, 2.0 * half, "blend", turn=theta, half=half, tlen=t,
                         u1=u1, n1=n1, u2=u2, n2=n2)
