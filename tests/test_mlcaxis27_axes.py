"""NC / MLC axis switching and the MLC's own axis moves (NC5 App. B.2: M2x432+i, M3x432+i, M2x416+i, M2x448+i,
M2x464+i, D2x256+2i, D2x288+2i, M3x448+i; decisions M26-20 … M26-27), on the mill bench (X is axis 0: M21432 …).
Read from the trace: X's setpoints and positions, the relays, the alarms, the summary."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SIGNALS = "M21432,M31432,M21448,M31448"
X_LIMITS = (500.0, 5000.0, 250000.0)  # benches/mill-3axis.toml: X velocity, acceleration, jerk
DT = 0.001

# M50 (a preview-halt M code follows it, M51: App. A §3.2.2 (2)): X to the MLC, to 30.5 absolute at 6000 mm/min,
# then 5 incremental, back to the NC; M50 finishes after that. Any other code finishes at once.
USER_MLC = '''SCAN_ON_CHANGE = True


def scan(mlc):
    st = mlc.state
    step = st.get("step", 0)
    if not step and mlc.m("M_STROBE") and int(mlc.d("M_CODE")) != 50:
        mlc.set("MST_FINISH")
    elif not step and not mlc.m("M_STROBE"):
        mlc.set("MST_FINISH", False)
    if mlc.m("M_STROBE") and int(mlc.d("M_CODE")) == 50 and not step:
        st["step"] = 1
        mlc.set("M21432")  # NC / MLC Axis Switching (X)
    elif step == 1 and mlc.m("M31432"):  # Axis Switch to MLC Axis Finished
        mlc.put("D21256", 30.5)
        mlc.put("D21288", 6000.0)
        mlc.set("M21448")  # trigger
        st["step"] = 2
    elif step == 2 and mlc.m("M31448"):  # target reached
        mlc.set("M21448", False)
        mlc.set("M21464")  # incremental
        mlc.put("D21256", 5.0)
        st["step"] = 3
    elif step == 3:
        mlc.set("M21448")
        st["step"] = 4
    elif step == 4 and mlc.m("M31448"):
        mlc.set("M21448", False)
        mlc.set("M21432", False)  # back to the NC
        st["step"] = 5
    elif step == 5 and not mlc.m("M31432"):
        mlc.set("MST_FINISH")
        st["step"] = 6
    elif step == 6 and not mlc.m("M_STROBE"):
        mlc.set("MST_FINISH", False)
        st["step"] = 0
'''


def _bench(tmp_path: Path) -> Path:
    """The shipped mill with M51 as the preview-halt M code (N1.118/N1.119)."""
    text = (ROOT / "benches" / "mill-3axis.toml").read_text()
    text = text.replace('mlc = "basic"\n', 'mlc = "basic"\n\n[params]\n"N1.118" = 51\n"N1.119" = 1\n', 1)
    path = tmp_path / "mill.toml"
    path.write_text(text)
    return path


def _run(hil, tmp_path, text: str, *args: str, name: str = "t"):
    prog = tmp_path / f"{name}.nc"
    prog.write_text(text)
    trace = tmp_path / f"{name}.csv"
    r = hil("run", str(prog), "--bench", str(_bench(tmp_path)), "--no-check", "--trace", str(trace),
            "--trace-signals", SIGNALS, *args)
    return r, trace.read_text()


def _rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


def _within_limits(xs: list[float], limits=X_LIMITS) -> None:
    """Velocity, acceleration and jerk of the setpoints, cycle by cycle, within the axis's limits."""
    v = [(b - a) / DT for a, b in zip(xs, xs[1:])]
    acc = [(b - a) / DT for a, b in zip(v, v[1:])]
    jerk = [(b - a) / DT for a, b in zip(acc, acc[1:])]
    assert max(map(abs, v)) <= limits[0] * (1 + 1e-9)
    assert max(map(abs, acc)) <= limits[1] * (1 + 1e-6)
    assert max(map(abs, jerk)) <= limits[2] * (1 + 1e-6)


