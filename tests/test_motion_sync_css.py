"""Issue 5 §4: constant surface speed (G96/G97) on the bench: the spindle drive's commanded speed
follows 1000·V/(π·D) as the tool faces towards the centre, clamped by G50 S."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.scripting import build_mlc
from hil.session import sim_slaves
from nc.program import parse_program

from conftest import ROOT

FACING = """G21 G18 G99
G50 S2000
G96 S150 M03
G00 X80. Z2.
G01 Z0. F0.2
X10. F0.1
G97 S500
G00 Z5.
M30
"""

# The drive is given 0x60FF in 0.1 rpm (Delta ASDA), so a commanded speed is within half a unit.
RPM_RES = 0.05


def run(text: str):
    bench = default_lathe()
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    sc = bench.spindles[0].scaling
    rows = []

    def grab(r):
        if r.channel is not None:
            rows.append((r.line, r._commands[0], sc.drive_to_rpm(r.rx[2].target_velocity),
                         r.spindle_actual_rpm()))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    return result, np.array(rows)


def test_facing_under_g96_raises_the_spindle_speed_clamped_by_g50():
    result, rows = run(FACING)
    assert result.ok, result.alarms
    face = rows[rows[:, 0] == 6]
    x, cmd = face[:, 1], face[:, 2]
    d = 2.0 * x  # no offsets: machine X radius = half the work diameter
    want = np.minimum(1000.0 * 150.0 / (math.pi * d), 2000.0)
    # the command tracks the surface-speed law at every cycle (1 count/s of rounding)
    assert np.allclose(cmd, want, rtol=1e-3, atol=RPM_RES)
    # it rises as X falls and stops at the G50 limit
    assert np.all(np.diff(cmd) >= -1e-6)
    assert cmd[0] < 600.0 and cmd.max() == np.float64(cmd.max()) and abs(cmd.max() - 2000.0) < 0.01
    clamped = d < 1000.0 * 150.0 / (math.pi * 2000.0)
    assert clamped.any() and np.allclose(cmd[clamped], 2000.0, atol=RPM_RES)
    # the drive really speeds up, and feed per rev follows its measured speed
    assert face[-1, 3] > 2.0 * face[0, 3]


def test_g97_returns_to_the_programmed_speed():
    result, rows = run(FACING)
    assert result.ok, result.alarms
    after = rows[rows[:, 0] == 8]
    assert abs(after[len(after) // 2, 2] - 500.0) < 0.01


def test_g96_surface_speed_never_exceeds_the_spindle_maximum():
    # without G50 the bench's spindle maximum (4000 rpm) is the clamp, even at the centre
    result, rows = run(FACING.replace("G50 S2000", "(no G50)").replace("X10. F0.1", "X0. F0.1"))
    assert result.ok, result.alarms
    face = rows[rows[:, 0] == 6]
    assert abs(face[:, 2].max() - 4000.0) < 0.01


def test_g50_clamp_also_holds_under_g97(hil, program, tmp_path):
    """A39: G50 S caps the spindle even in constant-rpm mode (lathe manual E-L32)."""
    import csv

    prog = program("G21 G18 G98\nG50 S800\nG97 S1500 M03\nG04 P500\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--trace", trace)
    assert r.code == 0, r.out + r.err
    rpm = [float(row["S1_rpm_act"]) for row in csv.DictReader(open(trace))]
    assert max(rpm) == pytest.approx(800.0, rel=0.01)


# ---- G96 from the S word on, before any move (session 3, motion decisions 30) -------------------
# The default lathe starts at machine X60 (radius); `G00 X100.` puts the tool at diameter 100, where
# 200 m/min is 1000·200/(π·100) = 636.6 rpm.

AT_100 = 1000.0 * 200.0 / (math.pi * 100.0)


def run_phases(text: str, params: dict[str, float] | None = None):
    """Run on the default lathe with the Delta lathe MLC (M03 waits for speed reached); per cycle
    (value of the pending aux or -1, X command, drive's commanded rpm)."""
    rows, _ = run_override(text, 100, params)
    return rows[:, :3]


def spinning(rows):
    return rows[np.abs(rows[:, 2]) > 0.5]


def test_g96_m03_starts_at_the_css_rpm_of_the_current_x_before_any_move():
    rows = run_phases("G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P100\nM05\nM30\n")
    on = spinning(rows)
    assert on[0, 1] == pytest.approx(50.0)  # X has not moved since the G00
    # the very first command the drive gets is the CSS speed, never S200 read as rpm
    assert on[0, 2] == pytest.approx(AT_100, abs=RPM_RES)
    assert np.allclose(on[:, 2], AT_100, atol=RPM_RES)


def test_g96_before_any_move_is_clamped_by_g50_s_and_by_the_spindle_maximum():
    rows = run_phases("G21 G18 G99\nG00 X100. Z5.\nG50 S500\nG96 S200 M03\nG04 P50\nM30\n")
    assert np.allclose(spinning(rows)[:, 2], 500.0, atol=RPM_RES)
    # no G50: the bench's spindle maximum (4000 rpm) caps 200 m/min at diameter 1 (63 662 rpm)
    rows = run_phases("G21 G18 G99\nG00 X1. Z5.\nG96 S200 M03\nG04 P50\nM30\n")
    assert np.allclose(spinning(rows)[:, 2], 4000.0, atol=RPM_RES)


def test_g97_s_is_exactly_rpm_and_g97_alone_keeps_the_speed_it_had():
    rows = run_phases("G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG97 S800\nG04 P50\nM30\n")
    assert spinning(rows)[-1, 2] == pytest.approx(800.0, abs=RPM_RES)
    # G97 without S: the spindle stays at the speed G96 had reached (Fanuc's rule), while X moves on
    rows = run_phases("G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG97\nG00 X50.\nG04 P50\nM30\n")
    on = spinning(rows)
    assert on[-1, 1] == pytest.approx(25.0)
    assert np.allclose(on[:, 2], AT_100, atol=RPM_RES)


def test_s_under_g96_changes_the_surface_speed_at_once_and_m05_m03_restarts_on_it():
    text = "G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P50\nS100\nM05\nG00 X50.\nM03\nG04 P50\nM30\n"
    rows = run_phases(text)
    s100 = np.flatnonzero(rows[:, 0] == 100.0)[0]
    # the cycle S100 is issued the drive still has 200 m/min; from then on 100 m/min, X still at 50
    assert rows[s100 + 1, 2] == pytest.approx(AT_100 / 2.0, abs=RPM_RES)
    m05 = np.flatnonzero(rows[:, 0] == 5.0)[0]
    assert rows[m05 + 5, 2] == 0.0
    # M03 again at X50 (diameter 50): 100 m/min is 636.6 rpm, from the first cycle the drive turns
    m03 = np.flatnonzero(rows[:, 0] == 3.0)[-1]
    after = spinning(rows[m03:])
    assert after[0, 1] == pytest.approx(25.0) and np.allclose(after[:, 2], AT_100, atol=RPM_RES)


def test_g96_while_the_spindle_turns_switches_without_a_move():
    rows = run_phases("G21 G18 G99\nG00 X100. Z5.\nG97 S300 M03\nG04 P50\nG96 S200\nG04 P50\nM30\n")
    g96 = np.flatnonzero(rows[:, 0] == 200.0)[0]
    assert rows[g96 - 1, 2] == pytest.approx(300.0, abs=RPM_RES)
    assert rows[g96 + 1, 2] == pytest.approx(AT_100, abs=RPM_RES)
    assert np.allclose(rows[g96 + 1:, 2][rows[g96 + 1:, 2] > 0], AT_100, atol=RPM_RES)


def test_g96_with_x_programmed_as_a_radius_uses_twice_x():
    # N2.001 Bit10 = 1: X words are radii, so X50. is diameter 100 (636.6 rpm at 200 m/min)
    text = "G21 G18 G99\nG00 X50. Z5.\nG96 S200 M03\nG01 X40. F0.1\nM30\n"
    rows = run_phases(text, {"N2.001 Bit10": 1})
    on = spinning(rows)
    assert on[0, 2] == pytest.approx(AT_100, abs=RPM_RES)
    assert on[-1, 1] == pytest.approx(40.0)
    assert on[-1, 2] == pytest.approx(1000.0 * 200.0 / (math.pi * 80.0), abs=RPM_RES)


def test_g96_m03_through_hil_run_with_the_lathe_mlc(hil, program, tmp_path):
    """The lathe MLC reads D31024 = the CSS rpm from the S strobe on (D31050 keeps S200, m/min), the
    drive is given it from the first cycle, and M03 finishes when the spindle reaches it."""
    import csv

    prog = program("G21 G18 G99\nG00 X100. Z5.\nG50 S3000\nG96 S200 M03\nG01 X50. F0.5\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--bench", ROOT / "benches" / "lathe-2axis.toml", "--trace", trace,
            "--trace-signals", "M31065,D31024,D31050,M31064,D31048,M21016")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    strobe = next(i for i, row in enumerate(rows) if row["M31065"] == "1")
    assert float(rows[strobe]["D31024"]) == pytest.approx(AT_100, rel=1e-6)
    assert float(rows[strobe]["D31050"]) == 200.0
    cmd = [float(row["S1_rpm_cmd"]) for row in rows]
    first = next(i for i, v in enumerate(cmd) if v > 0.5)
    assert cmd[first] == pytest.approx(AT_100, abs=RPM_RES)
    m03 = next(i for i, row in enumerate(rows) if row["M31064"] == "1" and row["D31048"] == "3")
    fin = next(i for i in range(m03, len(rows)) if rows[i]["M21016"] == "1")
    assert float(rows[fin]["S1_rpm_act"]) == pytest.approx(AT_100, rel=0.02)
    assert float(rows[fin]["X_cmd"]) == pytest.approx(50.0)  # the M03 waited before the first move
    # while X faces in to diameter 50 the MLC's D31024 and the drive follow X
    end = max(i for i, row in enumerate(rows) if abs(float(row["X_cmd"]) - 25.0) < 1e-9 and cmd[i] > 0.5)
    assert cmd[end] == pytest.approx(2.0 * AT_100, abs=RPM_RES)
    assert float(rows[end]["D31024"]) == pytest.approx(2.0 * AT_100, rel=1e-5)


def test_g50_s_is_a_limit_not_an_s_code_for_the_mlc(hil, program, tmp_path):
    """G50 S2000 while the spindle turns at S500 leaves it at 500 (no S strobe, D31024 unchanged)."""
    import csv

    prog = program("G21 G18 G98\nG97 S500 M03\nG04 P100\nG50 S2000\nG04 P300\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--trace", trace, "--trace-signals", "M31065,D31024")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    assert sum(1 for a, b in zip(rows, rows[1:]) if a["M31065"] == "0" and b["M31065"] == "1") == 1
    assert max(float(row["S1_rpm_cmd"]) for row in rows) == pytest.approx(500.0, abs=RPM_RES)
    assert {float(row["D31024"]) for row in rows[-10:]} == {500.0}


# ---- spindle override D2x026 and G96/G97 alone (session 3, motion decisions 31-32) ---------------

def run_override(text: str, percent: int, params: dict[str, float] | None = None):
    """As run_phases, with the operator's spindle override D21026 at `percent`; per cycle (aux value
    or -1, X command, drive's commanded rpm, line, measured rpm, Z command, spindle angle, 1 while the
    running move is a rapid else 0)."""
    bench = default_lathe()
    bench.params.update(params or {})
    mlc = build_mlc(bench, "lathe")
    mlc.put("D21026", percent)
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle), mlc=mlc)
    sc = bench.spindles[0].scaling
    rows = []

    def grab(r):
        ch = r.channel
        if ch is not None:
            aux = ch.pending_aux
            rows.append((aux.value if aux is not None else -1.0, r._commands[0],
                         sc.drive_to_rpm(r.rx[2].target_velocity), r.line, r.spindle_actual_rpm(),
                         r._commands[1], r.spindle_actual_angle(),
                         float(bool(ch.planner.blocks) and ch.planner.blocks[0].move.kind == "rapid")))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    assert result.ok, result.alarms  # M03 of the lathe MLC finishes only on "speed reached"
    return np.array(rows), runner


