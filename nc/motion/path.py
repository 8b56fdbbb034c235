"""Path geometry of one move as a function of path length s, evaluated for many s at once."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115; this module since bench B136)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.interp.arcs import sweep
from nc.moves import Move

_NO_CENTER = (0.0, 0.0)


@dataclass
class _Fields:  # Segment's constructor arguments, in order: the dataclasses that extend it take them as theirs
    axes: tuple[str, ...]
    start: np.ndarray
    end: np.ndarray
    length: float
    kind: str  # "line" or "arc"
    # arc data (plane axis indices, centre in the plane, radius, start angle, sweep)
    i1: int = 0
    i2: int = 0
    center: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.0
    a0: float = 0.0
    theta: float = 0.0
    arc_len: float = 0.0
    # A line's unit direction as plain floats, computed once: the look-ahead reads it per
    # junction and per block, where numpy calls on 3-element arrays cost more than the math.
    _dir: tuple[float, ...] | None = None
    _cos: tuple[float, ...] | None = None  # |_dir|: the direction cosines, for the block limits


class Segment:
    """A line or a helical arc through the channel axes, parametrised by path length.

    Compiled, an extension type (path.pxd, issue 17): one is made per block. Its end points are numpy arrays
    (`start`, `end`) or lists of floats (`start_floats`, `end_floats`, never changed in place), each made from
    the other when first read: a line from the run feed comes with lists, and the planner's per-block readers
    (the cruise's rows) take lists, so most blocks never make an array (two `np.array` calls a block,
    bench B156). The fields as `_Fields`' (ClothoidBlend and SplineSpan are dataclasses extending it)."""

    __dataclass_fields__ = _Fields.__dataclass_fields__
    __dataclass_params__ = _Fields.__dataclass_params__

    def __init__(self, axes: tuple[str, ...], start: np.ndarray, end: np.ndarray, length: float, kind: str,
                 i1: int = 0, i2: int = 0, center: tuple[float, float] = (0.0, 0.0), radius: float = 0.0,
                 a0: float = 0.0, theta: float = 0.0, arc_len: float = 0.0,
                 _dir: tuple[float, ...] | None = None, _cos: tuple[float, ...] | None = None) -> None:
        self.axes = axes
        self._pa = start
        self._pb = end
        self._fa = None
        self._fb = None
        self.length = length
        self.kind = kind
        self.i1 = i1
        self.i2 = i2
        self.center = center
        self.radius = radius
        self.a0 = a0
        self.theta = theta
        self.arc_len = arc_len
        self._dir = _dir
        self._cos = _cos

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(axes={self.axes!r}, start={self.start!r}, end={self.end!r}, "
                f"length={self.length!r}, kind={self.kind!r})")

    @property
    def start(self) -> np.ndarray:
        if self._pa is None:
            self._pa = np.array(self._fa)
        return self._pa

    @start.setter
    def start(self, value: np.ndarray) -> None:
        self._pa = value
        self._fa = None

    @property
    def end(self) -> np.ndarray:
        if self._pb is None:
            self._pb = np.array(self._fb)
        return self._pb

    @end.setter
    def end(self, value: np.ndarray) -> None:
        self._pb = value
        self._fb = None

    @property
    def start_floats(self) -> list[float]:
        """`start.tolist()`, kept (the list is shared: never change it in place)."""
        if self._fa is None:
            self._fa = self._pa.tolist()
        return self._fa

    @start_floats.setter
    def start_floats(self, value: list[float]) -> None:
        self._fa = value
        self._pa = None

    @property
    def end_floats(self) -> list[float]:
        """`end.tolist()`, kept (the list is shared: never change it in place)."""
        if self._fb is None:
            self._fb = self._pb.tolist()
        return self._fb

    @staticmethod
    def line_of(axes: tuple[str, ...], ls: list[float], le: list[float], length: float,
                d: list[float]) -> "Segment":
        """`line_segment` (kept as the class's own)."""
        return line_segment(axes, ls, le, length, d)

    @classmethod
    def of(cls, move: Move, axes: tuple[str, ...]) -> "Segment":
        start, end = move.start, move.end
        ls = [float(start.get(a, 0.0)) for a in axes]
        le = [float(end.get(a, 0.0)) for a in axes]
        if move.kind != "arc" or move.center is None:
            length = math.dist(ls, le)
            if length > 0.0:
                d = [(q - p) / length for p, q in zip(ls, le)]
                if cls is Segment:
                    return line_segment(axes, ls, le, length, d)
                return cls(axes, np.array(ls), np.array(le), length, "line", _dir=tuple(d),
                           _cos=tuple([abs(x) for x in d]))
            d = (0.0,) * len(axes)
            return cls(axes, np.array(ls), np.array(le), length, "line", _dir=d, _cos=d)
        # Python floats make float64 arrays: no dtype argument to parse (issue 17)
        s = np.array(ls)
        e = np.array(le)
        p1, p2 = move.plane
        i1, i2 = axes.index(p1), axes.index(p2)
        c = (move.center[p1], move.center[p2])
        theta = sweep((s[i1], s[i2]), (e[i1], e[i2]), c, move.dir == "cw")
        if move.turns:
            theta += math.copysign(2.0 * math.pi * float(move.turns), theta)
        r = math.hypot(s[i1] - c[0], s[i2] - c[1])
        a0 = math.atan2(s[i2] - c[1], s[i1] - c[0])
        arc_len = abs(theta) * r
        lin = e - s
        lin[i1] = lin[i2] = 0.0
        length = math.hypot(arc_len, float(np.linalg.norm(lin)))
        return cls(axes, s, e, length, "arc", i1, i2, c, r, a0, theta, arc_len)

    def points(self, s: np.ndarray) -> np.ndarray:
        """Positions (len(s) × axes) at path lengths s."""
        s = np.asarray(s, dtype=float)
        if self.length <= 0.0:
            return np.repeat(self.start[None, :], len(s), axis=0)
        u = (s / self.length)[:, None]
        p = self.start[None, :] + u * (self.end - self.start)[None, :]
        if self.kind == "arc":
            ang = self.a0 + self.theta * u[:, 0]
            p[:, self.i1] = self.center[0] + self.radius * np.cos(ang)
            p[:, self.i2] = self.center[1] + self.radius * np.sin(ang)
        return p

    def unit_tangent(self, at_end: bool) -> np.ndarray:
        """Direction of travel (per unit path length) at the start or end."""
        if self.length <= 0.0:
            return np.zeros(len(self.axes))
        d = (self.end - self.start) / self.length
        if self.kind == "arc":
            ang = self.a0 + (self.theta if at_end else 0.0)
            k = self.theta * self.radius / self.length
            d = d.copy()
            d[self.i1] = -math.sin(ang) * k
            d[self.i2] = math.cos(ang) * k
        return d

    def tangent(self, at_end: bool) -> tuple[float, ...]:
        """unit_tangent as plain floats (cached for lines)."""
        if self._dir is not None:
            return self._dir
        return tuple(self.unit_tangent(at_end).tolist())

    def direction_cosines(self) -> tuple[float, ...]:
        """max_direction_cosines as plain floats."""
        if self._cos is not None:
            return self._cos
        return tuple(self.max_direction_cosines().tolist())

    def curvature_vector(self, at_end: bool) -> np.ndarray:
        """d²(position)/ds² at the start or end: zero on a line, towards the centre on an arc."""
        c = np.zeros(len(self.axes))
        if self.kind != "arc" or self.length <= 0.0 or self.radius <= 0.0:
            return c
        ang = self.a0 + (self.theta if at_end else 0.0)
        k = self.theta * self.radius / self.length  # d(angle·r)/ds
        mag = (k * k) / self.radius
        c[self.i1] = -math.cos(ang) * mag
        c[self.i2] = -math.sin(ang) * mag
        return c

    def max_direction_cosines(self) -> np.ndarray:
        """Largest |d axis / d s| over the segment, per axis (for projecting axis limits)."""
        if self.length <= 0.0:
            return np.zeros(len(self.axes))
        d = np.abs((self.end - self.start) / self.length)
        if self.kind == "arc":
            k = abs(self.theta) * self.radius / self.length
            d[self.i1] = d[self.i2] = k  # a swept arc may pass through any direction: be safe
            if abs(self.theta) < math.pi:
                a = np.linspace(self.a0, self.a0 + self.theta, 33)
                d[self.i1] = float(np.max(np.abs(np.sin(a)))) * k
                d[self.i2] = float(np.max(np.abs(np.cos(a)))) * k
        return d


