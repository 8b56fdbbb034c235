"""User units (mm, degrees) ↔ drive units. The only place counts exist outside the drives.

A drive declares the units of its CiA 402 objects (`DriveUnits`): Delta ASDA-A2-E/A3-E/B3-E carry
positions in counts (PUU), velocities 0x606C/0x60FF in 0.1 rpm of the motor and torques
0x6077/0x6071 in 0.1 % of rated torque (linuxcnc-ethercat lcec_deasda.c: DEASDA_RPM_FACTOR 0.1;
Delta ASDA-A3 manual, CoE object list). `AxisScaling` converts with them both ways.
"""

from __future__ import annotations

from dataclasses import dataclass, field

VELOCITY_UNITS = ("0.1 rpm", "count/s")


@dataclass(frozen=True, slots=True)
class DriveUnits:
    """What one unit of a drive's velocity and torque objects is."""

    velocity: str = "0.1 rpm"  # 0x606C / 0x60FF: "0.1 rpm" (of the motor) or "count/s"
    torque_percent: float = 0.1  # 0x6077 / 0x6071: one unit in % of rated torque

    def __post_init__(self) -> None:
        if self.velocity not in VELOCITY_UNITS:
            raise ValueError(f"velocity unit {self.velocity!r}: choose one of {', '.join(VELOCITY_UNITS)}")

    def raw_per_count_per_s(self, counts_per_rev: int) -> float:
        """Drive velocity units for one count/s."""
        return 600.0 / counts_per_rev if self.velocity == "0.1 rpm" else 1.0

    def velocity_to_raw(self, cps: float, counts_per_rev: int) -> int:
        raw = round(cps * self.raw_per_count_per_s(counts_per_rev))
        return max(-0x7FFFFFFF, min(0x7FFFFFFF, int(raw)))  # a DINT, clamped as lcec_deasda does

    def raw_to_velocity(self, raw: float, counts_per_rev: int) -> float:
        """counts/s from the drive's velocity units."""
        return raw / self.raw_per_count_per_s(counts_per_rev)

    def raw_to_percent(self, raw: float) -> float:
        return raw * self.torque_percent


DELTA_UNITS = DriveUnits()


@dataclass(frozen=True, slots=True)
class AxisScaling:
    counts_per_rev: int = 1_280_000  # Delta ASDA default electronic-gear resolution (PUU per motor rev)
    gear_motor: int = 1  # motor revolutions ...
    gear_load: int = 1  # ... per this many load revolutions
    lead: float = 10.0  # mm per load revolution (ball-screw lead); 360 for a rotary axis in degrees
    direction: int = 1  # +1, or -1 when the motor is mounted reversed
    units: DriveUnits = field(default=DELTA_UNITS)  # the drive's velocity / torque units
    # Derived once: the bench cycle converts several values per axis every cycle.
    _cpu: float = field(init=False, repr=False, compare=False)
    _raw_per_cps: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_cpu", self.counts_per_rev * self.gear_motor / (self.gear_load * self.lead)
                           * self.direction)
        object.__setattr__(self, "_raw_per_cps", self.units.raw_per_count_per_s(self.counts_per_rev))

    @property
    def counts_per_unit(self) -> float:
        return self._cpu

    def to_counts(self, units: float) -> int:
        return int(round(units * self._cpu))

    def to_units(self, counts: float) -> float:
        return counts / self._cpu

    # ---- velocities: the drive's units (0x60FF / 0x606C) ----------------------------------------
    def velocity_to_drive(self, units_per_s: float) -> int:
        """mm/s (deg/s) to the drive's target-velocity units (DriveUnits.velocity_to_raw, with the
        factors derived once: the same products in the same order)."""
        raw = round(units_per_s * self._cpu * self._raw_per_cps)
        return max(-0x7FFFFFFF, min(0x7FFFFFFF, int(raw)))

    def drive_to_velocity(self, raw: float) -> float:
        """The drive's velocity units to mm/s (deg/s)."""
        return raw / self._raw_per_cps / self._cpu

    def drive_to_counts_per_s(self, raw: float) -> float:
        return raw / self._raw_per_cps  # DriveUnits.raw_to_velocity with the factor derived once

    def rpm_to_drive(self, rpm: float) -> int:
        """Load-side rev/min (spindles) to the drive's target-velocity units."""
        return self.velocity_to_drive(rpm / 60.0 * self.lead)

    def drive_to_rpm(self, raw: float) -> float:
        """The drive's velocity units to load-side rev/min."""
        return self.drive_to_velocity(raw) / self.lead * 60.0

    def torque_percent(self, raw: float) -> float:
        """0x6077 to % of rated torque."""
        return self.units.raw_to_percent(raw)
