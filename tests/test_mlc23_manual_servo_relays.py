"""The MLC's servo relays in the manual modes (decision M23-1): an axis held OFF (M2x272+i ON, or M2x012 OFF for
every axis) does not move in JOG, INC, MPG or HOME — the command is refused with App. A 0x0A07 "Servo is not
ready. The axis is not servo ON" — and a manual move in progress when the relay falls stops jerk-limited, the drive
disabled once the axis stands. Simulated lathe bench, default MLC, through the script API (hil/scripting.py)."""

from __future__ import annotations

import pytest

from hil.bench import default_lathe
from hil.scripting import Machine
from mlc.signals import m2

SERVO_NOT_READY = 0x0A07


def _enabled(m: Machine, axis: str) -> bool:
    return m.runner.tx[m.axis_index(axis)].statusword & 0x6F == 0x27  # CiA 402 operation enabled


def _codes(m: Machine) -> list[tuple[int, str | None]]:
    return [(a.code, a.axis) for a in m.all_alarms()]


def _machine() -> Machine:
    m = Machine(default_lathe())
    m.power_up()
    return m


def _z_off(m: Machine) -> None:
    m.set("M21273", 1)  # Servo OFF of the channel's 2nd axis, Z
    m.cycle(20)
    assert not _enabled(m, "Z") and _enabled(m, "X")


@pytest.mark.parametrize("command", ["jog", "inc", "mpg", "home"])
def test_a_manual_command_of_an_axis_held_off_is_refused_with_0A07_and_it_never_moves(command):
    m = _machine()
    _z_off(m)
    {"jog": lambda: m.jog("Z", 1, 0.3), "inc": lambda: m.inc("Z", 2), "mpg": lambda: m.mpg("Z", 50),
     "home": lambda: (m.mode("HOME"), m.pulse(m2(1, 321)))}[command]()
    m.cycle(50)
    assert m.command("Z") == 100.0 and m.position("Z") == pytest.approx(100.0, abs=1e-9)
    assert not _enabled(m, "Z")
    assert (SERVO_NOT_READY, "Z") in _codes(m)
    # the manual generator did not run on unseen either (a jump once the axis is back ON)
    assert not m.mlc.manual.busy and m.mlc.manual.position[1] == 100.0


def test_the_other_axis_jogs_while_one_is_held_off():
    m = _machine()
    _z_off(m)
    x0 = m.position("X")
    m.jog("X", 1, 0.3)
    assert m.position("X") > x0 + 3.0 and _codes(m) == []
    assert m.command("Z") == 100.0 and not _enabled(m, "Z")


def test_servo_off_during_a_jog_stops_the_axis_under_control_then_disables_it_at_standstill():
    m = _machine()
    m.mode("JOG")
    m.mlc.mem.set_bit(m2(1, 385), True)  # Z+ held
    m.cycle(150)
    rows = []
    m.set("M21273", 1)
    for _ in range(400):
        m.cycle()
        rows.append((m.command("Z"), m.position("Z"), _enabled(m, "Z")))
    m.mlc.mem.set_bit(m2(1, 385), False)
    assert (SERVO_NOT_READY, "Z") in _codes(m)
    steps = [b[0] - a[0] for a, b in zip(rows, rows[1:])]
    # a controlled stop: the command's speed falls over tens of cycles (16.7 mm/s = 0.0167 mm/cycle), no jump
    assert steps[0] > 0.015 and all(0.0 <= s <= 0.0168 for s in steps)
    assert sum(1 for s in steps if s > 1e-6) > 10
    off = next(i for i, r in enumerate(rows) if not r[2])
    stop = max(i for i, s in enumerate(steps[:off - 1]) if s > 0.0) + 1
    assert stop < 30 < off  # the command stood after 30 ms, the key still held; the drive disabled after that
    assert not any(r[2] for r in rows[off:])  # and stays off
    assert all(abs(r[1] - rows[stop][0]) < 0.01 for r in rows[stop:])  # Z stands where its command stopped


def test_back_on_the_axis_jogs_again_from_where_it_stands_no_jump():
    m = _machine()
    _z_off(m)
    m.jog("Z", 1, 0.3)  # refused
    m.set("M21273", 0)
    m.cycle(20)
    m.reset()
    m.cycle(5)
    assert _enabled(m, "Z")
    before = m.command("Z")
    m.mode("JOG")
    m.mlc.mem.set_bit(m2(1, 385), True)
    last = before
    for _ in range(100):
        m.cycle()
        assert 0.0 <= m.command("Z") - last <= 0.0168  # from 100, at no more than the jog speed
        last = m.command("Z")
    m.mlc.mem.set_bit(m2(1, 385), False)
    m.settle("Z")
    assert before == 100.0 and m.position("Z") > 101.0


def test_servo_all_off_m2x012_refuses_an_inc_of_x():
    m = _machine()
    m.set("M21012", 0)
    m.cycle(20)
    assert not _enabled(m, "X") and not _enabled(m, "Z")
    m.inc("X", 1)
    m.cycle(20)
    assert m.command("X") == pytest.approx(m.position("X"), abs=1e-9) and (SERVO_NOT_READY, "X") in _codes(m)
