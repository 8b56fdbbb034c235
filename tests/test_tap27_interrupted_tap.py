"""An interrupted rigid tap and its recovery (NC5 G command guide §3.13.2 G74/G84 note (6), manual line 3136;
App. B M2x080, M2x707, M3x707; decisions mlc M26-1 … M26-9).

The mill bench (benches/mill-3axis.toml) with the Delta MLC an exercising script runs: a G84 at S600 F900 (G94:
pitch 900 / 600 = 1.5 mm) to Z-15 from R2; the E-stop hits while Z is in the hole."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hil.scripting import Machine, mlc_setup
from hil.session import load_bench, make_link

ROOT = Path(__file__).resolve().parent.parent
MILL = str(ROOT / "benches" / "mill-3axis.toml")
TAP = "G17 G90 G94 G00 X0. Y0. Z10.\nM03 S600\nG99 G84 X0. Y0. Z-15. R2. F900.\nG80 G00 Z10.\nM30\n"
TAP_G95 = "G17 G90 G95 G00 X0. Y0. Z10.\nM03 S600\nG99 G84 X0. Y0. Z-15. R2. F1.5\nG80 G00 Z10.\nM30\n"
TAP_G74 = "G17 G90 G94 G00 X0. Y0. Z10.\nM04 S800\nG99 G74 X0. Y0. Z-12. R3. F1000.\nG80 G00 Z10.\nM30\n"


def codes(alarms) -> list[tuple[str, int | None]]:
    return [(a.code_text, a.line) for a in alarms]


@pytest.fixture
def machine():
    bench = load_bench(MILL, None, None)
    mlc, _, _ = mlc_setup(bench, "lathe", None, 0.5)
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    yield m
    m.close()


def interrupt(m: Machine, program: str = TAP, below: float = -5.0, how: str = "estop"):
    """Run `program`, E-stop (or reset) once Z's command is below `below`, then release and reset: the channel."""
    ch = m.start_program(program)
    tapping = []
    m.watchers.append(lambda mm: tapping.append(mm.get("M31707")) if mm.command("Z") < 1.9 else None)
    m.wait_until(lambda: m.command("Z") < below, 20.0, "Z in the hole")
    m.watchers.clear()
    assert tapping and all(tapping), "M3x707 is ON all the way into the hole"
    if how == "estop":
        m.estop()
        m.wait(0.5)
        m.estop(False)
    m.reset()
    m.wait(0.5)
    return ch


def test_an_estop_mid_tap_raises_0x0270_0x0c09_and_keeps_the_tapping_data(machine):
    ch = interrupt(machine)
    assert codes(ch.alarms) == [("0x0401", None), ("0x0270", 3), ("0x0C09", 3)]
    rec = ch.tap.record
    assert rec is not None and rec.cause == "emergency stop" and rec.stroke == "tap"
    assert (rec.axis, rec.hole, rec.r_level, rec.bottom) == ("Z", {"X": 0.0, "Y": 0.0}, 2.0, -15.0)
    assert -5.1 < rec.reached < -5.0  # the setpoint where the E-stop froze it
    assert rec.pitch == pytest.approx(1.5) and rec.hand == 1 and not rec.per_rev
    assert (rec.feed, rec.rpm, rec.spindle, rec.line) == (900.0, 600.0, 1, 3)
    # the status outlives the reset: the spindle stays at rest although the MLC's M2x704 (M03) is still ON
    assert machine.get("M21704") == 1 and abs(machine.get_rpm()) < 1.0
    assert machine.get("M31707") == 0  # nothing taps now


@pytest.mark.parametrize("program, pitch, hand, per_rev, r_level", [(TAP_G95, 1.5, 1, True, 2.0),
                                                                    (TAP_G74, 1.25, -1, False, 3.0)])
def test_the_record_keeps_g95_and_the_left_hand_of_g74(machine, program, pitch, hand, per_rev, r_level):
    ch = interrupt(machine, program)
    rec = ch.tap.record
    assert rec is not None and codes(ch.alarms)[1:] == [("0x0270", 3), ("0x0C09", 3)]
    assert (rec.pitch, rec.hand, rec.per_rev, rec.r_level) == (pytest.approx(pitch), hand, per_rev, r_level)