@pytest.mark.parametrize("stretch", ["0", "1"])
def test_the_mlc_switches_x_moves_it_absolute_then_incremental_and_hands_it_back(hil, tmp_path, monkeypatch,
                                                                              stretch):
    (tmp_path / "axis_mlc.py").write_text(USER_MLC)
    text = "G90 G01 X10. F3000\nM50\nM51\nG01 X20. Y5.\nM30\n"
    monkeypatch.setenv("DELTAHIL_STRETCH", stretch)
    r, trace = _run(hil, tmp_path, text, "--mlc", str(tmp_path / "axis_mlc.py"), name=f"s{stretch}")
    assert r.code == 0 and "alarms         none" in r.out, r.out + r.err
    assert "final machine position  X 20.0000  Y 5.0000" in r.out
    rows = _rows(trace)
    ask = next(i for i, row in enumerate(rows) if row["M21432"] == "1")
    done = next(i for i, row in enumerate(rows) if row["M31432"] == "1")
    assert done - ask == 2  # X stood: the NC's command of it is seen standing one cycle later, then Finished
    assert float(rows[ask]["X_cmd"]) == 10.0 and rows[ask]["line"] == "2"
    # the absolute move: the setpoint exactly on 30.5 when M3x448 comes on, at 6000 mm/min (100 mm/s) at most
    first = next(i for i, row in enumerate(rows) if row["M31448"] == "1")
    assert float(rows[first]["X_cmd"]) == 30.5 and float(rows[first - 1]["X_cmd"]) != 30.5
    xs = [float(row["X_cmd"]) for row in rows[done:first + 1]]
    _within_limits(xs, (100.0, 5000.0, 250000.0))
    assert max(abs(b - a) for a, b in zip(xs, xs[1:])) / DT == pytest.approx(100.0, rel=1e-6)
    # the incremental one: +5 from 30.5, reached exactly
    second = next(i for i, row in enumerate(rows) if i > first + 2 and row["M31448"] == "1")
    assert float(rows[second]["X_cmd"]) == 35.5
    # back to the NC: M3x432 drops, then the program's next move runs from 35.5 to 20 (not from 10)
    back = next(i for i, row in enumerate(rows) if i > second and row["M31432"] == "0")
    line4 = [float(row["X_cmd"]) for row in rows if row["line"] == "4"]
    assert int(rows[back]["cycle"]) < int(next(row["cycle"] for row in rows if row["line"] == "4"))
    assert line4[0] == pytest.approx(35.5, abs=1e-3) and line4[-1] == pytest.approx(20.0, abs=1e-9)
    assert all(b <= a + 1e-12 for a, b in zip(line4, line4[1:]))  # straight from 35.5 down to 20
    _within_limits([float(row["X_cmd"]) for row in rows])
    if stretch == "1":  # stretched or stepped, the same run cycle by cycle
        monkeypatch.setenv("DELTAHIL_STRETCH", "0")
        _, plain = _run(hil, tmp_path, text, "--mlc", str(tmp_path / "axis_mlc.py"), name="plain")
        assert [(row["X_cmd"], row["M31448"]) for row in _rows(plain)] == [(row["X_cmd"], row["M31448"])
                                                                            for row in rows]


def test_a_program_moving_an_mlc_axis_is_0x141C_and_stops(hil, tmp_path):
    r, trace = _run(hil, tmp_path, "G90 G01 X10. F3000\nG04 X0.5\nG01 X20. Y5.\nM30\n",
                    "--at", "t=0.3:set M21432=1")
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x141C axis X at line 3" in r.out and "M21432 ON" in r.out and "result         STOPPED" in r.out
    rows = _rows(trace)
    assert all(float(row["X_cmd"]) == 10.0 for row in rows if int(row["cycle"]) >= 300)  # X never moved again
    assert float(rows[-1]["Y_cmd"]) < 5.0  # the channel stopped the block


def test_a_switch_asked_while_the_nc_moves_the_axis_waits_for_it_to_stand(hil, tmp_path):
    r, trace = _run(hil, tmp_path, "G90 G01 X10. F3000\nG04 X0.5\nM30\n", "--at", "t=0.1:set M21432=1")
    assert r.code == 0, r.out + r.err
    rows = _rows(trace)
    done = next(i for i, row in enumerate(rows) if row["M31432"] == "1")
    assert float(rows[done]["X_cmd"]) == 10.0  # the NC's move ran to its end first
    # Finished the cycle after the NC's command of X first stood (the same value two cycles running)
    assert float(rows[done - 1]["X_cmd"]) == 10.0 and float(rows[done - 2]["X_cmd"]) != 10.0
    assert int(rows[done]["cycle"]) > 200