@cython.locals(seg=Segment)
def line_segment(axes: tuple[str, ...], ls: list[float], le: list[float], length: float,
                 d: list[float]) -> Segment:
    """A line from its start, end, length (math.dist) and unit direction worked out already (the run
    feed's `RunFeed.geom`, issue 17): the segment `of` makes from the same move, bit for bit. The lists are
    kept as they are (shared with the run feed's state: never changed in place)."""
    seg = Segment.__new__(Segment)  # compiled: the type's slot alone, no __init__'s arguments to parse, and
    # (typed) each field a store into its struct, not a setattr (bench B156)
    seg.axes = axes
    seg._pa = None
    seg._pb = None
    seg._fa = ls
    seg._fb = le
    seg.length = length
    seg.kind = "line"
    seg.i1 = 0
    seg.i2 = 0
    seg.center = _NO_CENTER
    seg.radius = 0.0
    seg.a0 = 0.0
    seg.theta = 0.0
    seg.arc_len = 0.0
    if len(d) == 3:  # spelt out (once per push)
        d0, d1, d2 = d
        seg._dir = (d0, d1, d2)
        seg._cos = (abs(d0), abs(d1), abs(d2))
    else:
        seg._dir = tuple(d)
        seg._cos = tuple([abs(x) for x in d])
    return seg