def test_a_reset_mid_tap_interrupts_it_too(machine):
    ch = interrupt(machine, how="reset")
    assert codes(ch.alarms) == [("0x0270", 3), ("0x0C09", 3)]
    assert ch.tap.record is not None and ch.tap.record.cause == "reset"


def test_hil_run_reset_mid_tap_ends_with_both_alarms_at_the_cycle_line(hil, program):
    # before: a reset in the hole ended the run "STOPPED: ... a reset flushes it" with no alarm
    r = hil("run", program(TAP), "--bench", MILL, "--at", "Z<-5:reset", "--no-check", "--json", "--no-progress")
    out = json.loads(r.out.strip().splitlines()[-1])
    assert r.code == 1 and [(a["code"], a["line"]) for a in out["alarms"]] == [("0x0270", 3), ("0x0C09", 3)]
    assert "the reset interrupted a tapping cycle" in out["alarms"][0]["message"]


def test_axis_moves_and_spindle_starts_are_refused_while_the_status_holds(machine):
    interrupt(machine)
    z = machine.position("Z")
    machine.mdi("G01 Z20. F500.", timeout=5)
    ch = machine.runner.channel
    assert codes(ch.alarms) == [("0x0270", 1)] and machine.position("Z") == pytest.approx(z, abs=1e-4)
    machine.reset()
    machine.mdi("M03 S500", timeout=5)
    ch = machine.runner.channel
    assert codes(ch.alarms) == [("0x0C09", 1)] and abs(machine.get_rpm()) < 1.0
    assert ch.tap.holds  # refusing is no recovery


def test_jog_and_mpg_are_refused_while_the_status_holds(machine):
    interrupt(machine)
    z = machine.position("Z")
    machine.jog("Z", 1, 0.3)  # the JOG key of Z held 0.3 s
    ch = machine.runner.channel
    assert codes(ch.alarms)[-1] == ("0x0270", None) and "JOG command is refused" in ch.alarms[-1].message
    assert machine.position("Z") == pytest.approx(z, abs=1e-6)
    machine.reset()
    machine.mpg("Z", pulses=50, ratio=10)  # 0.5 mm of detents: none is run, one alarm
    # one more 0x0270 (after the E-stop's and the JOG's): a turning handwheel is one refusal
    assert [a.code_text for a in machine.runner.channel.alarms].count("0x0270") == 3
    assert machine.position("Z") == pytest.approx(z, abs=1e-6)
    machine.reset()
    machine.pulse(21080)  # M21080 cancels: the same keys move Z again
    machine.jog("Z", 1, 0.3)
    assert machine.position("Z") > z + 1.0


def trace_retraction(machine: Machine, program: str) -> dict[str, np.ndarray]:
    """Run `program` (MDI) recording every cycle: Z command and actual, the spindle's position setpoint and actual
    angle (degrees), its drive mode, M3x707."""
    n = len(machine.runner.axes)
    sc = machine.runner.scales[n]
    rows: list[tuple] = []
    machine.watchers.append(lambda m: rows.append((m.command("Z"), m.position("Z"),
                                                   sc.to_units(m.runner.rx[n].target_position),
                                                   m.runner.spindle_actual_angle(), m.runner.rx[n].mode,
                                                   m.get("M31707"))))
    machine.mdi(program, timeout=20)
    machine.watchers.clear()
    cols = np.array(rows, dtype=float)
    return dict(zip(("z", "z_act", "deg", "deg_act", "mode", "m3x707"), cols.T))


