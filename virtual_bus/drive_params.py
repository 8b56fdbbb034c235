"""The settings of a simulated drive (`DriveParams`), apart from the drive model (virtual_bus.drive)
so a bench file can be read without loading the model: `hil path` reads the bench and never runs a
drive (its start-up, issue 16).
"""

from __future__ import annotations

from dataclasses import dataclass

from fieldbus.units import DELTA_UNITS, DriveUnits


@dataclass
class DriveParams:
    counts_per_rev: int = 1_280_000
    kp: float = 120.0  # position loop gain, 1/s (ASDA P2-00 style)
    kff: float = 0.95  # velocity feed-forward fraction (P2-02 style)
    velocity_bandwidth: float = 800.0  # rad/s of the velocity loop
    max_speed_rpm: float = 5000.0
    inertia: float = 1.0e-4  # kg·m², motor plus reflected load
    rated_torque: float = 2.39  # N·m (750 W ASDA-A3 class)
    viscous: float = 2.0e-4  # N·m per rad/s
    coulomb: float = 0.05  # N·m
    following_error_window: int = 3_840_000  # 0x6065 counts (3 motor revs)
    quick_stop_decel: float = 2.0e8  # counts/s² (0x6085)
    csv_accel: float = 5.0e7  # counts/s², the CSV ramp the drive applies (spindle)
    negative_limit: int | None = None  # hardware limit switch positions in counts
    positive_limit: int | None = None
    home_switch: int | None = None  # counts where the home switch toggles (position < this reads active)
    index_pulse_every: int | None = None  # counts between encoder index pulses; None = counts_per_rev
    probe_position: int | None = None  # counts where a touch-probe input (G31 skip) switches; None = no probe
    substeps: int = 4
    units: DriveUnits = DELTA_UNITS  # what 0x606C/0x60FF and 0x6077 carry (the device model's)
