"""The sim drive's per-cycle fast paths (issue 17: no limit switches, touch probe off) give the same
positions, speeds and status as the general path, cycle by cycle."""

from __future__ import annotations

import math

from fieldbus.pdo import RxPdo
from virtual_bus.drive import Cia402Drive, DriveParams

FAR = 10**15  # limit switches that are never reached: the general path, same physics


def _enable(d: Cia402Drive) -> None:
    for cw in (0x06, 0x07, 0x0F):
        d.exchange(RxPdo(controlword=cw, mode=8), 0.001)


def _run(params: DriveParams) -> list[tuple]:
    d = Cia402Drive(params=params)
    _enable(d)
    out = []
    for k in range(600):  # a jerk-free sine move out and back, then a quick stop mid-motion
        target = int(round(200_000 * (1 - math.cos(2 * math.pi * k / 400))))
        cw = 0x0F if k < 500 else 0x0B
        tx = d.exchange(RxPdo(controlword=cw, mode=8, target_position=target), 0.001)
        out.append((d.position, d.velocity, d.command, tx.statusword, tx.following_error, tx.torque_actual))
    return out


def test_no_limit_fast_path_equals_far_limits():
    fast = _run(DriveParams())
    general = _run(DriveParams(negative_limit=-FAR, positive_limit=FAR))
    assert fast == general
    assert fast[399][0] != fast[200][0]  # the drive moved: the comparison is not of two idle drives
    assert fast[-1][3] & 0x6F != 0x27  # and the quick stop was taken


def test_limit_switch_still_stops_the_axis():
    out = _run(DriveParams(positive_limit=100_000))
    assert max(p for p, *_ in out) <= 100_000


def _run_spindle(params: DriveParams) -> list[tuple]:
    """A spindle drive in CSV with touch probe 1 latching the encoder index: ramp up, run, reverse."""
    d = Cia402Drive(params=params)
    for cw in (0x06, 0x07, 0x0F):
        d.exchange(RxPdo(controlword=cw, mode=9), 0.001)
    out = []
    for k in range(900):
        rpm10 = 3_000 if k < 450 else -2_000  # 0x60FF in 0.1 rpm: 300 rpm, then -200 rpm
        tx = d.exchange(RxPdo(controlword=0x0F, mode=9, target_velocity=rpm10, touch_probe_function=0x0001
                              if k % 200 < 150 else 0), 0.001)
        out.append((d.position, d.velocity, d.command, d.target_velocity, tx.statusword, tx.velocity_actual,
                    tx.touch_probe_status, tx.touch_probe_pos1))
    return out


def test_csv_spindle_with_index_probe_fast_path_equals_far_limits():
    fast = _run_spindle(DriveParams())
    general = _run_spindle(DriveParams(negative_limit=-FAR, positive_limit=FAR))
    assert fast == general
    assert any(row[6] == 0x0003 for row in fast)  # the index was latched on the way
    assert fast[440][1] > 0 > fast[-1][1]  # it ran forward, then in reverse
