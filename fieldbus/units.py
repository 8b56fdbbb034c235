"""User units (mm, degrees) ↔ drive counts. The only place counts exist outside the drives."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class AxisScaling:
    counts_per_rev: int = 1_280_000  # Delta ASDA default electronic-gear resolution (PUU per motor rev)
    gear_motor: int = 1  # motor revolutions ...
    gear_load: int = 1  # ... per this many load revolutions
    lead: float = 10.0  # mm per load revolution (ball-screw lead); 360 for a rotary axis in degrees
    direction: int = 1  # +1, or -1 when the motor is mounted reversed

    @property
    def counts_per_unit(self) -> float:
        return self.counts_per_rev * self.gear_motor / (self.gear_load * self.lead) * self.direction

    def to_counts(self, units: float) -> int:
        return int(round(units * self.counts_per_unit))

    def to_units(self, counts: float) -> float:
        return counts / self.counts_per_unit

    def rpm_to_counts_per_s(self, rpm: float) -> int:
        """Load-side rev/min to counts/s (spindles in CSV)."""
        return int(round(rpm / 60.0 * self.lead * self.counts_per_unit))

    def counts_per_s_to_rpm(self, cps: float) -> float:
        return cps / self.counts_per_unit / self.lead * 60.0
