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
    # Rotary axes (degrees): G20 never scales their words.  Default: axes named A, B or C
    # (N2.01 axis configuration, ISO 841); a bench names them by `units = "deg"`.
    rotary_axes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.rotary_axes:
            self.rotary_axes = tuple(a for a in self.axes if a[:1] in ("A", "B", "C"))

    @property
    def is_lathe(self) -> bool:
        return self.machine == "lathe"

    @property
    def legacy(self) -> bool:
        """The older lathe controller of the lathe manual (variable map, WHILE/ENDW, M98 P L)."""
        return self.name == "lathe-2018"

    def bit(self, name: str) -> bool:
        return bool(self.params.get(name, 0))

    def param(self, name: str, default: float = 0.0) -> float:
        return self.params.get(name, default)


def default_params() -> dict[str, float]:
    return {
        "N8.018 Bit10": 0,  # 0: integer distances mean 0.001 unit (auto divide by 1000)
        "N1.11 Bit4": 0,  # 0: G04 X without a point is 0.001 s
        "N2.001 Bit10": 0,  # 0: X in diameter (lathe)
        "N1.040": 0.01,  # arc radius tolerance, mm
        "N1.042": 0.0,  # default cutting feed, mm/min (0: F must be programmed)
        "N1.010 Bit22": 0,  # 1: T codes call O9000 (nc5)
        "N1.010 Bit28": 0,  # 1: G-code macro calls allowed inside the called macro (8 layers)
        "N1.010": 0,  # G43/G44/G49 block without Z: 0 moves to the compensated position, 1 internal only
        "N1.118": 0,  # first M code of the preview-halt function (0: none)
        "N1.119": 0,  # number of halt M codes from N1.118
        "N1.120": 0, "N1.121": 0, "N1.122": 0,  # continuous G-code macro call: first G, first O, amount
        "N1.123": 0, "N1.124": 0, "N1.125": 0,  # continuous M-code macro call: first M, first O, amount
        "N8.22 Bit5": 0,  # macro file search: 0 same root as main first, 1 USB root first
        "M2x010": 0,  # block skip switch ('/')
        "preview depth": 8,  # blocks the interpreter reads ahead of motion (decisions A27)
        "M99 main restarts": 1,  # how often M99 in a main program restarts it before `hil path` stops (A22)
        "max blocks": 1_000_000,  # executed blocks before the emulator stops an endless loop (0xDE01)
        "preview log": 1000,  # last macro statements `Interpreter.preview_log` keeps (memory flat, B3)
        "macro statements per cycle": 40,  # macro statements read per cycle before motion goes on (B2)
    }


def make_profile(name: str, axes: tuple[str, ...] | None = None, params: dict[str, float] | None = None,
                 rotary: tuple[str, ...] = ()) -> Profile:
    if name not in PROFILE_NAMES:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILE_NAMES)}")
    p = default_params()
    if params:
        p.update(params)
    if name == "nc5-mill":
        return Profile(name, "mill", None, axes or ("X", "Y", "Z"), (), p, rotary)
    lathe_type = {"nc5-lathe-a": "A", "nc5-lathe-b": "B", "nc5-lathe-c": "C", "lathe-2018": "A"}[name]
    if name == "lathe-2018":  # L ch.1: P306 = 0/1/2 selects type A/B/C
        lathe_type = "ABC"[int(p.get("P306", 0)) % 3]
    p.setdefault("N1.08", "ABC".index(lathe_type))
    dia = () if p.get("N2.001 Bit10", 0) else ("X",)
    return Profile(name, "lathe", lathe_type, axes or ("X", "Z"), dia, p, rotary)
