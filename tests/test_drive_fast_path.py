"""The sim drive's per-cycle fast paths (issue 17: no limit switches, touch probe off) give the same
positions, speeds and status as the general path, cycle by cycle."""

from __future__ import annotations

import math

from dataclasses import replace

from fieldbus.pdo import RxPdo, copy_rx
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


def _state(d: Cia402Drive) -> tuple:
    return (d.state, d.mode, d.position, d.velocity, d.acceleration, d.command, d.target_velocity, d.torque,
            d.time, d.error_code, d._prev_target, d._want_cps, d._limit_flags, d._probe_latched, d._probe_pos)


def _exchange_both(params: DriveParams, rxs: list[RxPdo], origin: float = 0.0) -> list[tuple]:
    """`exchange` (its usual-cycle path, issue 17) against `apply`, `step`, `feedback` called one by one:
    the same image and the same drive state after every cycle."""
    fast, ref = Cia402Drive(params=params), Cia402Drive(params=replace(params))
    fast.modes.origin = ref.modes.origin = origin
    out = []
    for rx in rxs:
        tx = fast.exchange(copy_rx(rx), 0.001)
        ref.apply(copy_rx(rx))
        ref.step(0.001)
        assert tx == ref.feedback()
        assert _state(fast) == _state(ref)
        out.append((tx.statusword, tx.position_actual, tx.error_code))
    return out


def _enabling(mode: int) -> list[RxPdo]:
    return [RxPdo(controlword=cw, mode=mode) for cw in (0x06, 0x07, 0x0F)]


def test_exchange_equals_apply_step_feedback_in_csp_with_a_following_error_fault():
    moves = [RxPdo(controlword=0x0F, mode=8, target_position=int(300_000 * (1 - math.cos(math.pi * k / 150))))
             for k in range(300)]
    jump = [RxPdo(controlword=0x0F, mode=8, target_position=100_000)] * 20  # beyond 0x6065: AL009
    reset = [RxPdo(controlword=0x0F, mode=8)] * 200 + [RxPdo(controlword=0x80, mode=8)] + _enabling(8)
    params = DriveParams(home_switch=100_000, following_error_window=30_000, quick_stop_decel=2e10)
    out = _exchange_both(params, _enabling(8) + moves + jump + reset + moves, origin=1234.5)
    codes = [code for _, _, code in out]
    assert 0x0009 in codes and 0 in codes[codes.index(0x0009):]  # the fault was taken, then reset
    assert len({pos for _, pos, _ in out}) > 100  # the axis moved


def test_exchange_equals_apply_step_feedback_at_a_limit_switch_and_in_csv():
    to_limit = [RxPdo(controlword=0x0F, mode=8, target_position=600 * k) for k in range(400)]
    out = _exchange_both(DriveParams(positive_limit=100_000), _enabling(8) + to_limit)
    assert any(sw & 0x0800 for sw, _, _ in out)  # 0x6041 bit 11: the limit switch was reached
    spin = [RxPdo(controlword=0x0F, mode=9, target_velocity=3_000 if k < 200 else -1_000,
                  touch_probe_function=1) for k in range(400)]
    to_csp = [RxPdo(controlword=0x0F, mode=8, target_position=0)] * 30
    out = _exchange_both(DriveParams(), _enabling(9) + spin + to_csp)
    assert out[-1][0] & 0x1000 and len({pos for _, pos, _ in out}) > 100
