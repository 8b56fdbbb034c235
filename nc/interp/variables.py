"""Macro variable store. None is the vacant value (#0, NC5 App. B.3.1.1)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Variables:
    values: dict[int, float] = field(default_factory=dict)

    def get(self, number: int) -> float | None:
        if number == 0:
            return None
        return self.values.get(number)

    def set(self, number: int, value: float | None) -> None:
        if value is None:
            self.values.pop(number, None)
        else:
            self.values[number] = float(value)