def test_spindle_override_scales_g97_and_g96_and_speed_reached_follows_it():
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG97 S1000 M03\nG04 P200\nM30\n", 80)
    on = spinning(rows)
    assert np.allclose(on[:, 2], 800.0, atol=RPM_RES)
    # M03 finished (speed reached against 800, not 1000) and the drive really turns at 800
    assert on[-1, 4] == pytest.approx(800.0, rel=0.01)
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P200\nM30\n", 80)
    on = spinning(rows)
    assert np.allclose(on[:, 2], 0.8 * AT_100, atol=RPM_RES)
    assert on[-1, 4] == pytest.approx(0.8 * AT_100, rel=0.01)


def test_override_above_100_stays_within_g50_s_and_feed_per_rev_follows_the_actual_speed():
    # 120 % of 636.6 = 763.9 rpm, capped by G50 S700; under G97 S1000 × 120 % likewise
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG50 S700\nG96 S200 M03\nG04 P100\nM30\n", 120)
    assert np.allclose(spinning(rows)[:, 2], 700.0, atol=RPM_RES)
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG50 S700\nG97 S1000 M03\nG04 P100\nM30\n", 120)
    assert np.allclose(spinning(rows)[:, 2], 700.0, atol=RPM_RES)
    # G99 F0.2 at 80 % of S1000: Z moves 0.2 mm per revolution of the measured 800 rpm = 160 mm/min
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG97 S1000 M03\nG01 Z-20. F0.2\nM30\n", 80)
    cut = rows[rows[:, 3] == 4]
    v = -np.diff(cut[:, 5]) / 0.001 * 60.0
    cruise = v[np.abs(v - v.max()) < 1e-6 * v.max()]
    assert len(cruise) > 1000 and cruise[0] == pytest.approx(0.2 * np.median(cut[:, 4]), rel=1e-3)
    assert cruise[0] == pytest.approx(160.0, rel=1e-3)


