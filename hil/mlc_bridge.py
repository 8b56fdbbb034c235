"""Bus feedback → the MLC's drive status (servo on, connected, torque, velocity), each cycle."""

from __future__ import annotations

from typing import Any

from fieldbus.cia402 import State
from hil.cycle_lean import factors
from mlc.nc_link import DriveStatus

_FAULT, _REACTION = State.FAULT, State.FAULT_REACTION_ACTIVE


def drive_status(runner: Any, status: Any) -> list[DriveStatus]:
    """The drives' status this cycle. The records are the runner's own, updated in place every cycle
    (the MLC reads them within the cycle): no new objects per cycle. `status`: the link's
    `LinkStatus` of this cycle, read once by the runner (None: the link reports none)."""
    n_axes = len(runner.axes)
    out: list[DriveStatus] | None = getattr(runner, "_drive_status", None)
    if out is None or len(out) != len(runner.masters):
        out = [DriveStatus(runner._name(i), spindle=i >= n_axes) for i in range(len(runner.masters))]
        runner._drive_status = out
    enabled = State.OPERATION_ENABLED
    facs = getattr(runner, "_factors", None) or factors(runner.scales)  # unit factors read once (hil/cycle_lean.py)
    origin = runner.origin.tolist()
    states = status.states if status is not None else None  # LinkStatus.slave_ok spelt out
    n_states = len(states) if states is not None else 0
    for i, (m, tx, f, d) in enumerate(zip(runner.masters, runner.tx, facs, out)):
        # AxisScaling's conversions spelt out, the same divisions in the same order (bit for bit)
        cpu = f.cpu
        d.connected = states is None or (i < n_states and states[i] == "OP")  # the slave in OP (issue 6)
        st = m.state
        d.servo_on = st is enabled
        d.fault = st is _FAULT or st is _REACTION
        d.torque = tx.torque_actual * f.torque * 10.0  # D30240: 0.1 %
        d.velocity = v = tx.velocity_actual / f.raw_per_cps / cpu
        d.rpm = v / f.lead * 60.0  # AxisScaling.drive_to_rpm, velocity not converted twice
        d.position = p = tx.position_actual / cpu
        if i < n_axes:  # the limit switch (0x60FD bits 0/1 when bit 11 is set) and the NC's machine position
            d.limit = ((tx.digital_inputs & 0x3) or 0x3) if tx.statusword & 0x0800 else 0
            d.machine_position = p + origin[i]
        d.mode = getattr(tx, "mode_display", 8)
    return out
