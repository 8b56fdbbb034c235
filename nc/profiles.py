"""Controller profiles: which dialect the interpreter speaks and its power-on state.

Parameters keep the manuals' names (N1.08, N2.001 Bit10, N8.018 Bit10 ...) so a bench file can
set them as a Delta engineer would read them off the controller.
"""

from __future__ import annotations

from dataclasses import dataclass, field

PROFILE_NAMES = ("nc5-lathe-a", "nc5-lathe-b", "nc5-lathe-c", "nc5-mill", "lathe-2018")


@dataclass
class Profile:
    name: str
    machine: str  # "lathe" or "mill"
    lathe_type: str | None  # "A", "B", "C" (N1.08) or None on a mill
    axes: tuple[str, ...]
    diameter_axes: tuple[str, ...] = ()
    params: dict[str, float] = field(default_factory=dict)

    @property
    def is_lathe(self) -> bool:
        return self.machine == "lathe"

    def param(self, name: str, default: float = 0.0) -> float:
        return self.params.get(name, default)


def default_params() -> dict[str, float]:
    return {
        "N8.018 Bit10": 0,  # 0: integer distances mean 0.001 unit (auto divide by 1000)
        "N1.11 Bit4": 0,  # 0: G04 X without a point is 0.001 s
        "N2.001 Bit10": 0,  # 0: X in diameter (lathe)
        "N1.040": 0.01,  # arc radius tolerance, mm
        "N1.042": 0.0,  # default cutting feed, mm/min (0: F must be programmed)
    }


def make_profile(name: str, axes: tuple[str, ...] | None = None, params: dict[str, float] | None = None) -> Profile:
    if name not in PROFILE_NAMES:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILE_NAMES)}")
    p = default_params()
    if params:
        p.update(params)
    if name == "nc5-mill":
        return Profile(name, "mill", None, axes or ("X", "Y", "Z"), (), p)
    lathe_type = {"nc5-lathe-a": "A", "nc5-lathe-b": "B", "nc5-lathe-c": "C", "lathe-2018": "A"}[name]
    p.setdefault("N1.08", "ABC".index(lathe_type))
    dia = () if p.get("N2.001 Bit10", 0) else ("X",)
    return Profile(name, "lathe", lathe_type, axes or ("X", "Z"), dia, p)