def test_g84_48_retracts_to_r_with_the_spindle_reversed_and_locked_to_the_pitch(machine):
    interrupt(machine)
    z0 = machine.position("Z")
    c = trace_retraction(machine, "G84.48\nG00 Z30.\n")
    ch = machine.runner.channel
    assert not ch.alarms and not ch.tap.holds and ch.tap.log[-1][0] == "G84.48"
    sync = c["mode"] == 8  # the spindle drive follows in position mode (CSP) while Z retracts
    k = np.flatnonzero(sync)
    assert len(k) > 100 and np.all(np.diff(k) == 1)
    z, deg = c["z"][k], c["deg"][k]
    assert z[0] == pytest.approx(z0, abs=2e-3) and z[-1] == pytest.approx(2.0, abs=1e-6)  # the R point
    assert np.all(np.diff(z) >= 0) and np.all(np.diff(deg) <= 0)  # up, the spindle against M03
    # every cycle: Z's travel is the spindle's turns times the pitch (1.5 mm), to a drive count (Z's is 2.5 nm)
    np.testing.assert_allclose(z - z[0], -(deg - deg[0]) / 360.0 * 1.5, rtol=0, atol=3e-6)
    assert (deg[0] - deg[-1]) / 360.0 * 1.5 == pytest.approx(2.0 - z0, abs=3e-3)  # from where Z stood
    # the drives follow it: the thread's phase (Z's actual travel against the spindle's actual turns) stays
    # within 5 µm in every cycle of the retraction
    za, da = c["z_act"][k], c["deg_act"][k]
    assert np.max(np.abs((za - za[0]) + (da - da[0]) / 360.0 * 1.5)) < 0.005
    assert np.all(c["m3x707"][k[1:]] == 1)  # M3x707 ON while the tap is retracted (decision M26-5)
    assert c["m3x707"][-1] == 0 and c["mode"][-1] == 9  # then off, and the drive back in CSV
    assert machine.position("Z") == pytest.approx(30.0, abs=0.01)  # the program read on from R


def test_g84_48_without_an_interrupted_tap_does_nothing_and_g84_49_is_no_code(machine):
    machine.mdi("G00 Z5.")
    machine.mdi("G84.48\nG01 Z4. F300.\n")
    ch = machine.runner.channel
    assert not ch.alarms and machine.position("Z") == pytest.approx(4.0, abs=0.01)
    machine.mdi("G84.49")
    assert codes(machine.runner.channel.alarms) == [("0x021D", 1)]


def test_m2x080_cancels_the_status_without_motion(machine):
    interrupt(machine)
    machine.set("M21704", False)  # the ladder drops M03's relay, or the spindle turns again once the status ends
    z, deg = machine.position("Z"), machine.runner.spindle_actual_angle()
    machine.pulse(21080)  # M21080: M2x080 Canceling Tapping Interrupt Status
    machine.wait(0.2)
    ch = machine.runner.channel
    assert not ch.tap.holds and ch.tap.log[-1][0] == "M2x080"
    assert machine.position("Z") == pytest.approx(z, abs=1e-6)
    assert machine.runner.spindle_actual_angle() == pytest.approx(deg, abs=1e-6)
    machine.mdi("G01 Z12. F600.")  # moves are no longer refused
    assert not machine.runner.channel.alarms and machine.position("Z") == pytest.approx(12.0, abs=0.01)


def test_m2x707_from_the_mlc_retracts_as_g84_48_does(machine):
    interrupt(machine)
    n = len(machine.runner.axes)
    modes = []
    machine.watchers.append(lambda m: modes.append((m.runner.rx[n].mode, m.get("M31707"))))
    machine.pulse(21707)  # M21707: M2x707 1st Spindle Retraction After Tapping
    t = machine.wait_until(lambda: not machine.runner.channel.busy, 5.0, "the retraction")
    ch = machine.runner.channel
    assert t > 0.3 and not ch.tap.holds and ch.tap.log[-1][0] == "M2x707"
    assert machine.command("Z") == 2.0 and (8, 1) in modes
    machine.wait(0.2)
    assert machine.position("Z") == pytest.approx(2.0, abs=1e-3)


PANEL_MLC = """from mlc import lathe

SCAN_ON_CHANGE = False


def setup(mlc):
    lathe.setup(mlc)


def scan(mlc):
    lathe.scan(mlc)
    # the machine's panel: key M100 retracts an interrupted tap, key M101 cancels the status; the lamp Y0 shows
    # that the spindle is in the rigid tapping
    mlc.set("SPINDLE1_TAP_RETRACT", mlc.m("M100"))
    mlc.set("CANCEL_TAP_INTERRUPT", mlc.m("M101"))
    mlc.set("Y0", mlc.m("SPINDLE1_RIGID_TAPPING"))
"""