def test_speed_mode_runs_at_the_velocity_follows_a_change_and_stops_when_the_trigger_drops(hil, tmp_path):
    at = ["t=0.05:set M21432=1", "t=0.05:set M21416=1", "t=0.05:set D21288=3000", "t=0.1:set M21448=1",
          "t=0.3:set D21288=-1500", "t=0.5:set M21448=0"]
    r, trace = _run(hil, tmp_path, "G04 X0.8\nM30\n", *[a for e in at for a in ("--at", e)])
    assert r.code == 0 and "alarms         none" in r.out, r.out + r.err
    rows = _rows(trace)
    xs = [float(row["X_cmd"]) for row in rows]
    _within_limits(xs)
    v = {int(row["cycle"]): (float(b["X_cmd"]) - float(row["X_cmd"])) / DT for row, b in zip(rows, rows[1:])}
    reached = [int(row["cycle"]) for row in rows if row["M31448"] == "1"]
    # 50 mm/s reached (M3x448 ON) within the ramp's time, held until the velocity changes
    assert 100 < reached[0] < 130 and v[reached[0] + 5] == pytest.approx(50.0, rel=1e-9)
    assert v[290] == pytest.approx(50.0, rel=1e-9)
    assert not any(302 <= c <= 320 for c in reached)  # the new speed not yet there: OFF
    assert v[450] == pytest.approx(-25.0, rel=1e-9) and 450 in reached
    # the trigger dropped: a controlled stop, then X stands where it stopped; M3x448 OFF
    end = xs[-2]  # (the last row: the drive disabled, its command follows the measured position)
    assert all(x == end for x in xs[-100:-1]) and rows[-1]["M31448"] == "0"
    assert rows[-1]["M31432"] == "1"  # still the MLC's axis


def test_an_nc_reset_stops_an_mlc_move_under_control_short_of_its_target(hil, tmp_path):
    at = ["t=0.05:set M21432=1", "t=0.05:set D21256=200", "t=0.05:set D21288=30000", "t=0.1:set M21448=1",
          "t=0.3:pulse M21004"]
    r, trace = _run(hil, tmp_path, "G04 X0.8\nM30\n", *[a for e in at for a in ("--at", e)])
    rows = _rows(trace)
    xs = [float(row["X_cmd"]) for row in rows]
    _within_limits(xs)
    assert 20.0 < xs[-2] < 190.0 and all(x == xs[-2] for x in xs[-50:-1])  # stopped short of 200, standing
    assert all(row["M31448"] == "0" for row in rows)


def test_an_estop_brakes_an_mlc_move_like_every_axis_and_disables_it_only_at_standstill(hil, tmp_path):
    at = ["t=0.05:set M21432=1", "t=0.05:set D21256=200", "t=0.05:set D21288=30000", "t=0.1:set M21448=1",
          "t=0.3:estop"]
    r, trace = _run(hil, tmp_path, "G04 X0.8\nM30\n", *[a for e in at for a in ("--at", e)])
    assert "ALARM 0x0401" in r.out and "result         STOPPED" in r.out, r.out + r.err
    rows = _rows(trace)
    k = next(i for i, row in enumerate(rows) if int(row["cycle"]) == 301)
    assert float(rows[k]["X_vel"]) > 400.0  # X ran at the axis's 500 mm/s (30000 mm/min asked, capped)
    speeds = [float(row["X_vel"]) for row in rows[k:]]
    assert all(b <= a + 1.0 for a, b in zip(speeds, speeds[1:])) and sum(1 for v in speeds if v > 1.0) > 100
    off = next(i for i, row in enumerate(rows) if i > k and int(row["X_sw"]) & 0x6F != 0x27 and
               int(row["X_sw"]) & 0x6F != 0x07)  # neither operation enabled nor quick stop active
    assert abs(float(rows[off - 1]["X_vel"])) < 0.01
    assert 100.0 < float(rows[-1]["X_act"]) < 200.0 and all(row["M31448"] == "0" for row in rows)


