"""Tool offset tables: length and wear per axis, nose/cutter radius and wear, tip type, life data.

nc5 numbers tools 1–512 (G10 P1–P512) with one length per channel axis (#26000+…); lathe-2018 has
offsets 1–64 for X/Y/Z (#6001…).  Values are stored as programmed (lathe X length as a diameter
value in diameter mode)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class ToolTable:
    lengths: dict[tuple[str, int], float] = field(default_factory=dict)
    wears: dict[tuple[str, int], float] = field(default_factory=dict)
    radius: dict[int, float] = field(default_factory=dict)
    radius_wear: dict[int, float] = field(default_factory=dict)
    tip: dict[int, float] = field(default_factory=dict)
    tolerance: dict[tuple[str, int], float] = field(default_factory=dict)
    life: dict[tuple[str, int], float] = field(default_factory=dict)  # (kind, tool) -> value

    def length(self, axis: str, n: int) -> float:
        return self.lengths.get((axis, n), 0.0)

    def wear(self, axis: str, n: int) -> float:
        return self.wears.get((axis, n), 0.0)