def test_a_user_mlc_drives_the_recovery_by_name(tmp_path):
    module = tmp_path / "panel_mlc.py"
    module.write_text(PANEL_MLC)
    bench = load_bench(MILL, None, None)
    mlc, _, _ = mlc_setup(bench, str(module), None, 0.5)
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    try:
        lamp = []
        m.watchers.append(lambda mm: lamp.append(mm.get("Y0")))
        interrupt(m)
        assert 1 in lamp and m.get("Y0") == 0
        m.set("M100", 1)  # the key pressed: the user scan raises M2x707, the NC retracts
        m.wait_until(lambda: m.runner.channel.busy, 0.1, "the retraction to start")
        m.wait_until(lambda: not m.runner.channel.busy, 5.0, "the retraction to end")
        m.set("M100", 0)
        assert m.runner.channel.tap.log[-1][0] == "M2x707" and m.command("Z") == pytest.approx(2.0, abs=1e-6)
    finally:
        m.close()


def test_a_reset_during_the_retraction_stops_it_short_and_the_status_stays(machine):
    interrupt(machine)
    machine.pulse(21707)
    machine.wait_until(lambda: machine.command("Z") > -2.0, 5.0, "Z half way")
    machine.reset()
    machine.wait_until(lambda: not machine.runner.channel.busy, 5.0, "the stop")
    ch = machine.runner.channel
    assert ch.tap.holds and -2.0 < machine.command("Z") < 2.0
    assert codes(ch.alarms)[-2:] == [("0x0270", 3), ("0x0C09", 3)]
    machine.mdi("G84.48")  # and G84.48 takes it from there to R
    assert not machine.runner.channel.tap.holds and machine.command("Z") == 2.0


def test_hil_run_traces_m3x707_through_the_whole_tapping_cycle(hil, program, tmp_path):
    # M26-5: ON from the first stroke into the hole until the G80 G00 after the cycle; every cycle with Z in the
    # hole is ON (the reversal at the bottom included), before the cycle and after it OFF
    trace = tmp_path / "t.csv"
    r = hil("run", program(TAP.replace("M30", "M05\nM30")), "--bench", MILL, "--trace-signals", "M31707",
            "--trace", trace)
    assert r.code == 0, r.out + r.err
    c = np.genfromtxt(trace, delimiter=",", names=True)
    on = c["M31707"] == 1
    k = np.flatnonzero(on)
    assert len(k) > 2000 and np.all(np.diff(k) == 1)  # one span
    below = np.flatnonzero(c["Z_cmd"] < 2.0 - 1e-6)
    # the NC's outputs of a cycle are written before its step: ON from the scan after Z's first step below R
    assert np.all(on[below + 1]) and k[0] == below[0] + 1 and c["line"][k[0]] == 3
    assert c["line"][k[-1] + 1] == 4 and c["Z_cmd"][-1] == pytest.approx(10.0, abs=1e-6)  # until G80 G00 Z10.
    assert not np.any(on[k[-1] + 1:])


def test_the_example_script_interrupts_a_tap_and_recovers_with_g84_48(hil):
    r = hil("script", ROOT / "examples" / "scripts" / "tap_recovery.py", "--bench", MILL)
    assert r.code == 0, r.out + r.err  # every alarm met was cleared by a reset
    assert "interrupted: 0x0401 (line None), 0x0270 (line 3), 0x0C09 (line 3)" in r.out
    assert "record: Z setpoint -5.00" in r.out and "R 2.0000, pitch 1.5000 mm, G94 F900 S600, line 3" in r.out
    assert "G01 while the status holds: 0x0270 Z -5.1" in r.out
    # Z from where the E-stop braked it (-5.1555) to R: 7.1555 mm = 4.770 turns of 1.5 mm, against M03
    assert "G84.48: Z 2.0000 after 0.5" in r.out and "the spindle -4.77" in r.out and "status ended" in r.out
    assert "Z      100.0000 →    10.0000" in r.out and "modes CSV/CSP/CSV" in r.out
