"""Modal state of one NC channel (32 G-code groups) and its coordinate frames."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from nc.profiles import Profile

PLANES: dict[int, tuple[str, str]] = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}
N_EXT_WCS = 64  # G54 P1–P64 (N§3.6.5)


def power_on_groups(profile: Profile) -> dict[int, float]:
    """Group number -> G code at power-on (decisions A3: the manual's bold defaults are lost).

    Values are the code numbers *of this profile's dialect* (type A lathe: G98 = feed/min)."""
    if not profile.is_lathe:
        return {1: 0, 2: 17, 3: 90, 5: 94, 6: 21, 7: 40, 8: 49, 9: 80, 10: 98, 11: 50, 12: 54, 13: 64,
                14: 67, 15: 69, 16: 15, 17: 97, 18: 25, 31: 0}
    t = profile.lathe_type
    g = {1: 0, 2: 18, 6: 21 if t != "C" else 71, 7: 40, 9: 80, 12: 54, 13: 64, 14: 67, 17: 97, 18: 50.1, 31: 0}
    if t == "A":
        g[5] = 99
    else:
        g.update({3: 90, 5: 95, 10: 98, 11: 50})
    return g


@dataclass
class ModalState:
    groups: dict[int, float] = field(default_factory=dict)  # group -> code as programmed
    motion: float = 0  # group 01 function: 0, 1, 2, 3, 2.4, 3.4, 32 (thread), 34
    plane: int = 18  # group 02
    inch: bool = False  # group 06
    per_rev: bool = True  # group 05
    absolute: bool = True  # group 03 (types B/C, mill)
    exact_stop_modal: bool = False  # G61
    feed: float | None = None  # F as programmed (mm/min or mm/rev, or inch)
    spindle_speed: float = 0.0  # S, rpm (or m/min under G96)
    spindle_max: float | None = None  # G50 S / G92 S clamp
    css: bool = False  # G96
    surface_speed: float = 0.0  # the last S under G96 (m/min): `G96` without S resumes it (Fanuc)
    spindle_dir: int = 0  # +1 M03, -1 M04, 0 M05
    tool: int = 0  # T as programmed
    tool_offset: int = 0  # lathe: offset number (last two digits of T)
    wcs: int = 0  # 0 = G54 ... 5 = G59, 6+ = G54 P1...
    comp: int = 40  # group 07: 40 / 41 / 42
    d_number: int = 0  # D (mill radius comp)
    length_comp: int = 49  # group 08: 43 / 44 / 49
    h_number: int = 0
    cycle: str | None = None  # active modal cycle function name (group 09)
    cycle_return: int = 98  # group 10 (mill, lathe B/C): 98 initial level, 99 R level
    polar: bool = False  # G16
    scaling: bool = False  # G51
    rotation: bool = False  # G68
    macro_modal: bool = False  # G66

    def copy(self) -> "ModalState":
        """An independent copy: every field is a number, flag or string but the groups dict."""
        st = object.__new__(type(self))  # copy.copy without its reduce protocol (a twin per lathe cycle)
        st.__dict__.update(self.__dict__)
        st.groups = dict(self.groups)
        return st

    @classmethod
    def power_on(cls, profile: Profile) -> "ModalState":
        g = power_on_groups(profile)
        st = cls(groups=g, plane=int(g[2]))
        st.per_rev = profile.is_lathe
        return st


@dataclass
class Frames:
    """Machine = work + external offset (G10 L2 P0) + work offset (G54–G59, G54 P1–P64)
    + local shift (G52) + coordinate shift (G92/G50) + tool offset.  All in machine units
    (a lathe X in radius)."""

    axes: tuple[str, ...]
    work_offsets: list[dict[str, float]] = field(default_factory=list)  # 0..5 G54–G59, 6.. P1–P64
    external: dict[str, float] = field(default_factory=dict)
    local_shift: dict[str, float] = field(default_factory=dict)
    set_shift: dict[str, float] = field(default_factory=dict)
    tool_shift: dict[str, float] = field(default_factory=dict)

    _memo: ClassVar[tuple | None] = None  # (wcs, axes, the five offsets, origins) of the last call
    _shared: ClassVar[bool] = False  # work_offsets is shared with a copy: `writable_offsets` copies it first

    def __post_init__(self) -> None:
        if not self.work_offsets:
            self.work_offsets = [{a: 0.0 for a in self.axes} for _ in range(6 + N_EXT_WCS)]

    def copy(self) -> "Frames":
        """An independent copy (what copy.deepcopy gives, at a tenth of its cost: a lathe cycle's
        contour is interpreted on a copy of the interpreter, issue 16). The 70 work offsets are shared
        until either side writes one: writers take them from `writable_offsets`."""
        twin = Frames(self.axes, self.work_offsets, self.external.copy(),
                      self.local_shift.copy(), self.set_shift.copy(), self.tool_shift.copy())
        twin._memo = self._memo  # compared by value and never changed: valid for the equal copy too
        twin._shared = self._shared = True
        return twin

    def writable_offsets(self) -> list[dict[str, float]]:
        """`work_offsets` to change in place (G10 L2/L20, #5221…): this frame's own, copied first if
        a copy shares them."""
        if self._shared:
            self.work_offsets = list(map(dict.copy, self.work_offsets))
            self._shared = False
        return self.work_offsets

    def origins(self, wcs: int, axes: tuple[str, ...]) -> dict[str, float]:
        """`origin` of every axis at once (the interpreter's per-block coordinate conversion). The dict
        may be shared with the next call: read it, never change it."""
        e, w, lo, s, t = self.external, self.work_offsets[wcs], self.local_shift, self.set_shift, self.tool_shift
        # The last result again while the offsets it came from hold the same values (they are plain
        # dicts, changed in place by G10, G92, #5221…; compared by value, a NaN never matches). Equal
        # values give the same sums bit for bit: a sum can only be -0.0 where all five terms are -0.0,
        # so equal dicts differing in the sign of a zero matter only where `e` holds a zero.
        memo = self._memo
        if memo is not None and memo[0] == wcs and memo[1] == axes and memo[2] == w and memo[3] == e \
                and memo[4] == lo and memo[5] == s and memo[6] == t:
            return memo[7]
        if not (e or lo or s or t):  # the usual case; 0.0 + w is the sum below bit for bit (even for -0.0)
            out = {a: 0.0 + w.get(a, 0.0) for a in axes}
        else:
            out = {a: e.get(a, 0.0) + w.get(a, 0.0) + lo.get(a, 0.0) + s.get(a, 0.0) + t.get(a, 0.0) for a in axes}
        self._memo = None if 0 in e.values() else (wcs, axes, dict(w), dict(e), dict(lo), dict(s), dict(t), out)
        return out

    def origin(self, wcs: int, axis: str) -> float:
        return (self.external.get(axis, 0.0) + self.work_offsets[wcs].get(axis, 0.0)
                + self.local_shift.get(axis, 0.0) + self.set_shift.get(axis, 0.0)
                + self.tool_shift.get(axis, 0.0))
