"""The drive status the NC writes every cycle (App. B.2.2.1/B.2.4.1: M30000, M3x034/036, the axis relays M3x256…,
the spindle block M3x704…, D30240… torque, D30272…/D30336… velocity, D30400… peak, D3x026 spindle speed feedback,
D3x028 spindle angle) must all be among the devices a bulk stretch works out cycle by cycle for a gated user scan
(hil/stretch_bulk.written_devices): a device missing there is one whose change does not wake an MLC that reads it
(an MLC counting spindle revolutions from D3x028 would count none while a stretch runs)."""

from __future__ import annotations

import pytest

from hil.stretch_bulk import written_devices
from mlc.drive_status import DriveStatus
from mlc.memory import DeviceMemory
from mlc.nc_link import ChannelLink
from mlc.on_change import AREA_M, AREA_WORDS


def _drives() -> list[DriveStatus]:
    axes = [DriveStatus(a, servo_on=True, torque=-123.0, velocity=v, rpm=v * 12.0, position=p)
            for a, v, p in (("X", 25.0, 10.5), ("Z", -40.0, -3.25))]
    spindle = DriveStatus("S1", servo_on=True, torque=55.0, velocity=100.0, rpm=1001.3, position=123.3, spindle=True)
    return axes + [spindle]


@pytest.mark.parametrize("x", [1, 2])
def test_every_device_the_drive_status_changes_is_watched_by_a_bulk_stretch(x):
    mem = DeviceMemory()
    link = ChannelLink(mem, x=x)
    before_m, before_w = bytes(mem.m), bytes(mem.d.tobytes())
    link._drive_outputs(_drives(), None)
    changed_m = {i for i, (a, b) in enumerate(zip(before_m, mem.m)) if a != b}
    words = mem.d
    changed_w = {i for i in range(len(words)) if before_w[2 * i:2 * i + 2] != words[i].tobytes()}
    assert 30000 + 1000 * x + 26 in changed_w and 30000 + 1000 * x + 28 in changed_w  # D3x026, D3x028
    watched = written_devices(x)
    missing = sorted([f"M{i}" for i in changed_m if (AREA_M, i) not in watched]
                     + [f"D{i}" for i in changed_w if (AREA_WORDS, i) not in watched])
    assert not missing, missing
