"""Bench description: the machine profile, axes with their drives and units, spindles, bus and cycle."""

from __future__ import annotations

from dataclasses import dataclass, field

from fieldbus.units import AxisScaling
from nc.motion.limits import AxisLimits, MotionConfig
from virtual_bus.drive import DriveParams


@dataclass
class AxisConfig:
    name: str
    scaling: AxisScaling = field(default_factory=AxisScaling)
    limits: AxisLimits = field(default_factory=AxisLimits)
    drive: DriveParams = field(default_factory=DriveParams)
    start: float = 0.0  # machine position of the simulated axis at power-on, mm


@dataclass
class SpindleConfig:
    name: str = "S1"
    scaling: AxisScaling = field(default_factory=lambda: AxisScaling(counts_per_rev=1_280_000, lead=360.0))
    max_rpm: float = 4000.0
    drive: DriveParams = field(default_factory=lambda: DriveParams(max_speed_rpm=6000.0, csv_accel=1.0e8))


@dataclass
class Bench:
    name: str = "lathe-2axis"
    profile: str = "nc5-lathe-a"
    axes: list[AxisConfig] = field(default_factory=list)
    spindles: list[SpindleConfig] = field(default_factory=list)
    cycle: float = 0.001
    bus: str = "sim"
    params: dict[str, float] = field(default_factory=dict)
    enable_timeout: float = 0.5  # s allowed for every drive to reach operation enabled
    settle_time: float = 0.3  # s the bench keeps cycling after the program to let axes settle
    max_time: float = 3600.0  # s of simulated time before the run is abandoned with an alarm

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    def motion_config(self) -> MotionConfig:
        return MotionConfig(cycle=self.cycle, axes=self.axis_names, limits={a.name: a.limits for a in self.axes})


def default_lathe() -> Bench:
    """X (radius, 5 mm lead) and Z (10 mm lead) on ASDA-class drives, one spindle."""
    x = AxisConfig("X", AxisScaling(lead=5.0), AxisLimits(300.0, 3000.0, 150_000.0), start=60.0)
    z = AxisConfig("Z", AxisScaling(lead=10.0), AxisLimits(400.0, 4000.0, 200_000.0), start=100.0)
    return Bench(axes=[x, z], spindles=[SpindleConfig()])
