"""A CSP drive stepped over a stretch of cycles at once (virtual_bus/drive_stretch.py, issue 17) gives, cycle by
cycle, the feedback exchange() gives one cycle at a time, leaves the drive in the same state, and stops before
a cycle that faults or reaches a limit switch (which exchange() then takes)."""

from __future__ import annotations

import math
from dataclasses import astuple

import numpy as np
import pytest

from fieldbus.cia402 import State
from fieldbus.pdo import RxPdo
from virtual_bus.drive import Cia402Drive, DriveParams
from virtual_bus.drive_stretch import can_stretch, csp_stretch, csv_stretch

FIELDS = ("statusword", "position_actual", "velocity_actual", "torque_actual", "following_error")


def _enabled(params: DriveParams, origin: float, mode: int = 8) -> tuple[Cia402Drive, RxPdo]:
    d = Cia402Drive(params=params)
    d.modes.origin = origin
    rx = RxPdo(mode=mode)
    for cw in (0x06, 0x07, 0x0F):
        rx.controlword = cw
        d.exchange(rx, 0.001)
    return d, rx


def _targets(seed: int, n: int) -> list[int]:
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    path = 300_000 * (1 - np.cos(2 * math.pi * k / rng.uniform(300, 900))) + rng.normal(0, 30, n).cumsum()
    path[n // 3: n // 3 + 40] = path[n // 3]  # a stop: target reached bits, torque settling
    return [int(round(v)) for v in path]


def _state(d: Cia402Drive) -> tuple:
    return (d.position, d.velocity, d.command, d.time, d.acceleration, d.torque, d._prev_target, d.state,
            d.error_code, d._want_cps, d.target_velocity, d._probe_latched, d._probe_pos)


def _reference(d: Cia402Drive, rx: RxPdo, field: str, values: list[int]) -> tuple[list, list]:
    """exchange() once per value of `field`: the feedback and the model state after each cycle."""
    want, states = [], []
    for v in values:
        setattr(rx, field, v)
        want.append(d.exchange(rx, 0.001))
        states.append(_state(d))
    return want, states


@pytest.mark.parametrize("seed", range(4))
def test_stretch_equals_exchange_cycle_by_cycle(seed):
    params = DriveParams(home_switch=150_000 if seed % 2 else None)
    origin = 1234.0 * seed
    one, rx1 = _enabled(params, origin)
    many, rx2 = _enabled(params, origin)
    targets = _targets(seed, 1500)
    want, states = _reference(one, rx1, "target_position", targets)
    rng = np.random.default_rng(seed)
    got, k = [], 0
    while k < len(targets):
        chunk = targets[k:k + int(rng.integers(1, 90))]
        rx2.target_position = chunk[-1]
        s = csp_stretch(many, rx2, chunk, 0.001)
        assert s.done == len(chunk) and s.last is not None
        got += list(zip(*(getattr(s, f) for f in FIELDS)))
        assert astuple(s.last) == astuple(want[k + len(chunk) - 1])
        assert _state(many) == states[k + len(chunk) - 1]  # every float of the model, at every stretch's end
        k += len(chunk)
    assert got == [tuple(getattr(tx, f) for f in FIELDS) for tx in want]
    assert _state(many) == _state(one)
    assert len({g[1] for g in got}) > 500  # it moved


def test_stretch_stops_before_the_cycle_that_faults():
    params = DriveParams(following_error_window=20_000)
    one, rx1 = _enabled(params, 0.0)
    many, rx2 = _enabled(params, 0.0)
    targets = [0] * 30 + [100_000] * 30  # a step five times the following-error window
    rx2.target_position = targets[-1]
    s = csp_stretch(many, rx2, targets, 0.001)
    assert s.done == 30  # the step's first cycle would fault: the stretch ends before it
    for t in targets[:s.done]:
        rx1.target_position = t
        one.exchange(rx1, 0.001)
    assert _state(many) == _state(one) and many.state is State.OPERATION_ENABLED
    rx1.target_position = rx2.target_position = targets[s.done]
    a, b = one.exchange(rx1, 0.001), many.exchange(rx2, 0.001)  # the faulting cycle, taken by exchange()
    assert astuple(a) == astuple(b) and many.state is State.FAULT_REACTION_ACTIVE


@pytest.mark.parametrize("seed", range(2))
def test_a_limited_drive_stretches_short_of_its_switch(seed):
    """A CSP drive with limit switches inside its path: stretches stop before a cycle whose sub-steps reach a
    switch, exchange() takes that cycle (the drive holds at the switch, sets 0x60FD and its limit code), and
    stretches go on once the path is back inside; the same feedback and model state every cycle."""
    params = DriveParams(positive_limit=450_000, negative_limit=-50_000)
    one, rx1 = _enabled(params, 0.0)
    many, rx2 = _enabled(params, 0.0)
    targets = _targets(seed, 1500)
    want, states = _reference(one, rx1, "target_position", targets)
    rng = np.random.default_rng(seed)
    got, k, stepped = [], 0, 0
    while k < len(targets):
        chunk = targets[k:k + int(rng.integers(1, 90))]
        s = csp_stretch(many, rx2, chunk, 0.001)
        got += list(zip(*(getattr(s, f) for f in FIELDS)))
        k += s.done
        if s.done < len(chunk):  # the switch: this cycle by exchange()
            rx2.target_position = targets[k]
            tx = many.exchange(rx2, 0.001)
            got.append(tuple(getattr(tx, f) for f in FIELDS))
            k, stepped = k + 1, stepped + 1
        assert _state(many) == states[k - 1]
    assert got == [tuple(getattr(tx, f) for f in FIELDS) for tx in want]
    assert stepped > 0 and any(tx.statusword & 0x0800 for tx in want)  # the switch was reached


def test_no_stretch_where_the_plain_csp_path_does_not_hold():
    d, rx = _enabled(DriveParams(negative_limit=-10**9), 0.0, mode=9)
    assert not can_stretch(d, rx, 9) and csv_stretch(d, rx, 2, 0.001).done == 0  # a CSV drive with limits
    d, rx = _enabled(DriveParams(), 0.0)
    rx.touch_probe_function = 1  # a G31 probe armed: the latch is per sub-step
    assert not can_stretch(d, rx)
    rx.touch_probe_function, rx.controlword = 0, 0x0B  # quick stop requested
    assert not can_stretch(d, rx)


@pytest.mark.parametrize("probe", [0, 1])
def test_csv_spindle_stretch_equals_exchange_with_its_index_latch(probe):
    """A spindle run up to 1200 rpm, held, reversed: stretches wherever can_stretch allows (with the index
    probe armed: once it latched), exchange() elsewhere; the same feedback and model state every cycle."""
    params = DriveParams()
    one, rx1 = _enabled(params, 77.0, mode=9)
    many, rx2 = _enabled(params, 77.0, mode=9)
    for rx in (rx1, rx2):
        rx.touch_probe_function = probe
    speeds = [12000] * 700 + [-6000] * 600  # 0x60FF in 0.1 rpm
    want, states = _reference(one, rx1, "target_velocity", speeds)
    rng = np.random.default_rng(probe)
    k = stretched = 0
    latch = next((j for j, tx in enumerate(want) if tx.touch_probe_status == 3), len(want))
    before = 0  # cycles stretched before the index latched: an armed probe no longer keeps the spindle stepped
    while k < len(speeds):
        rx2.target_velocity = speeds[k]
        c = min(int(rng.integers(1, 70)), len(speeds) - k)
        c = next((j for j in range(1, c) if speeds[k + j] != speeds[k]), c)  # a stretch holds one 0x60FF
        s = csv_stretch(many, rx2, c, 0.001)
        if s.done == 0:
            assert astuple(many.exchange(rx2, 0.001)) == astuple(want[k])
            k += 1
        else:
            got = list(zip(*(getattr(s, f) for f in FIELDS)))
            assert got == [tuple(getattr(tx, f) for f in FIELDS) for tx in want[k:k + s.done]]
            assert astuple(s.last) == astuple(want[k + s.done - 1])
            assert k + s.done <= latch or k > latch  # a stretch never takes the latching cycle
            before += max(0, min(k + s.done, latch) - k)
            k, stretched = k + s.done, stretched + s.done
        assert _state(many) == states[k - 1]
    assert stretched > 1000 and abs(want[699].velocity_actual - 12000) < 20
    assert (want[-1].touch_probe_status == 3) == bool(probe)
    if probe:
        assert before > 0.5 * latch > 5  # the run-up to the first index edge stretches too


def test_a_standing_drive_repeats_its_cycle_exactly_in_runs_of_parts():
    """CspRun/CsvRun (a B27 pass's drives, a part at a time): a drive standing at its target (a mill's Z and its
    spindle in a CAM program) repeats the cycle it ended where it began, only its time going on; every
    cycle's feedback and every float of the model are exchange()'s, the standing cycles and the moves after."""
    from virtual_bus.drive_stretch import CspRun, CsvRun

    params = DriveParams()
    one, rx1 = _enabled(params, 500.0)
    many, rx2 = _enabled(params, 500.0)
    targets = [5000] * 1000 + [0] * 300 + _targets(3, 400) + [0] * 5  # standing at 5000, then at 0
    want, states = _reference(one, rx1, "target_position", targets)
    run, k, still = CspRun(many, rx2, 0.001), 0, []
    for n in (1, 2, 150, 347, 500, 300, 60, 345, 5):
        run.step(targets[k:k + n])
        still.append(run.still is not None)
        k += n
    rx2.target_position = targets[-1]
    s = run.finish()
    assert s.done == len(targets) and still[3:5] == [True, True]  # settled within 500 cycles, then repeated
    assert list(zip(*(getattr(s, f) for f in FIELDS))) == [tuple(getattr(tx, f) for f in FIELDS) for tx in want]
    assert _state(many) == states[-1]

    one, rx1 = _enabled(params, 77.0, mode=9)
    many, rx2 = _enabled(params, 77.0, mode=9)
    speeds = [0] * 400 + [3000] * 200
    want, states = _reference(one, rx1, "target_velocity", speeds)
    got = []
    for part in (speeds[:400], speeds[400:]):
        rx2.target_velocity = part[0]
        run = CsvRun(many, rx2, 0.001)
        for n in (3, 100, len(part) - 103):
            run.step(n)
            still.append(run.still)
        s = run.finish()
        got += list(zip(*(getattr(s, f) for f in FIELDS)))
        assert _state(many) == states[len(got) - 1]
    assert got == [tuple(getattr(tx, f) for f in FIELDS) for tx in want] and still[-6:-3] == [True] * 3
