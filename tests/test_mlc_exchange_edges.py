"""The NC side of the exchange skips work while the MLC's relays hold their level (issue 17): the
spindle alarm relays, the user alarms, the command relays and the #25000 variable ranges are only
looked at when they changed. These check that every change is still seen, in the cycle it happens,
on the real channel and the default lathe MLC (the scripting Machine)."""

from __future__ import annotations

from types import SimpleNamespace

from hil.bench import default_lathe
from hil.scripting import Machine
from mlc.machine import Mlc
from nc.interp.variables import MlcExchange


def _machine() -> Machine:
    bench = default_lathe()
    m = Machine(bench, Mlc(None, axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config()))
    m.power_up()
    return m


def _codes(m: Machine, code: object) -> int:
    return sum(1 for a in m.mlc.link.alarms if a.code == code)


def test_spindle_alarm_relay_raises_on_each_rising_edge_only():
    m = _machine()
    m.cycle(5)
    assert _codes(m, 0x0C0A) == 0
    m.set("M21711", 1)  # 1st spindle alarm
    m.cycle(1)
    assert _codes(m, 0x0C0A) == 1
    m.cycle(20)  # held: no new edge
    assert _codes(m, 0x0C0A) == 1
    m.set("M21711", 0)
    m.cycle(3)
    m.set("M21727", 1)  # 2nd spindle's alarm, after quiet cycles
    m.cycle(1)
    assert [a.message for a in m.mlc.link.alarms if a.code == 0x0C0A][-1].endswith("spindle 2")
    m.set("M21711", 1)
    m.cycle(1)
    assert _codes(m, 0x0C0A) == 3


def test_user_alarm_raised_again_after_it_was_cleared():
    m = _machine()
    m.cycle(5)
    m.mlc.mem.set_alarm(12)
    m.cycle(2)
    assert _codes(m, "A12") == 1 and m.get("M31040") == 1
    m.mlc.mem.set_alarm(12, False)
    m.cycle(5)
    assert m.get("M31040") == 0
    m.mlc.mem.set_alarm(12)
    m.cycle(1)
    assert _codes(m, "A12") == 2


def test_variable_ranges_follow_every_change_after_quiet_cycles():
    m = _machine()
    ex = MlcExchange()
    m.mlc.link.variables = SimpleNamespace(mlc=ex)
    m.cycle(3)
    assert ex.read(25000) == 0.0
    m.set("M21128", 1)  # -> #25000
    m.cycle(1)
    assert ex.read(25000) == 1.0
    m.cycle(10)
    m.mlc.mem.set_s16(21130, -7)  # D21130 -> #25130
    m.cycle(1)
    assert ex.read(25130) == -7.0 and ex.read(25000) == 1.0
    m.set("M21128", 0)
    m.cycle(1)
    assert ex.read(25000) == 0.0


def test_feed_hold_and_cycle_start_edges_after_long_quiet_stretches():
    m = _machine()
    ch = m.start_program("G98 G01 W-30. F300\nM30\n")  # Z at 5 mm/s for 6 s
    m.cycle(300)  # the command relays unchanged for hundreds of cycles
    assert ch.state.name == "RUNNING"
    m.set("M21001", 1)  # feed hold: a rising edge
    m.cycle(2)
    m.set("M21001", 0)
    m.wait(0.5)
    z = m.position("Z")
    m.wait(0.5)
    assert ch.state.name == "HOLD" and m.get("M31017") == 1 and m.position("Z") == z
    m.cycle_start()
    m.wait(0.5)
    assert ch.state.name == "RUNNING" and m.position("Z") < z - 1.0
