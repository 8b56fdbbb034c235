"""Manual motion through the special relays (MPG, JOG, INC, HOME, interlocks), feed hold and
E-stop, on the simulated bench with the default lathe MLC."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.bench import default_lathe
from hil.scripting import Machine


@pytest.fixture
def machine() -> Machine:
    m = Machine(default_lathe())
    m.power_up()
    return m


@pytest.mark.parametrize("pulses", [1, 37, -250])
def test_mpg_moves_pulses_times_ratio_times_unit(machine, pulses):
    x0 = machine.command("X")
    machine.mpg("X", pulses, ratio=10)
    assert machine.command("X") - x0 == pytest.approx(pulses * 10 * 0.001, abs=1e-9)
    assert machine.position("X") - x0 == pytest.approx(pulses * 10 * 0.001, abs=2e-4)
    assert machine.get("M31003") == 1  # MPG mode status


def test_mpg_counter_wraps_at_16_bits(machine):
    machine._mpg_count = 0xFFF0
    machine.mlc.mem.set_u16(30004, 0xFFF0)
    z0 = machine.command("Z")
    machine.mpg("Z", 40, ratio=100)  # crosses 0xFFFF → 0x0000
    assert machine.command("Z") - z0 == pytest.approx(4.0, abs=1e-9)


def test_jog_is_hold_to_run_at_the_jog_speed(machine):
    z0 = machine.command("Z")
    machine.jog("Z", -1, 0.5, percent=50)  # N2.030 1000 mm/min × 50 %
    moved = z0 - machine.command("Z")
    assert moved == pytest.approx(0.5 * 500 / 60.0, rel=0.01)


def test_inc_steps_by_d2x014_units(machine):
    x0 = machine.command("X")
    machine.inc("X", -3, units=1234)
    assert machine.command("X") - x0 == pytest.approx(-3 * 1.234, abs=1e-9)


def test_interlock_blocks_the_locked_direction_only(machine):
    machine.set("M21336")  # X positive direction locked
    x0 = machine.command("X")
    machine.jog("X", 1, 0.2)
    assert machine.command("X") == pytest.approx(x0, abs=1e-12)
    machine.jog("X", -1, 0.2)
    assert machine.command("X") < x0 - 1.0


def test_homing_sets_homed_and_done_status(machine):
    assert machine.get("M31320") == 0
    took = machine.home("Z")
    assert machine.command("Z") == pytest.approx(0.0, abs=1e-9)
    assert machine.get("M31321") == 1 and machine.get("M31337") == 1 and machine.get("M31353") == 1
    assert took > 0.1  # 100 mm at the homing speed, not a jump


def _stop_distance(v: float, a: float, j: float) -> float:
    """Shortest jerk-limited stop from speed v with zero acceleration."""
    if v >= a * a / j:
        return v * (v / a + a / j) / 2.0
    return v * math.sqrt(v / j)


def test_feed_hold_stops_within_the_jerk_limited_distance_and_resumes(machine):
    ch = machine.start_program("G98 G01 W-80. F6000\nM30\n")
    machine.wait(0.4)  # at 100 mm/s on Z
    samples = []
    machine.watchers.append(lambda m: samples.append(m.command("Z")))
    z_hold = machine.command("Z")
    machine.set("M21001")  # feed hold relay: acted on at the next NC scan
    machine.wait(0.3)
    machine.set("M21001", False)
    assert machine.get("M31017") == 1 and machine.get("M31016") == 0
    z_stop = machine.command("Z")
    lim = machine.bench.axes[1].limits
    cfg = machine.bench.motion_config()
    share = cfg.share_tangential  # the path profile's share of the axis budget
    ideal = _stop_distance(100.0, share * lim.max_acceleration, share * lim.max_jerk)
    latency = 100.0 * 0.002  # the relay is read at the next NC scan, the stop starts the cycle after
    # The position filter (N1.036/N1.037) lags the interpolation by its group delay at 100 mm/s.
    n1, n2 = cfg.filter_cycles()
    lag = 100.0 * (n1 - 1 + n2 - 1) / 2.0 * cfg.cycle
    assert ideal + lag - 1e-6 <= z_hold - z_stop <= ideal + lag + latency
    assert abs(samples[-1] - samples[-2]) < 1e-9  # standing still
    machine.pulse(21000)  # cycle start resumes
    machine.wait_until(lambda: not ch.busy, 5.0)
    assert machine.command("Z") == pytest.approx(100.0 - 80.0, abs=1e-6)


def test_estop_brakes_on_the_drives_quick_stop_and_reset_enables_again(machine):
    """E-stop (M2x013) is a stop category 1 (decision B12): the NC stops interpolating and zeroes the
    spindle command within one cycle, every drive brakes on its own quick-stop ramp (CiA 402
    state 0x07, 0x6085) within the axis's acceleration, and is disabled at standstill. Released and
    reset, the drives are enabled again and the NC takes over where the axes stand."""
    machine.mdi("M03 S800")
    ch = machine.start_program("G98 G01 U-40. W-80. F6000\nM30\n")
    machine.wait(0.3)
    rows = []
    machine.watchers.append(lambda m: rows.append((m.position("Z"), m.runner.rx[2].target_velocity,
                                                   [tx.statusword & 0x6F for tx in m.runner.tx])))
    machine.estop()  # M21013 set, then one cycle
    machine.wait(0.3)
    assert machine.get("M31018") == 1
    assert [a.code for a in ch.alarms] == [0x0401]
    assert rows[0][1] == 0  # the spindle command is zero the first cycle after the relay
    assert all(sw == 0x07 for sw in rows[2][2])  # every drive in Quick Stop Active two cycles on
    z = np.array([r[0] for r in rows])
    a = np.abs(np.diff(z, 2)) / machine.bench.cycle ** 2
    assert a.max() <= machine.bench.axes[1].limits.max_acceleration * 1.01  # braked, not frozen dead
    assert abs(z[-1] - z[-2]) < 1e-9  # standing
    assert not any(m.enabled for m in machine.runner.masters)  # disabled at standstill
    machine.estop(False)
    machine.reset()
    machine.wait(0.05)
    assert machine.get("M31019") == 1 and machine.get("M31025") == 0 and not ch.busy
    assert all(m.enabled for m in machine.runner.masters)
    z0 = machine.position("Z")
    assert machine.command("Z") == pytest.approx(z0, abs=1e-6)  # the NC took over the braked position
    machine.mdi("G98 G01 W5. F3000")
    assert machine.command("Z") == pytest.approx(z0 + 5.0, abs=1e-6)  # no jump: 5 mm on from there




def test_0x1603_oscillation_enable_in_home_mode_stops_and_refuses_the_homing(machine):
    """App. A 0x1603 'Oscillation function is not allowed in the home mode. The M2x264 oscillation function cannot
    be enabled in the homing mode.' and N App. B M2x264 'Only available on modes other than HOME and EDIT': Z's
    homing is under way when the MLC turns M2x264 on; the NC raises 0x1603, Z stops short of its home position
    (0) without the homing-done status, and a new home trigger while M2x264 stays on is refused with 0x1603 too.
    With M2x264 off and a reset, the same trigger homes Z."""
    machine.mode("HOME")
    z0 = machine.command("Z")
    machine.pulse(21321)  # M2x321: Z homing
    machine.wait(0.2)
    machine.set("M21264")
    machine.wait(1.0)
    codes = [a.code for a in machine.mlc.link.alarms]
    assert codes == [0x1603]
    z_stop = machine.command("Z")
    assert 1.0 < z0 - z_stop < z0 - 1.0  # moved towards home, stopped well before it
    assert machine.get("M31337") == 0  # Z homing not done
    machine.pulse(21321)
    machine.wait(0.5)
    assert [a.code for a in machine.mlc.link.alarms] == [0x1603, 0x1603] and machine.command("Z") == z_stop
    machine.set("M21264", False)
    machine.pulse(21004)  # M2x004 reset
    assert machine.home("Z") > 0.0 and machine.command("Z") == pytest.approx(0.0, abs=1e-9)
