"""Bus feedback → the MLC's drive status (servo on, connected, torque, velocity), each cycle."""

from __future__ import annotations

from typing import Any

from fieldbus.cia402 import State
from mlc.nc_link import DriveStatus


def drive_status(runner: Any) -> list[DriveStatus]:
    out = []
    n_axes = len(runner.axes)
    status = runner.link.status() if callable(getattr(runner.link, "status", None)) else None
    for i, (m, tx, sc) in enumerate(zip(runner.masters, runner.tx, runner.scales)):
        spindle = i >= n_axes
        vel = sc.drive_to_velocity(tx.velocity_actual)
        rpm = sc.drive_to_rpm(tx.velocity_actual)
        connected = status is None or status.slave_ok(i)  # the slave in OP (issue 6)
        out.append(DriveStatus(runner._name(i), connected=connected, servo_on=m.state is State.OPERATION_ENABLED,
                               fault=m.faulted, torque=sc.torque_percent(tx.torque_actual) * 10.0,  # D30240: 0.1 %
                               velocity=vel, rpm=rpm,
                               position=sc.to_units(tx.position_actual), spindle=spindle,
                               mode=getattr(tx, "mode_display", 8)))
    return out