def test_threads_run_at_100_percent_whatever_the_override_and_stay_in_phase():
    from test_motion_sync_thread import circ_spread, locked, passes_program, phase

    xs = [19.4, 19.0, 18.6]
    rows, runner = run_override(passes_program(xs), 80)
    lines = [5 + 4 * i for i in range(len(xs))]
    for ln in lines:
        m = rows[rows[:, 3] == ln]
        # S600, not 480 (the chain's last cycle already hands back to the override)
        assert np.allclose(m[:-1, 2], 600.0, atol=RPM_RES)
        assert np.allclose(m[:, 4], 600.0, rtol=1e-3)  # the spindle has reached it before the pass
    # between passes the next thread waits in the look-ahead: 600 throughout; after the last, 480
    assert np.allclose(rows[(rows[:, 3] > 5) & (rows[:, 3] < 13), 2], 600.0, atol=RPM_RES)
    assert np.allclose(rows[rows[:, 3] == 14, 2], 480.0, atol=RPM_RES)
    log = runner.channel.planner.thread_log
    assert circ_spread(np.array([sync % 360.0 for _, sync, _ in log])) < 0.5
    thread = np.column_stack([rows[:, 3], rows[:, 1], rows[:, 5], rows[:, 5], rows[:, 6]])
    cmd = np.concatenate([phase(locked(thread[thread[:, 0] == ln]), 2) for ln in lines])
    assert circ_spread(cmd) < 0.5


