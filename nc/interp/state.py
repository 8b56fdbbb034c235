"""Modal state of one NC channel and its coordinate frames."""

from __future__ import annotations

from dataclasses import dataclass, field

from nc.profiles import Profile

PLANES: dict[int, tuple[str, str]] = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}


@dataclass
class ModalState:
    motion: int = 0  # group 01: 0, 1, 2, 3 (G00/G01/G02/G03)
    plane: int = 18  # group 02
    inch: bool = False  # group 06: G20 / G21
    per_rev: bool = True  # G99 (type A) / G95: feed per revolution
    absolute: bool = True  # G90 / G91 (types B and C, mill)
    exact_stop_modal: bool = False  # G61
    feed: float | None = None  # F as programmed (mm/min or mm/rev)
    spindle_speed: float = 0.0  # S, rpm
    spindle_dir: int = 0  # +1 M03, -1 M04, 0 M05
    tool: int = 0  # T number as programmed
    wcs: int = 0  # 0 = G54 ... 5 = G59

    @classmethod
    def power_on(cls, profile: Profile) -> "ModalState":
        if profile.is_lathe:
            return cls(motion=0, plane=18, per_rev=True, absolute=True)
        return cls(motion=0, plane=17, per_rev=False, absolute=True)


@dataclass
class Frames:
    """Machine = work + work offset (G54–G59) + local shift (G52) + coordinate shift (G92/G50)."""

    axes: tuple[str, ...]
    work_offsets: list[dict[str, float]] = field(default_factory=list)
    local_shift: dict[str, float] = field(default_factory=dict)
    set_shift: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.work_offsets:
            self.work_offsets = [{a: 0.0 for a in self.axes} for _ in range(6)]

    def origin(self, wcs: int, axis: str) -> float:
        return (self.work_offsets[wcs].get(axis, 0.0) + self.local_shift.get(axis, 0.0)
                + self.set_shift.get(axis, 0.0))
