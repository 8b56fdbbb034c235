"""The R1-EC digital I/O modules a remote I/O station is built from (`[[io]] modules = [...]`):
name → direction, points and the ident the station lists in 0xF050 ("Detected module ident list").
The idents are this project's (0x1DD001nn inputs, 0x1DD002nn outputs, nn = points), not Delta part
numbers (docs/decisions/ethercat.md, E10). Both the master (the 0x142E check) and the virtual slave
(virtual_bus/ethercat/r1ec.py) read this one table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Module:
    name: str  # DI16 …
    direction: str  # "in" / "out"
    points: int
    ident: int

    @property
    def ctype(self) -> str:
        """The CoE type of the module's data object (one sub-index holding all its points)."""
        return {8: "USINT", 16: "UINT", 32: "UDINT"}[self.points]


MODULES: dict[str, Module] = {
    f"D{d}{n}": Module(f"D{d}{n}", "in" if d == "I" else "out", n, 0x1DD0_0000 | (0x100 if d == "I" else 0x200) | n)
    for d in ("I", "O") for n in (8, 16, 32)
}
BY_IDENT: dict[int, Module] = {m.ident: m for m in MODULES.values()}
DEFAULT_MODULES: tuple[str, ...] = ("DI16", "DO16")


def split(modules: Sequence[str]) -> tuple[list[Module], list[Module]]:
    """(input modules, output modules), each in station order; KeyError for an unknown name."""
    mods = [MODULES[m] for m in modules]
    return [m for m in mods if m.direction == "in"], [m for m in mods if m.direction == "out"]


def points(modules: Sequence[str]) -> tuple[int, int]:
    """(digital inputs, digital outputs) of a module list."""
    ins, outs = split(modules)
    return sum(m.points for m in ins), sum(m.points for m in outs)


def ident_name(ident: int) -> str:
    """A module ident as its name, or in hex when it is not an R1-EC digital module of ours."""
    m = BY_IDENT.get(ident)
    return m.name if m else f"0x{ident:08X}"