def test_g96_alone_switches_at_once_on_the_last_g96_surface_speed():
    at_100_150 = 1000.0 * 150.0 / (math.pi * 100.0)
    text = "G21 G18 G99\nG00 X100. Z5.\nG96 S150\nG97 S300 M03\nG04 P50\nG96\nG04 P50\nM30\n"
    rows, _ = run_override(text, 100)
    s300 = np.flatnonzero(rows[:, 0] == 300.0)[-1]
    g96 = s300 + np.flatnonzero(rows[s300:, 0] == 150.0)[0]  # the S aux G96 alone gives
    assert rows[g96 - 1, 2] == pytest.approx(300.0, abs=RPM_RES)  # G97 S300 until G96 is read
    assert rows[g96 + 1, 2] == pytest.approx(at_100_150, abs=RPM_RES)  # S150 (m/min) from G96 on
    assert np.allclose(rows[g96 + 1:, 2][rows[g96 + 1:, 2] > 0], at_100_150, atol=RPM_RES)
    # no S ever given under G96: 0 m/min (Fanuc), the spindle stops rather than read 300 rpm as m/min
    rows, _ = run_override("G21 G18 G99\nG00 X100. Z5.\nG97 S300 M03\nG04 P50\nG96\nG04 P50\nM30\n", 100)
    g96 = np.flatnonzero(rows[:, 0] == 0.0)[0]
    assert rows[g96 - 1, 2] == pytest.approx(300.0, abs=RPM_RES) and np.all(rows[g96 + 1:, 2] == 0.0)


def test_g97_alone_hands_the_css_rpm_to_the_mlc_as_its_s():
    text = "G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P50\nG97\nG00 X50.\nG04 P50\nM30\n"
    rows, runner = run_override(text, 80)
    # the S strobe of G97 alone carries the rpm G96 had at X diameter 100, the new G97 speed
    assert np.any(np.abs(rows[:, 0] - AT_100) < 1e-6 * AT_100)
    from mlc.signals import d3

    assert runner.mlc.mem.f32(d3(runner.mlc.link.x, 24)) == pytest.approx(AT_100, rel=1e-6)  # D31024
    on = spinning(rows)
    assert on[-1, 1] == pytest.approx(25.0)
    assert on[-1, 2] == pytest.approx(0.8 * AT_100, abs=RPM_RES)


