"""Software travel limits, checked when the channel hands a move to the planner.

Two segments, as NC5 §3.8.3.7 (G10 L21) numbers them:

- 1st segment: the bench's axis ``soft_limits`` (machine coordinates), overridden per axis by
  ``G10 L21 P1`` (positive) / ``P2`` (negative); crossing it raises 0x0A01.
- 2nd segment: only when a program sets it with ``G10 L21 P3`` / ``P4``; crossing raises 0x0A03.

G10 L21 values are stored by the interpreter in ``profile.params["soft limit P<n> <axis>"]`` as
programmed, so an X value on a lathe in diameter mode is a diameter and is halved here (machine X
is a radius).  The check runs on the whole path of a move — an arc that bulges past a limit is
caught even when both of its end points lie inside — so a move that would cross never starts.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

from nc.alarms import Alarm
from nc.moves import Move

_EPS = 1e-9
_AWAY = 1e-6  # mm: a manual move left the limit position it was clamped on


@dataclass
class SoftLimits:
    first: dict[str, tuple[float, float]] = field(default_factory=dict)  # bench axis config, machine units
    params: Mapping[str, float] = field(default_factory=dict)  # the interpreter's profile params (G10 L21)
    diameter_axes: tuple[str, ...] = ()
    disabled: set[str] = field(default_factory=set)  # axes whose 1st segment is off (MLC M2x368)

    @classmethod
    def for_bench(cls, bench, profile=None) -> "SoftLimits":
        first = {a.name: a.soft_limits for a in bench.axes if a.soft_limits is not None}
        if profile is None:
            return cls(first)
        return cls(first, profile.params, tuple(profile.diameter_axes))

    def window(self, axis: str, segment: int) -> tuple[float | None, float | None]:
        """(lower, upper) of one segment for one axis, machine coordinates; None where unset."""
        lo: float | None
        hi: float | None
        lo, hi = self.first.get(axis, (None, None)) if segment == 1 else (None, None)
        scale = 0.5 if axis in self.diameter_axes else 1.0
        pos = self.params.get(f"soft limit {2 * segment - 1} {axis}")
        neg = self.params.get(f"soft limit {2 * segment} {axis}")
        if pos is not None:
            hi = pos * scale
        if neg is not None:
            lo = neg * scale
        return lo, hi

    def __post_init__(self) -> None:
        # axis -> the G10 L21 parameter names P1-P4 as `window` reads them, and the axis's scale (`_inside`)
        self._names: dict[str, tuple[str, str, str, str, float]] = {}
        self._all: set[str] = set()  # the names of all axes in `_names`, in one set
        # `_inside`'s box: axis (those in `_names`) -> the bench's 1st segment widened by _EPS (+-inf where it
        # has none), or False when params hold a G10 L21 value of any of these axes; found
        # for the params, their length and the bench's segments it names (decisions bench B158)
        self._box: dict[str, tuple[float, float]] | bool = False
        self._box_of: tuple[object, int, object] | None = None
        # `check`'s first test: (params, their length, first, the box's test as straight-line code), made with the
        # box (`_new_box`), None while there is none (decisions bench B173)
        # and the test of an end alone (`line_test`)
        self._fast: tuple[object, int, object, Callable[[dict, dict], bool], Callable[[dict], bool]] | None = None

    def _keys(self, axis: str) -> tuple[str, str, str, str, float]:
        k = self._names[axis] = (f"soft limit 1 {axis}", f"soft limit 2 {axis}", f"soft limit 3 {axis}",
                                 f"soft limit 4 {axis}", 0.5 if axis in self.diameter_axes else 1.0)
        self._all.update(k[:4])
        self._box_of = None  # the box is found again with this axis
        self._fast = None
        return k

    def _new_box(self) -> dict[str, tuple[float, float]] | bool:
        params, first = self.params, self.first
        self._box_of = (params, len(params), first)
        self._fast = None
        if not params.keys().isdisjoint(self._all):
            self._box = False
        else:
            box: dict[str, tuple[float, float]] = {}
            for a in self._names:
                lo, hi = first.get(a, (None, None))
                box[a] = (-math.inf if lo is None else lo - _EPS, math.inf if hi is None else hi + _EPS)
            self._box = box
            self._fast = (params, len(params), first, *_box_test(box))
        return self._box

    def _inside(self, move: Move) -> bool:
        """True when a line (rapid, thread) with the same axes at both ends stays inside both segments:
        `check` finds no alarm for it (issue 17: the channel asks for every move; `window`'s names
        formatted and the path ranges built were some 10 us a move). False: not known, `check` decides."""
        start, end = move.start, move.end
        if (move.kind == "arc" and move.center) or len(start) != len(end):
            return False
        first, params, disabled = self.first, self.params, self.disabled
        box = self._box
        of = self._box_of
        if of is None or of[0] is not params or of[1] != len(params) or of[2] is not first:
            box = self._new_box()
        if box and not disabled:
            # no G10 L21 value for any axis seen and no axis's 1st segment off (a CAM run's case, issue 17): the
            # bench's 1st segment alone, both ends inside it (as the min and max of the two are below: a NaN end
            # passes there too), without the loop's 12 look-ups. Each axis of `end` in `start` (as many): the same
            # axes at both ends.
            try:
                for a, e in end.items():
                    s = start[a]
                    lo, hi = box[a]  # type: ignore[index]  # KeyError: an axis not seen, its names made below
                    if s < lo or s > hi or e < lo or e > hi:
                        return False
                return True
            except KeyError:
                pass
        if start.keys() != end.keys():
            return False
        names = self._names
        for a, e in end.items():
            s = start[a]
            mn = e if e < s else s  # min(s, e) and max(s, e) as `_path_ranges` takes them
            mx = e if e > s else s
            p1, n1, p2, n2, scale = names.get(a) or self._keys(a)
            if a not in disabled:
                lo, hi = first.get(a, (None, None))
                v = params.get(p1)
                if v is not None:
                    hi = v * scale
                v = params.get(n1)
                if v is not None:
                    lo = v * scale
                if (hi is not None and mx > hi + _EPS) or (lo is not None and mn < lo - _EPS):
                    return False
            v = params.get(p2)
            if v is not None and mx > v * scale + _EPS:
                return False
            v = params.get(n2)
            if v is not None and mn < v * scale - _EPS:
                return False
        return True

    def line_test(self) -> tuple[Callable[[dict, dict], bool], Callable[[dict], bool], Mapping[str, float], int] | None:
        """`check`'s first test for a run of reads (hil.stretch_reads.Ahead.peek, issue 17, decisions bench B193):
        (the box's straight-line test of a start and an end, its test of an end alone, the params, their length) while
        that test is `check`'s first one (the params, their length and the bench's segments those the box was found
        for, no axis's 1st segment off), None when `check` must decide. A line or rapid it answers True for is one
        `check` finds no alarm for, as long as the params keep that length (a G10 L21 value adds a key: the box no
        longer holds); so is one whose start equals an end the test of an end found inside. False is "not known"."""
        fast = self._fast
        params = self.params
        if fast is None or self.disabled or fast[0] is not params or fast[1] != len(params) or fast[2] is not self.first:
            return None
        return fast[3], fast[4], params, fast[1]

    def check(self, move: Move) -> Alarm | None:
        """The limit alarm this move would raise, or None when its whole path stays inside."""
        kind = move.kind
        if kind == "dwell":
            return None
        fast = self._fast
        if fast is not None and kind != "arc" and not self.disabled:
            # a line inside the box (`_inside`'s first case, a CAM run's every move): one call of straight-line
            # code while the params and the bench's segments are those the box was found for (issue 17)
            params = self.params
            try:
                if fast[0] is params and fast[1] == len(params) and fast[2] is self.first \
                        and fast[3](move.start, move.end):
                    return None
            except KeyError:  # as many axes, not the box's: `_inside` decides
                pass
        if self._inside(move):
            return None
        ranges = _path_ranges(move)
        for segment, code in ((1, 0x0A01), (2, 0x0A03)):
            for axis, (mn, mx) in ranges.items():
                if segment == 1 and axis in self.disabled:
                    continue
                lo, hi = self.window(axis, segment)
                side = None
                if hi is not None and mx > hi + _EPS:
                    side, value, lim = "+", mx, hi
                elif lo is not None and mn < lo - _EPS:
                    side, value, lim = "-", mn, lo
                if side is not None:
                    return Alarm(code, f"software limit {segment} {side} of axis {axis}: the move would reach "
                                       f"{value:.4f}, limit {lim:.4f} (machine coordinates); the move was not started",
                                 line=move.line, block=move.block, program=move.program, axis=axis)
        return None


def _box_test(box: dict[str, tuple[float, float]]) -> tuple[Callable[[dict, dict], bool], Callable[[dict], bool]]:
    """`_inside`'s box test for these axes as straight-line code: True when both ends hold as many axes as the box,
    each inside it (a NaN passes, as `_inside`'s loop lets it: `check` finds no alarm for it either; an axis of
    another name is "not known" too). The bounds are literals, each test one compare-and-branch. False is "not known":
    `_inside` decides."""
    def lit(v: float) -> str:
        return "1e999" if v == math.inf else "-1e999" if v == -math.inf else repr(v)
    src = ["def inside(s, e):", f"    if len(s) != {len(box)} or len(e) != {len(box)}:", "        return False",
           "    try:"] + ([] if box else ["        pass"])
    for p in "se":
        for a, (lo, hi) in box.items():
            src += [f"        v = {p}[{a!r}]", f"        if v < {lit(lo)} or v > {lit(hi)}:", "            return False"]
    src += ["    except KeyError:  # an axis of another name", "        return False", "    return True"]
    # the same test of an end alone (`end_inside`): a move whose start is the end of one found inside needs no more
    src += ["def end_inside(e):", f"    if len(e) != {len(box)}:", "        return False", "    try:"]
    src += [] if box else ["        pass"]
    for a, (lo, hi) in box.items():
        src += [f"        v = e[{a!r}]", f"        if v < {lit(lo)} or v > {lit(hi)}:", "            return False"]
    src += ["    except KeyError:", "        return False", "    return True"]
    space: dict = {}
    exec(compile("\n".join(src) + "\n", "<soft-limit box>", "exec"), space)
    return space["inside"], space["end_inside"]


def _path_ranges(move: Move) -> dict[str, tuple[float, float]]:
    """Per axis (min, max) of the machine-coordinate path of a line, rapid, thread or arc."""
    axes: Iterable[str] = set(move.start) | set(move.end)
    r = {a: (min(move.start.get(a, move.end.get(a, 0.0)), move.end.get(a, move.start.get(a, 0.0))),
             max(move.start.get(a, move.end.get(a, 0.0)), move.end.get(a, move.start.get(a, 0.0)))) for a in axes}
    if move.kind != "arc" or not move.center:
        return r
    a1, a2 = move.plane
    c1, c2 = move.center.get(a1, 0.0), move.center.get(a2, 0.0)
    s1, s2 = move.start.get(a1, 0.0) - c1, move.start.get(a2, 0.0) - c2
    e1, e2 = move.end.get(a1, 0.0) - c1, move.end.get(a2, 0.0) - c2
    radius = math.hypot(s1, s2)
    t0, t1 = math.atan2(s2, s1), math.atan2(e2, e1)
    ccw = move.dir == "ccw"
    sweep = (t1 - t0) % (2 * math.pi) if ccw else (t0 - t1) % (2 * math.pi)
    if sweep < 1e-12 or move.turns:
        sweep = 2 * math.pi  # full circle (or a helix with extra turns)
    # The plane axes reach an extreme at the quadrant angles the arc sweeps through.
    for k in range(4):
        q = k * math.pi / 2
        d = (q - t0) % (2 * math.pi) if ccw else (t0 - q) % (2 * math.pi)
        if d <= sweep + 1e-12:
            p1, p2 = c1 + radius * math.cos(q), c2 + radius * math.sin(q)
            for ax, v in ((a1, p1), (a2, p2)):
                lo, hi = r.get(ax, (v, v))
                r[ax] = (min(lo, v), max(hi, v))
    return r


@dataclass
class ManualLimitLatch:
    """The soft-limit alarms of the manual modes (JOG, INC, MPG), App. A 0x0A01-0x0A04.

    A manual move is clamped at the limit (nc.manual), so there the axis *reaches* the limit position: 0x0A01
    (1st segment) / 0x0A03 (2nd) is raised and latched. "The machine must move away from the limit position before
    system reset": a reset while the axis still stands on it leaves the alarm; once the axis has moved away, 0x0A02
    / 0x0A04 ("the status ... needs to be cleared") is raised, and the next reset clears the latch."""

    latched: dict[str, tuple[int, str, bool]] = field(default_factory=dict)  # axis -> (segment, side, moved away)

    @staticmethod
    def window(limits: SoftLimits, axis: str, first_on: bool) -> tuple[tuple[float, int] | None, tuple[float, int] | None]:
        """The tighter of both segments per side, as ((lower, segment) | None, (upper, segment) | None)."""
        lows, highs = [], []
        for seg in ((1, 2) if first_on else (2,)):
            lo, hi = limits.window(axis, seg)
            if lo is not None:
                lows.append((lo, seg))
            if hi is not None:
                highs.append((hi, seg))
        return (max(lows) if lows else None), (min(highs, key=lambda t: t[0]) if highs else None)

    def update(self, axis: str, position: float, low: tuple[float, int] | None,
               high: tuple[float, int] | None, clamped: bool) -> Alarm | None:
        """After a manual step (`clamped`: the step was cut at a limit): the alarm this axis raises now, or None."""
        held = self.latched.get(axis)
        if held is not None:
            seg, side, away = held
            bound = low if side == "-" else high
            if not away and (bound is None or abs(position - bound[0]) > _AWAY):
                self.latched[axis] = (seg, side, True)
                return Alarm(0x0A02 if seg == 1 else 0x0A04, f"software limit {seg} {side} of axis {axis}: moved away "
                             f"to {position:.4f}; reset to clear", axis=axis)
            return None
        if not clamped:  # a program may end on a limit; only a manual move cut by it has *reached* it
            return None
        for bound, side in ((low, "-"), (high, "+")):
            if bound is not None and abs(position - bound[0]) <= _EPS:
                self.latched[axis] = (bound[1], side, False)
                return Alarm(0x0A01 if bound[1] == 1 else 0x0A03, f"software limit {bound[1]} {side} of axis "
                             f"{axis}: the axis reached the limit position {bound[0]:.4f} in manual mode; move it "
                             f"away before reset", axis=axis)
        return None

    def reset(self) -> list[Alarm]:
        """A reset: latches whose axis moved away are cleared; the alarms of axes still on the limit stay."""
        self.latched = {a: v for a, v in self.latched.items() if not v[2]}
        return [Alarm(0x0A01 if seg == 1 else 0x0A03, f"software limit {seg} {side} of axis {a}: still on the "
                      f"limit position, move it away before reset", axis=a) for a, (seg, side, _) in self.latched.items()]
