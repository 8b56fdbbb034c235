"""The virtual drive's CiA 402 profile modes (issue 23): profile position, profile velocity, homing and cyclic
synchronous torque, driven by their controlword bits and objects as CiA 402-2 defines them (statusword bits 10, 12,
13 per mode; homing methods of §10.7; 0x607C: position actual at the home position). Simulated time only."""

from __future__ import annotations

import pytest

from fieldbus.pdo import RxPdo
from virtual_bus.drive import Cia402Drive, DriveParams
from virtual_bus.drive_modes import HOMING_METHODS, MODE_OBJECTS, SUPPORTED_MASK, ModeObjects, check_value

CPR = 1_280_000
DT = 0.001


def enabled(mode: int, start: float = 0.0, **params) -> Cia402Drive:
    d = Cia402Drive(DriveParams(counts_per_rev=CPR, **params))
    d.position = d.command = start
    for cw in (0x06, 0x07, 0x0F):
        d.exchange(RxPdo(controlword=cw, mode=mode), DT)
    return d


def until(d: Cia402Drive, rx: RxPdo, done, limit: float = 10.0):
    for _ in range(int(limit / DT)):
        tx = d.exchange(rx, DT)
        if done(tx):
            return tx
    raise AssertionError(f"not within {limit} s: statusword 0x{tx.statusword:04X}")


def test_supported_modes_are_what_runs():
    assert SUPPORTED_MASK == 0x3A5  # PP, PV, HM, CSP, CSV, CST: bits 0, 2, 5, 7, 8, 9
    assert set(MODE_OBJECTS) >= {(0x6081, 0), (0x6083, 0), (0x6084, 0), (0x607C, 0), (0x6098, 0), (0x6099, 1),
                                 (0x6099, 2), (0x609A, 0), (0x6072, 0), (0x607D, 1), (0x607D, 2), (0x6091, 1),
                                 (0x605A, 0)}
    o = ModeObjects()
    assert not check_value(0x6098, 0, 7, o) and all(check_value(0x6098, 0, m, o) for m in HOMING_METHODS)
    assert not check_value(0x6091, 1, 2, o) and check_value(0x6091, 1, 1, o)


def test_profile_position_handshake_and_move():
    d = enabled(1)
    d.modes.objects.profile_velocity = CPR  # 60 rpm
    tx = d.exchange(RxPdo(controlword=0x0F, mode=1, target_position=640_000), DT)
    assert tx.statusword & 0x1400 == 0x0400  # no set-point: target reached, no acknowledge
    tx = d.exchange(RxPdo(controlword=0x1F, mode=1, target_position=640_000), DT)
    assert tx.statusword & 0x1000  # bit 12 set-point acknowledge while bit 4 is high
    tx = d.exchange(RxPdo(controlword=0x0F, mode=1, target_position=640_000), DT)
    assert not tx.statusword & 0x1400  # moving: acknowledge gone, target not reached
    t0 = d.time
    tx = until(d, RxPdo(controlword=0x0F, mode=1, target_position=640_000), lambda tx: tx.statusword & 0x0400)
    assert abs(tx.position_actual - 640_000) <= 100  # 0x6067 window
    assert d.time - t0 == pytest.approx(0.5, abs=0.05)  # half a revolution at 1 rev/s (0.2 s ramps are short)
    # relative (bit 6): another 10 000 counts from the last target
    d.exchange(RxPdo(controlword=0x5F, mode=1, target_position=10_000), DT)
    d.exchange(RxPdo(controlword=0x4F, mode=1, target_position=10_000), DT)
    tx = until(d, RxPdo(controlword=0x4F, mode=1), lambda tx: tx.statusword & 0x0400)
    assert abs(tx.position_actual - 650_000) <= 100


def test_profile_position_clips_to_the_software_limits():
    d = enabled(1)
    d.modes.objects.max_position_limit = 200_000
    d.exchange(RxPdo(controlword=0x1F, mode=1, target_position=640_000), DT)
    tx = until(d, RxPdo(controlword=0x0F, mode=1, target_position=640_000), lambda tx: tx.statusword & 0x0400)
    assert abs(tx.position_actual - 200_000) <= 100


