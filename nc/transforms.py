"""Programmable coordinate transforms: scaling G51/G50, mirror G51.1/G50.1 (mill G24/G25),
rotation G68/G69 (polar G15/G16 is done by the interpreter's geometry).

They act on programmed work coordinates, in this order (decisions A56–A58, Fanuc):
mirror → scaling → rotation. Under an odd number of reflections (a mirrored plane axis, or a
negative scale on one plane axis) G02/G03 swap and G41/G42 swap (A57).

The interpreter calls:
* ``modal(host, fn, block)`` for fn in scale, scale_off, mirror, mirror_off, G68, G69;
* ``apply(host, work) -> work`` on every programmed end point and arc centre (work coords);
* ``inverse(host, work) -> work`` to get the program-frame position for incremental moves;
* ``arc_cw(host, plane, cw) -> cw`` and ``comp_code(host, plane, "G41") -> "G42"``.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field
from typing import Any

from nc.alarms import NcAlarm
from nc.program.blocks import Block, Word

PLANE_AXES = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}


@dataclass
class TransformStack:
    mirror: dict[str, float] = field(default_factory=dict)  # axis -> mirror centre (work)
    scale: dict[str, float] = field(default_factory=dict)  # axis -> ratio
    scale_center: dict[str, float] = field(default_factory=dict)
    rot_angle: float = 0.0  # degrees, CCW positive in the rotation plane
    rot_center: tuple[float, float] = (0.0, 0.0)
    rot_plane: tuple[str, str] | None = None

    @property
    def active(self) -> bool:
        return bool(self.mirror or self.scale or self.rot_plane)

    # ---- points ------------------------------------------------------------------------------
    def apply(self, work: dict[str, float]) -> dict[str, float]:
        out = dict(work)
        for a, c in self.mirror.items():
            if a in out:
                out[a] = 2.0 * c - out[a]
        for a, k in self.scale.items():
            if a in out:
                c = self.scale_center.get(a, 0.0)
                out[a] = c + (out[a] - c) * k
        if self.rot_plane is not None:
            a1, a2 = self.rot_plane
            if a1 in out and a2 in out:
                th = math.radians(self.rot_angle)
                cx, cy = self.rot_center
                dx, dy = out[a1] - cx, out[a2] - cy
                out[a1] = cx + dx * math.cos(th) - dy * math.sin(th)
                out[a2] = cy + dx * math.sin(th) + dy * math.cos(th)
        return out

    def inverse(self, work: dict[str, float]) -> dict[str, float]:
        out = dict(work)
        if self.rot_plane is not None:
            a1, a2 = self.rot_plane
            if a1 in out and a2 in out:
                th = -math.radians(self.rot_angle)
                cx, cy = self.rot_center
                dx, dy = out[a1] - cx, out[a2] - cy
                out[a1] = cx + dx * math.cos(th) - dy * math.sin(th)
                out[a2] = cy + dx * math.sin(th) + dy * math.cos(th)
        for a, k in self.scale.items():
            if a in out and k != 0:
                c = self.scale_center.get(a, 0.0)
                out[a] = c + (out[a] - c) / k
        for a, c in self.mirror.items():
            if a in out:
                out[a] = 2.0 * c - out[a]
        return out

    def reflected(self, plane: tuple[str, str]) -> bool:
        """Odd number of reflections in the plane: arcs and compensation side swap."""
        n = sum(1 for a in plane if a in self.mirror)
        n += sum(1 for a in plane if self.scale.get(a, 1.0) < 0)
        return n % 2 == 1

    def check_arc(self, plane: tuple[str, str]) -> None:
        k1, k2 = abs(self.scale.get(plane[0], 1.0)), abs(self.scale.get(plane[1], 1.0))
        if abs(k1 - k2) > 1e-12:
            raise NcAlarm(0x025F, "an arc cannot be scaled with different ratios on its two plane axes")

    def radius_scale(self, plane: tuple[str, str]) -> float:
        return abs(self.scale.get(plane[0], 1.0))


_stacks: "weakref.WeakKeyDictionary[Any, TransformStack]" = weakref.WeakKeyDictionary()


def stack(host: Any) -> TransformStack:
    try:
        st = _stacks.get(host)  # asked on every block: build a stack only the first time
        if st is None:
            st = _stacks[host] = TransformStack()
        return st
    except TypeError:
        if not hasattr(host, "_transform_stack"):
            host._transform_stack = TransformStack()
        return host._transform_stack


def _ratio(w: Word) -> float:
    """P/I/J/K ratio: 0.001 units without a decimal point (P100 = 0.1), as written with one."""
    return w.value if w.has_point else w.value * 0.001


def _angle(host: Any, w: Word) -> float:
    if w.has_point or host.profile.param("N8.018 Bit10"):
        return w.value
    return w.value * 0.001


def _plane(host: Any) -> tuple[str, str]:
    return PLANE_AXES.get(int(host.state.plane), ("X", "Y"))


def modal(host: Any, fn: str, block: Block) -> None:
    ts = stack(host)
    here = inverse(host, host.work_position())
    if fn == "scale":
        p = block.get("P")
        ratio = _ratio(p) if p is not None else None
        per_axis = {"X": block.get("I"), "Y": block.get("J"), "Z": block.get("K")}
        ts.scale = {}
        ts.scale_center = {}
        for a in host.profile.axes:
            w = per_axis.get(a)
            k = _ratio(w) if w is not None else ratio
            if k is None:
                k = 1.0
            if k == 0 or abs(k) > 999.999:
                raise NcAlarm(0x0223, f"scaling ratio {k:g} out of range (0.001–999.999)")
            if abs(k - 1.0) > 1e-12:
                ts.scale[a] = k
            cw = block.get(a)
            ts.scale_center[a] = host.distance(cw, a) if cw is not None else here.get(a, 0.0)
        if p is None and not any(per_axis.values()):
            raise NcAlarm(0x0222, "G51 needs P (all axes) or I/J/K (per axis)")
    elif fn == "scale_off":
        ts.scale, ts.scale_center = {}, {}
    elif fn == "mirror":
        words = [w for w in block.words if w.letter in host.profile.axes]
        if not words:
            raise NcAlarm(0x0222, "mirror needs the axis and its centre (e.g. X0.)")
        for w in words:
            ts.mirror[w.letter] = host.distance(w, w.letter)
    elif fn == "mirror_off":
        words = [w for w in block.words if w.letter in host.profile.axes]
        if not words:
            ts.mirror = {}
        for w in words:
            ts.mirror.pop(w.letter, None)
    elif fn == "G68":
        plane = _plane(host)
        r = block.get("R")
        ang = _angle(host, r) if r is not None else 0.0
        if abs(ang) > 360.0:
            raise NcAlarm(0x0223, f"rotation angle {ang:g} beyond ±360°")
        if not host.state.absolute and ts.rot_plane is not None:
            ang += ts.rot_angle  # G91: incremental angle (decisions A58)
        c1, c2 = block.get(plane[0]), block.get(plane[1])
        cx = host.distance(c1, plane[0]) if c1 is not None else here.get(plane[0], 0.0)
        cy = host.distance(c2, plane[1]) if c2 is not None else here.get(plane[1], 0.0)
        ts.rot_plane, ts.rot_angle, ts.rot_center = plane, ang, (cx, cy)
    elif fn == "G69":
        ts.rot_plane, ts.rot_angle, ts.rot_center = None, 0.0, (0.0, 0.0)


def apply(host: Any, work: dict[str, float]) -> dict[str, float]:
    return stack(host).apply(work)


def inverse(host: Any, work: dict[str, float]) -> dict[str, float]:
    return stack(host).inverse(work)


def arc_cw(host: Any, plane: tuple[str, str], cw: bool) -> bool:
    ts = stack(host)
    if ts.scale:
        ts.check_arc(plane)
    return (not cw) if ts.reflected(plane) else cw


def radius_scale(host: Any, plane: tuple[str, str]) -> float:
    """The ratio an arc's R is scaled by under G51 (equal on both plane axes, else arc_cw raised 0x025F)."""
    return stack(host).radius_scale(plane)


def comp_code(host: Any, plane: tuple[str, str], code: str | None) -> str | None:
    if code not in ("G41", "G42") or not stack(host).reflected(plane):
        return code
    return "G42" if code == "G41" else "G41"


def reset(host: Any) -> None:
    """M02/M30/reset cancel scaling, mirror and rotation."""
    stack(host).__init__()