def test_the_example_script_drives_x_as_an_mlc_axis_and_the_nc_takes_it_back(hil):
    r = hil("script", ROOT / "examples" / "scripts" / "mlc_axis.py", "--bench", ROOT / "benches" / "mill-3axis.toml")
    assert r.code == 0, r.out + r.err
    assert "absolute: X 30.5000" in r.out and "incremental: X 35.5000" in r.out
    # 0.5 s at -1200 mm/min from 35.5 plus the ramps: -20 mm/s reached at 5000 mm/s² and 250000 mm/s³
    assert "speed mode: X 25.1400" in r.out
    assert "NC again: G01 X0. from X 25.1400 to X 0.0000, alarms 0" in r.out


def test_software_limits_refuse_a_target_past_them_and_stop_a_speed_mode_run_short_of_them(hil, tmp_path):
    # X's window on the mill: -300 … 300 (1st segment, App. A 0x0A01)
    at = ["t=0.05:set M21432=1", "t=0.05:set D21256=-300.5", "t=0.05:set D21288=24000", "t=0.1:set M21448=1"]
    r, trace = _run(hil, tmp_path, "G04 X2.\nM30\n", *[a for e in at for a in ("--at", e)], name="pos")
    assert "ALARM 0x0A01 axis X" in r.out and "target -300.5000 is past the limit -300.0000" in r.out, r.out
    assert all(float(row["X_cmd"]) == 0.0 for row in _rows(trace))  # the move was not started
    at = ["t=0.05:set M21432=1", "t=0.05:set M21416=1", "t=0.05:set D21288=24000", "t=0.1:set M21448=1"]
    r, trace = _run(hil, tmp_path, "G04 X2.\nM30\n", *[a for e in at for a in ("--at", e)], name="speed")
    assert "ALARM 0x0A01 axis X" in r.out and "software limit 1 + of MLC axis X" in r.out, r.out
    xs = [float(row["X_cmd"]) for row in _rows(trace)]
    _within_limits(xs)
    assert 290.0 < max(xs) <= 300.0 and xs[-2] == max(xs)  # at 400 mm/s towards +300: stopped short of it


JOG_SCRIPT = '''def main(machine):
    mem = machine.mlc.mem
    machine.mode("JOG")
    machine.set("M21432")
    machine.wait_until(lambda: machine.get("M31432") == 1, 1.0, "X switched")
    machine.jog("X", 1, 0.3)
    print(f"JOG of the MLC axis: X {machine.command('X'):.4f}")
    mem.set_f32(21256, 10.0)
    mem.set_f32(21288, 6000.0)
    machine.set("M21448")
    machine.cycle(2)
    machine.wait_until(lambda: machine.get("M31448") == 1, 2.0, "X at 10")
    machine.set("M21432", False)
    machine.wait_until(lambda: machine.get("M31432") == 0, 1.0, "X back")
    machine.jog("X", 1, 0.3)
    machine.wait(0.3)
    print(f"JOG as an NC axis again: X {machine.command('X'):.4f}, alarms {len(machine.all_alarms())}")
'''


def test_a_jog_of_an_mlc_axis_does_nothing_and_after_the_hand_back_it_jogs_from_the_mlc_position(hil, tmp_path):
    script = tmp_path / "jog.py"
    script.write_text(JOG_SCRIPT)
    r = hil("script", script, "--bench", ROOT / "benches" / "mill-3axis.toml")
    assert r.code == 0, r.out + r.err
    assert "JOG of the MLC axis: X 0.0000" in r.out  # 0.3 s of JOG+ (N2.030 speed): interlocked, X stood
    # JOG mode all along: the manual motion takes X at 10 from the MLC, 0.3 s of JOG at 1000 mm/min = +5
    assert "JOG as an NC axis again: X 15.0000, alarms 0" in r.out


