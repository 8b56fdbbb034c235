"""App. A 0x0A01-0x0A04 in the manual modes (issue 19): a JOG/INC/MPG move is clamped at the software limit, so
there the axis reaches it. App. A 0x0A01 / 0x0A03: "The axis has reached the software limit position ... The
machine must move away from the limit position before system reset"; 0x0A02 / 0x0A04: "After moving away from the
... software limit, this alarm will be displayed. Please reset the machine." Simulated lathe bench, default MLC."""

from __future__ import annotations

import dataclasses

import pytest

from hil.bench import default_lathe
from hil.scripting import Machine


def _machine(z_limits=(95.0, 200.0)) -> Machine:
    bench = default_lathe()
    bench.axes[1] = dataclasses.replace(bench.axes[1], soft_limits=z_limits)  # Z starts at 100
    m = Machine(bench)
    m.power_up()
    return m


def _codes(m: Machine) -> list[int]:
    return [a.code for a in m.mlc.link.alarms]


def test_0x0a01_then_0x0a02_jog_onto_the_first_segment_move_away_and_reset():
    m = _machine()
    m.jog("Z", -1, 1.0)  # 16.7 mm/s towards the lower limit 95: reached after 0.3 s
    assert m.command("Z") == pytest.approx(95.0, abs=1e-9) and m.position("Z") == pytest.approx(95.0, abs=1e-3)
    assert _codes(m) == [0x0A01] and m.mlc.link.alarms[0].axis == "Z"
    m.reset()  # still on the limit: the alarm stays
    assert _codes(m) == [0x0A01]
    m.jog("Z", 1, 0.2)  # away from it
    assert m.command("Z") > 96.0
    assert _codes(m) == [0x0A01, 0x0A02]
    m.reset()
    m.cycle(5)
    assert _codes(m) == []
    m.jog("Z", 1, 0.2)  # moving on inside the window raises nothing
    assert _codes(m) == []


def test_0x0a03_then_0x0a04_inc_onto_the_second_segment_of_g10_l21():
    """N§3.8.3.7 G10 L21 P3 (2nd segment, positive side) at Z110 inside the bench's 1st segment (up to 200): INC
    steps of 4 mm from Z100 stop at 110, 0x0A03; one step back, 0x0A04; a reset clears it."""
    m = _machine()
    m.mdi("G10 L21 P3 Z110.\nM30\n")
    m.reset()
    assert _codes(m) == []
    m.inc("Z", 3, units=4000)
    assert m.command("Z") == pytest.approx(110.0, abs=1e-9)
    assert _codes(m) == [0x0A03]
    m.inc("Z", -1, units=4000)
    assert m.command("Z") == pytest.approx(106.0, abs=1e-9)
    assert _codes(m) == [0x0A03, 0x0A04]
    m.reset()
    m.cycle(5)
    assert _codes(m) == []


def test_m2x368_turns_the_first_segment_off_for_manual_moves():
    """M2x368 (software limit of the 1st axis... per axis, off): the jog runs past 95 with no alarm."""
    m = _machine()
    m.set("M21369")  # Z (2nd axis)
    m.jog("Z", -1, 0.6)
    assert m.command("Z") < 92.0 and _codes(m) == []


def test_0x0402_then_0x0a06_jog_onto_the_drive_limit_switch_move_away_and_reset():
    """App. A 0x0A06 'The status of hardware limit needs to be cleared. After moving away from the hardware limit,
    this alarm will be displayed. Please reset the machine.': Z's drive has its positive limit switch at 105. The
    jog runs onto it: the drive stops Z there and the NC raises 0x0402 (decisions B16) and holds the jog command at
    the switch instead of running on. Jogging further into it does nothing; a reset on the switch keeps the limit
    alarm; jogging away raises 0x0A06; a reset clears it, and the next hit raises 0x0402 again."""
    bench = default_lathe()
    z = bench.axes[1]
    bench.axes[1] = dataclasses.replace(z, drive=dataclasses.replace(z.drive, positive_limit=z.scaling.to_counts(105.0)))
    m = Machine(bench)
    m.power_up()
    m.jog("Z", 1, 1.0)  # from 100 at 16.7 mm/s: on the switch after 0.3 s
    assert m.position("Z") == pytest.approx(105.0, abs=1e-3) and m.command("Z") < 105.1  # the command stopped too
    assert [(a.code, a.axis) for a in m.runner.result.alarms] == [(0x0402, "Z")]
    m.jog("Z", 1, 0.3)  # into the switch: locked
    assert m.command("Z") < 105.1 and _codes(m) == []
    m.reset()
    assert _codes(m) == [0x0402]  # still on the switch
    m.jog("Z", -1, 0.3)
    assert m.position("Z") == pytest.approx(100.0, abs=0.05)  # 5 mm away: the move started at the switch
    assert _codes(m) == [0x0402, 0x0A06]
    m.reset()
    m.cycle(5)
    assert _codes(m) == []
    m.jog("Z", 1, 1.0)
    assert [a.code for a in m.runner.result.alarms] == [0x0402, 0x0402]


def test_0x1601_then_0x1602_the_nc_homing_search_runs_into_the_limit_switch():
    """App. A 0x1601 'The hardware limit is triggered during homing ... Check if the homing search direction is
    correct' and 0x1602 'This alarm will be triggered after clearing 0x1601 hardware limit alarm': Z's home switch
    (active below 40) lies beyond its negative limit switch (60), so the NC's homing search (HOME mode, M2x321)
    meets the limit first: 0x1601, Z held on the switch, not homed. A reset on the switch shows 0x1602; moving off
    raises 0x0A06 and the next reset clears everything."""
    from hil.scripting import ScriptError

    bench = default_lathe()
    z = bench.axes[1]
    bench.axes[1] = dataclasses.replace(z, drive=dataclasses.replace(
        z.drive, home_switch=z.scaling.to_counts(40.0), negative_limit=z.scaling.to_counts(60.0)))
    m = Machine(bench)
    m.power_up()
    with pytest.raises(ScriptError, match="Z homing not reached"):
        m.home("Z", timeout=5.0)
    assert _codes(m) == [0x1601] and m.get("M31337") == 0  # not homed
    assert m.position("Z") == pytest.approx(60.0, abs=1e-3) and m.command("Z") == pytest.approx(60.0, abs=0.02)
    m.reset()
    assert _codes(m) == [0x1602]
    m.jog("Z", 1, 0.3)
    assert m.position("Z") == pytest.approx(65.0, abs=0.05)
    assert _codes(m) == [0x1602, 0x0A06]
    m.reset()
    m.cycle(5)
    assert _codes(m) == []