def test_g96_holds_through_a_turning_cycle():
    # G90 (A system, outer diameter cycle): its cut moves carry the surface speed like G01 does
    text = "G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG90 X80. Z-10. F0.2\nM30\n"
    rows, _ = run_override(text, 100)
    cyc = rows[(rows[:, 3] == 4) & (np.abs(rows[:, 2]) > 0.5)]
    cut = cyc[cyc[:, 7] == 0.0]  # the cut moves: the speed at the tool's diameter, every cycle
    d = 2.0 * cut[:, 1]
    assert np.allclose(cut[:, 2], 1000.0 * 200.0 / (math.pi * d), rtol=1e-3, atol=RPM_RES)
    assert cyc[:, 1].min() == pytest.approx(40.0)
    # its rapids (in to X80, back to Z5 at X100): the speed at their end point (decision motion 70)
    first_cut = np.flatnonzero(cyc[:, 7] == 0.0)[0]
    inward, back = cyc[:first_cut], cyc[first_cut:][cyc[first_cut:, 7] == 1.0]
    back = back[back[:, 1] > 50.0 - 1e-9]  # (the feed out's last setpoints come in its rows: blocks[0] moved on)
    assert len(inward) > 20 and np.all(inward[:, 7] == 1.0) and len(back) > 20
    assert np.allclose(inward[:, 2], 1000.0 * 200.0 / (math.pi * 80.0), rtol=0.0, atol=RPM_RES)
    assert np.allclose(back[:, 2], 1000.0 * 200.0 / (math.pi * 100.0), rtol=0.0, atol=RPM_RES)


def test_g96_rapids_take_the_speed_at_their_end_point():
    """Decision motion 70 (catalogue A40; Fanuc "CSS for rapid traverse (G00)"): a G00 under G96 is given the speed
    of its end point from its first cycle, which the spindle reaches while the tool moves; a G01 follows the tool."""
    text = "G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P50\nG00 X40.\nG01 X80. F0.2\nM30\n"
    rows, _ = run_override(text, 100)
    rapid = rows[(rows[:, 3] == 5) & (rows[:, 7] == 1.0)]
    assert len(rapid) > 20 and rapid[0, 1] > 49.0 and rapid[-1, 1] < 21.0  # the rows span the whole rapid
    assert np.allclose(rapid[:, 2], 1000.0 * 200.0 / (math.pi * 40.0), rtol=0.0, atol=RPM_RES)  # one: at D 40
    feed = rows[(rows[:, 3] == 6) & (rows[:, 7] == 0.0)]
    assert np.allclose(feed[:, 2], 1000.0 * 200.0 / (math.pi * 2.0 * feed[:, 1]), rtol=1e-3, atol=RPM_RES)
    assert np.ptp(feed[:, 2]) > 300.0  # D 40 → 80: the speed halves along the cut


def test_spindle_override_from_the_command_line(hil, tmp_path):
    r = hil("spindle", "1000", "--override", "80", "--seconds", "0.2")
    assert r.code == 0, r.err
    assert "800.0 rpm at speed" in r.out
    assert hil("spindle", "1000", "--override", "-5").code == 2
    script = tmp_path / "css.py"
    script.write_text("def main(machine):\n"
                      "    machine.spindle_override(80)\n"
                      "    machine.mdi('G21 G18 G99 G00 X100. Z5.')\n"
                      "    machine.mdi('G96 S200 M03')\n"
                      "    machine.wait(0.2)\n"
                      "    print(f'css at {machine.get_rpm():.1f} rpm')\n")
    r = hil("script", str(script))
    assert r.code == 0, r.err
    assert f"css at {0.8 * AT_100:.1f} rpm" in r.out


def test_spindle_override_turned_during_hil_run_under_g96(hil, program, tmp_path):
    """`--at` turns D21026 to 80 % mid-dwell: the drive drops to 80 % of the CSS rpm, D31024 keeps it."""
    import csv

    prog = program("G21 G18 G99\nG00 X100. Z5.\nG96 S200 M03\nG04 P500\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--bench", ROOT / "benches" / "lathe-2axis.toml", "--trace", trace,
            "--trace-signals", "D31024,D21026", "--at", "line=4:set SPINDLE1_OVERRIDE=80")
    assert r.code == 0, r.out + r.err
    rows = [row for row in csv.DictReader(trace.open()) if float(row["S1_rpm_cmd"]) > 0.5]
    cmd = [float(row["S1_rpm_cmd"]) for row in rows]
    assert cmd[0] == pytest.approx(AT_100, abs=RPM_RES)
    assert cmd[-1] == pytest.approx(0.8 * AT_100, abs=RPM_RES)
    assert float(rows[-1]["S1_rpm_act"]) == pytest.approx(0.8 * AT_100, rel=0.01)
    assert all(float(row["D31024"]) == pytest.approx(AT_100, rel=1e-6) for row in rows)
    assert float(rows[0]["D21026"]) == 100.0 and float(rows[-1]["D21026"]) == 80.0