def test_a_rotary_mlc_axis_takes_its_velocity_in_rpm(hil, tmp_path):
    """App. B.2 D2x288: rotary axes (A/B/C) in rpm. A 4th axis A (units deg, axis 3: M21435, D21262/D21294):
    to 90° at 10 rpm = 60 °/s."""
    bench = (ROOT / "benches" / "mill-3axis.toml").read_text()
    bench = bench.replace("[[spindles]]", '[[axes]]\nname = "A"\nunits = "deg"\nlead = 360.0\n'
                                          'limits = { velocity = 3600.0, acceleration = 36000.0, jerk = 1800000.0 }\n\n'
                                          "[[spindles]]", 1)
    (tmp_path / "mill4.toml").write_text(bench)
    prog = tmp_path / "a.nc"
    prog.write_text("G04 X2.\nM30\n")
    trace = tmp_path / "a.csv"
    at = ["t=0.05:set M21435=1", "t=0.05:set D21262=90", "t=0.05:set D21294=10", "t=0.1:set M21451=1"]
    r = hil("run", str(prog), "--bench", str(tmp_path / "mill4.toml"), "--no-check", "--trace", str(trace),
            "--trace-signals", "M31435,M31451", *[a for e in at for a in ("--at", e)])
    assert r.code == 0, r.out + r.err
    rows = _rows(trace.read_text())
    xs = [float(row["A_cmd"]) for row in rows]
    assert max(abs(b - a) for a, b in zip(xs, xs[1:])) / DT == pytest.approx(60.0, rel=1e-6)
    done = next(i for i, row in enumerate(rows) if row["M31451"] == "1")
    assert xs[done] == 90.0 and 1.5 < float(rows[done]["t"]) - 0.1 < 1.52  # 90° at 60 °/s: 1.5 s and the ramps


def test_a_move_read_ahead_before_the_hand_back_is_refused_not_stepped(hil, tmp_path):
    """Decision M26-30: without the preview-halt M code after M50 (App. A §3.2.2 (2)), line 3 is read while X is the
    MLC's and starts at X10, where X stood when it was switched; X comes back at 35.5. Planned from X10 it stepped X
    back 25 mm in a cycle (setpoints at 1,591 mm/s, 0x0602 overspeed). Now the move never starts: 0x141C at line 3,
    X stays at 35.5 and no setpoint exceeds X's velocity."""
    (tmp_path / "axis_mlc.py").write_text(USER_MLC)
    r, trace = _run(hil, tmp_path, "G90 G01 X10. F3000\nM50\nG01 X20. Y5.\nM30\n", "--mlc",
                    str(tmp_path / "axis_mlc.py"), name="ahead")
    assert r.code != 0
    assert "ALARM 0x141C axis X in ahead.nc at line 3: G01 X20. Y5." in r.out and "0x0602" not in r.out, r.out
    assert "final machine position  X 35.5000  Y 0.0000" in r.out, r.out
    xs = [float(row["X_cmd"]) for row in _rows(trace)]
    assert max(abs(b - a) for a, b in zip(xs, xs[1:])) / DT <= X_LIMITS[0]
    assert xs[-1] == 35.5


HOME_SCRIPT = '''def main(machine):
    mem = machine.mlc.mem
    machine.mode("HOME")
    machine.set("M21432")
    machine.wait_until(lambda: machine.get("M31432") == 1, 1.0, "X switched")
    mem.set_f32(21256, 10.0)
    mem.set_f32(21288, 6000.0)
    machine.set("M21448")
    machine.cycle(2)
    machine.wait_until(lambda: machine.get("M31448") == 1, 2.0, "X at 10")
    machine.pulse(21320)  # M2x320: home X
    machine.wait(1.0)
    print(f"home trigger on the MLC axis: X {machine.command('X'):.4f}, homed {machine.get('M31336')}")
    machine.set("M21432", False)
    machine.wait_until(lambda: machine.get("M31432") == 0, 1.0, "X back")
    machine.home("X")
    print(f"homed as an NC axis again: X {machine.command('X'):.4f}, homed {machine.get('M31336')}")
'''


def test_a_home_trigger_of_an_mlc_axis_does_nothing_and_after_the_hand_back_it_homes(hil, tmp_path):
    """Decision M26-29: HOME mode's trigger M2x320+i is a manual command like a JOG: the MLC's axis ignores it (it
    was taken: M3x336 "homed" came ON while the MLC held X at 10); back with the NC, X homes to 0."""
    script = tmp_path / "home.py"
    script.write_text(HOME_SCRIPT)
    r = hil("script", script, "--bench", ROOT / "benches" / "mill-3axis.toml")
    assert r.code == 0, r.out + r.err
    assert "home trigger on the MLC axis: X 10.0000, homed 0" in r.out, r.out
    assert "homed as an NC axis again: X 0.0000, homed 1" in r.out.replace("X -0.0000", "X 0.0000"), r.out
