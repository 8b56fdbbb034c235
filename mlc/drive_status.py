"""The drive status the bench gives the NC each cycle and how the NC publishes it to the MLC.

`DriveStatus` is filled by the bench (hil/mlc_bridge.py) in place every cycle; `write_drive_outputs`
is `ChannelLink._drive_outputs` (mlc/nc_link.py): one pass over the drives for the summary relays,
the velocities and speeds packed into the D words in one write each (issue 17).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mlc.signals import d2
from nc.motion.css import spindle_speed


@dataclass(slots=True)  # set field by field every cycle (hil/mlc_bridge.py): slots, no instance dict
class DriveStatus:
    """What the bus tells the NC about one drive, in user units (filled by the bench each cycle)."""

    name: str
    connected: bool = True
    servo_on: bool = False
    fault: bool = False
    torque: float = 0.0  # 0.1 % of rated (0x6077)
    velocity: float = 0.0  # mm/s or deg/s (0x606C scaled)
    rpm: float = 0.0  # motor/load rev per minute
    position: float = 0.0
    spindle: bool = False
    limit: int = 0  # hardware limit switch reached: 1 negative, 2 positive (0x60FD bits 0/1), 3 unknown side
    machine_position: float = 0.0  # position + the NC-side homing offset (the NC's machine coordinate)
    mode: int = 8


def write_drive_outputs(self: Any, drives: list[DriveStatus], ch: Any = None) -> None:
    """The drives' status into the NC→MLC area (`ChannelLink._drive_outputs`, every cycle): M30000,
    M3x034/035/036, the per-axis relays M3x256…/464…, D30240… torque, D30272… velocity, D30336… rpm,
    D30400… peak torque, and the spindle block M3x704… with D3x026/D3x028. `self` is the ChannelLink."""
    mem, x = self.mem, self.x
    m = mem.m
    b3 = 30000 + 1000 * x  # M3x000
    # one pass for the summary relays (no generator per relay: this runs every cycle)
    connected, fault, servo = 1, 0, 1
    for d in drives:
        if not d.connected:
            connected = 0
        if d.fault:
            fault = 1
        if not d.servo_on:
            servo = 0
    # the axes / spindles split, made once for the bench's records (the same list, filled in place each cycle)
    split = self._drive_split
    if split is None or split[0] is not drives or split[1] != len(drives):
        axes = [d for d in drives if not d.spindle]
        spindles = [d for d in drives if d.spindle]
        order = axes + spindles if spindles else axes
        split = self._drive_split = (drives, len(drives), order[:32], spindles[:8])
    order, spindles = split[2], split[3]
    m[30000] = connected  # M30000
    m[b3 + 34] = fault
    m[b3 + 35] = m[b3 + 36] = servo  # M3x035: the bench's power-up servo-ons every axis itself (N1.10 = 0, M21-4)
    w = mem.words  # D30240… written as words into the memory itself
    for k, d in enumerate(order):
        servo_on = d.servo_on
        if k < 16 and not d.spindle:  # the axis relays M3x256+k …
            v = d.velocity
            a = b3 + k
            m[a + 256] = 1 if d.connected else 0
            m[a + 272] = 1 if servo_on else 0
            m[a + 464] = 1 if v > 1e-4 or v < -1e-4 else 0  # moving
            m[a + 480] = 1 if v > 1e-4 else 0
            m[a + 496] = 1 if v < -1e-4 else 0
        torque = int(round(d.torque))
        w[30240 + k] = torque & 0xFFFF  # s16
        if servo_on:  # D30400+k: the peak |torque| while the servo is on, else 0
            t = -torque if torque < 0 else torque
            if t > 0xFFFF:
                t = 0xFFFF
            if w[30400 + k] < t:
                w[30400 + k] = t
        else:
            w[30400 + k] = 0
    mem.set_f32s(30272, [d.velocity * 60.0 for d in order])  # D30272…: one packed write
    mem.set_f32s(30336, [d.rpm for d in order])
    for k, d in enumerate(spindles):
        m[b3 + 96 + k] = 1 if d.connected else 0
        w[30432 + k] = int(round(d.torque)) & 0xFFFF
        base = b3 + 704 + 16 * k
        cmd = self.commanded_rpm(k)
        if k == 0:  # what the drive is really given: G96, override, G50 clamp
            css, clamp = (ch.css_rpm, ch.spindle_max) if ch is not None else (None, None)
            ovr = ch.spindle_factor if ch is not None else mem.u16(d2(x, 26)) / 100.0
            cmd = spindle_speed(cmd, css, clamp, self.spindle_max_rpm, ovr)
        rpm = d.rpm
        m[base + 1] = 1 if abs(rpm) < 1.0 else 0
        reached = abs(cmd) > 0 and abs(rpm - cmd) <= max(1.0, 0.02 * abs(cmd))
        m[base] = 1 if reached else 0
        m[base + 6] = 1 if d.servo_on else 0
        m[base + 5] = 1 if d.mode == 8 else 0
        if k == 0:
            mem.set_f32s(b3 + 26, [rpm, d.position % 360.0])  # D3x026, D3x028