def test_profile_velocity_reaches_and_reports():
    d = enabled(3)
    d.modes.objects.profile_acceleration = 300  # 0 → 3000 rpm in 300 ms: 0 → 1000 rpm in 100 ms
    tx = d.exchange(RxPdo(controlword=0x0F, mode=3, target_velocity=10_000), DT)
    assert tx.statusword & 0x1000  # still standing: speed = 0
    tx = until(d, RxPdo(controlword=0x0F, mode=3, target_velocity=10_000), lambda tx: tx.statusword & 0x0400)
    assert d.time == pytest.approx(0.1, abs=0.02) and not tx.statusword & 0x1000
    assert tx.velocity_actual == pytest.approx(10_000, abs=100)
    tx = until(d, RxPdo(controlword=0x10F, mode=3, target_velocity=10_000), lambda tx: tx.statusword & 0x1000)  # halt
    assert abs(tx.velocity_actual) <= 100


def test_cyclic_torque_accelerates_by_torque_over_inertia():
    d = enabled(10)
    tx = d.exchange(RxPdo(controlword=0x0F, mode=10, target_torque=100), DT)  # 10 % of 2.39 N·m
    assert tx.statusword & 0x1000  # the drive follows the target torque
    v0 = d.velocity
    for _ in range(10):
        tx = d.exchange(RxPdo(controlword=0x0F, mode=10, target_torque=100), DT)
    p = d.params
    rad_per_count = 2 * 3.141592653589793 / CPR
    expected = (0.239 - p.coulomb) / p.inertia * 0.010 / rad_per_count  # viscous drag is small here
    assert d.velocity - v0 == pytest.approx(expected, rel=0.05)
    assert tx.torque_actual == pytest.approx(100, abs=3)
    d.modes.objects.max_torque = 50  # 0x6072 clips it
    for _ in range(5):
        tx = d.exchange(RxPdo(controlword=0x0F, mode=10, target_torque=100), DT)
    assert tx.torque_actual == pytest.approx(50, abs=3)


def home(method: int, start: int, offset: int = 1000, **params):
    d = enabled(6, start, **params)
    d.modes.objects.homing_method = method
    d.modes.objects.home_offset = offset
    tx = d.exchange(RxPdo(controlword=0x0F, mode=6), DT)
    assert tx.statusword & 0x3400 == 0x0400  # not started
    tx = until(d, RxPdo(controlword=0x1F, mode=6), lambda tx: tx.statusword & 0x3400 in (0x1400, 0x2000, 0x2400))
    return d, tx


EDGE = 300_000


@pytest.mark.parametrize("method,start,home_at", [
    (21, 600_000, EDGE), (21, 0, EDGE), (22, 600_000, EDGE), (22, 0, EDGE),  # home switch edge
    (5, 600_000, CPR), (6, 600_000, 0),  # then the index pulse beyond the edge (every revolution)
    (17, 100_000, -200_000), (18, 100_000, 400_000),  # the limit switches
    (1, 100_000, 0), (2, 100_000, 0),  # limit switch, then the index pulse back inside
    (33, 700_000, 0), (34, 700_000, CPR), (35, 700_000, 700_000), (37, 700_000, 700_000),
])
def test_homing_methods(method, start, home_at):
    params = {"home_switch": EDGE} if method in (5, 6, 21, 22) else \
        {"negative_limit": -200_000, "positive_limit": 400_000} if method in (1, 2, 17, 18) else {}
    d, tx = home(method, start, **params)
    assert tx.statusword & 0x3400 == 0x1400  # homing attained and target reached
    assert d.modes.origin == 1000 - home_at  # the home position (physical counts) reads 0x607C = 1000
    assert abs(tx.position_actual - 1000) <= 100  # it stands on the home position


def test_homing_into_a_limit_switch_is_an_error_and_bit4_low_interrupts():
    d, tx = home(21, 100_000, home_switch=-1_000_000, negative_limit=-200_000)
    assert tx.statusword & 0x2000 and d.modes.origin == 0  # homing error: no new origin
    d = enabled(6, home_switch=EDGE)
    d.modes.objects.homing_method = 21
    for _ in range(20):
        d.exchange(RxPdo(controlword=0x1F, mode=6), DT)
    tx = until(d, RxPdo(controlword=0x0F, mode=6), lambda tx: abs(tx.velocity_actual) == 0 and tx.statusword & 0x400)
    assert tx.statusword & 0x3400 == 0x0400  # interrupted


def test_origin_carries_into_csp():
    d, tx = home(35, 700_000, offset=0)
    pos = tx.position_actual
    assert pos == 0
    for _ in range(50):
        tx = d.exchange(RxPdo(controlword=0x0F, mode=8, target_position=1000), DT)
    assert abs(tx.position_actual - 1000) <= 5 and abs(d.position - 701_000) <= 5
