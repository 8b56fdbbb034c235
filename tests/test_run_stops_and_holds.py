"""`hil run` at the edges a bench engineer tries: an M00 hold's line in the trace and its `line=N` events
(decision B56), `--max-time` (B57), events after an E-stop (B58) — checked on the trace in simulated time."""

from __future__ import annotations

import csv

import numpy as np

from hil.cli import main
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")
# 50 mm/s along X, then M00 on line 3, then back
M00 = "G90 G54 G17 G21 G94\nG01 X20. F3000\nM00\nG01 X0. F3000\nM30\n"


def read(path) -> dict[str, np.ndarray | list[str]]:
    rows = list(csv.DictReader(open(path)))
    cols: dict = {c: np.array([float(r[c]) for r in rows]) for c in rows[0] if c not in ("alarm", "event")}
    cols["event"] = [r.get("event", "") for r in rows]
    return cols


def run(tmp_path, program: str, *args: str, bench: str = MILL) -> tuple[int, dict]:
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    trace = tmp_path / "t.csv"
    code = main(["run", str(prog), *(["--bench", bench] if bench else []), "--trace", str(trace), "--no-check", *args])
    return code, read(trace) if trace.exists() else {}


def test_the_m00_block_is_the_current_line_while_it_holds(tmp_path, capsys):
    code, c = run(tmp_path, M00, "--m00-resume", "0.3", "--at", "line=3:set D21006=7")
    out = capsys.readouterr().out
    assert code == 0, out
    held = np.flatnonzero(c["line"] == 3)
    # the hold: X stands at 20 for the operator's 0.3 s, and every row of it names line 3
    assert 0.29 <= len(held) * 0.001 <= 0.32, len(held)
    assert np.allclose(c["X_cmd"][held], 20.0, atol=1e-9)
    assert np.all(np.diff(held) == 1) and c["line"][held[-1] + 1] == 4
    assert "never triggered" not in out and "line 3  set D21006=7   [line=3]" in out


def test_a_line_event_on_the_m00_block_presses_cycle_start(tmp_path, capsys):
    # the simulated operator would wait 5 s; the scripted Cycle Start on the M00 line resumes at once
    code, c = run(tmp_path, M00, "--m00-resume", "5", "--at", "line=3:cycle-start")
    out = capsys.readouterr().out
    assert code == 0, out
    held = np.flatnonzero(c["line"] == 3)
    assert 1 <= len(held) <= 3, len(held)  # the press lands in the scan after the first cycle of line 3
    assert c["t"][-1] < 2.5 and abs(c["X_cmd"][-1]) < 1e-9


def test_an_m00_hold_longer_than_the_aux_timeout_is_no_mlc_finish_warning(tmp_path, capsys):
    # M00 is never strobed: it waits for Cycle Start, so --aux-timeout (the MLC's M2x016) does not apply
    code, c = run(tmp_path, M00, "--mlc", "lathe", "--m00-resume", "2", "--aux-timeout", "1")
    out = capsys.readouterr()
    assert code == 0 and "warning" not in out.out + out.err, out
    assert 1.99 <= np.count_nonzero(c["line"] == 3) * 0.001 <= 2.02


def test_m00_holds_on_the_basic_mlc_until_the_operators_cycle_start(tmp_path, capsys):
    # the mill's basic MLC: M00 is the NC's hold (M3x037 until Cycle Start), as on the lathe MLC (decision B78)
    for resume in (0.3, 1.2):
        code, c = run(tmp_path, M00, "--m00-resume", str(resume))
        out = capsys.readouterr().out
        assert code == 0 and "basic" in out, out
        held = np.flatnonzero(c["line"] == 3)
        assert resume - 0.01 <= len(held) * 0.001 <= resume + 0.02, (resume, len(held))
        assert np.allclose(c["X_cmd"][held], 20.0, atol=1e-9) and abs(c["X_cmd"][-1]) < 1e-9
    # the same hold as the lathe MLC's on the same bench, within two cycles
    _, lathe = run(tmp_path, M00, "--m00-resume", "1.2", "--mlc", "lathe")
    assert abs(np.count_nonzero(lathe["line"] == 3) - len(held)) <= 2


def test_m01_runs_on_under_the_basic_mlc_and_m00_resume_0_does_not_wait(tmp_path, capsys):
    # M01 holds only with the optional-stop switch M2x009 (§3.8.1.2), which the basic MLC has not
    code, c = run(tmp_path, M00.replace("M00", "M01"), "--m00-resume", "5")
    assert code == 0 and np.count_nonzero(c["line"] == 3) <= 2 and c["t"][-1] < 2.5
    code, c = run(tmp_path, M00, "--m00-resume", "0")
    assert code == 0 and np.count_nonzero(c["line"] == 3) <= 2 and c["t"][-1] < 2.5
    capsys.readouterr()
    # the lathe MLC with the switch ON holds M01 for the operator's --m00-resume, as the guide says
    code, c = run(tmp_path, M00.replace("M00", "M01"), "--mlc", "lathe", "--at", "t=0:set M21009=1",
                  "--m00-resume", "0.7")
    assert code == 0 and 0.69 <= np.count_nonzero(c["line"] == 3) * 0.001 <= 0.72
    capsys.readouterr()


# the lathe: Z feeds to -5, the turret indexes 2 stations (0.3 s, mlc/lathe.py) on line 3, Z feeds back
TURRET = "G21 G18 G98\nG01 Z-5. F600\nT0303\nG01 Z0.\nM30\n"


def test_an_mst_block_is_the_current_line_while_the_nc_waits_for_its_finish(tmp_path, capsys):
    # NC5's screen shows the block being executed: the T block while the turret indexes (decision B79)
    code, c = run(tmp_path, TURRET, "--at", "line=3:set D21006=7", bench="")
    out = capsys.readouterr().out
    assert code == 0, out
    held = np.flatnonzero(c["line"] == 3)
    assert 0.29 <= len(held) * 0.001 <= 0.31, len(held)  # 2 stations × 0.15 s, the handshake's scans
    assert np.all(np.diff(held) == 1) and np.allclose(c["Z_cmd"][held], -5.0, atol=1e-9)
    assert c["line"][held[0] - 1] == 2 and c["line"][held[-1] + 1] == 4
    assert "line 3  set D21006=7   [line=3]" in out and "never triggered" not in out


CUT = "G90 G54 G17 G21 G94\nG01 X100. F3000\nM30\n"  # 2 s at 50 mm/s along X on the mill


def test_max_time_stops_a_run_held_by_a_zero_feed_override(tmp_path, capsys):
    # 0 % feed override: the cut never moves; --max-time 1.5 ends it as the bench's max_time would, at 1.5 s
    code, c = run(tmp_path, CUT, "--feed-override", "0", "--max-time", "1.5")
    out = capsys.readouterr().out
    assert code == 1, out
    assert "ALARM 0xDE03 at line 2 -- run exceeded --max-time of 1.5 s" in out and "result         STOPPED" in out
    assert np.all(np.abs(c["X_cmd"]) < 1e-9)  # nothing moved
    hit = [i for i, a in enumerate(csv.DictReader(open(tmp_path / "t.csv"))) if a["alarm"] == "0xDE03"]
    assert len(hit) == 1 and abs(c["t"][hit[0]] - 1.5) < 0.0015
    assert c["t"][-1] < 2.0 and int(c["X_sw"][-1]) & 0x6F in (0x40, 0x21)  # drives disabled at the end


def test_max_time_cuts_a_moving_axis_along_the_path(tmp_path, capsys):
    code, c = run(tmp_path, CUT, "--max-time", "1")
    out = capsys.readouterr().out
    assert code == 1 and "run exceeded --max-time of 1 s" in out, out
    x = c["X_cmd"]
    stop = int(np.argmax(c["t"] >= 1.0))
    assert 45.0 < x[stop] < 55.0 and x[-1] < 70.0  # X was at ≈ 50 mm, braked along the path, never reached 100
    assert np.all(np.diff(x) >= -1e-9)  # no reversal: a jerk-limited stop, not a jump
    assert int(c["X_sw"][-1]) & 0x6F in (0x40, 0x21)


def test_bad_max_time_is_a_usage_error(tmp_path, capsys):
    for bad in ("0", "-1", "nan", "inf"):
        code, _ = run(tmp_path, CUT, "--max-time", bad)
        err = capsys.readouterr().err
        assert code == 2 and f"--max-time {bad}: simulated seconds must be > 0" in err and "Traceback" not in err


def test_max_time_names_the_block_the_nc_waits_on(tmp_path, capsys):
    # an MLC that never answers M09: the run stands at line 3 (M09), where max_time finds it, not at the move before
    mlc = tmp_path / "never.py"
    mlc.write_text("def scan(mlc):\n    pass\n")
    code, c = run(tmp_path, "G90 G54 G17 G21 G94\nG01 X10. F3000\nM09\nG01 X0.\nM30\n", "--mlc", str(mlc),
                  "--max-time", "1", "--aux-timeout", "0.5")
    out = capsys.readouterr().out
    assert code == 1 and "ALARM 0xDE03 in p.nc at line 3: M09 -- run exceeded --max-time of 1 s" in out, out


def test_recovery_events_timed_after_an_estop_are_refused_before_the_run(tmp_path, capsys):
    # the E-stop aborts the program and the run ends at it: estop-off / reset / cycle-start later could never act
    ev = tmp_path / "ev.txt"
    ev.write_text("t=0.3:estop\nt=0.2:set D21006=1\ncycle=600:estop-off   # release\nt=0.7:reset\n")
    code, c = run(tmp_path, CUT, "--events", str(ev))
    err = capsys.readouterr().err
    assert code == 2 and not c and "Traceback" not in err, err
    assert f"{ev}:3: 'cycle=600:estop-off' comes after the E-stop 't=0.3:estop' ({ev}:1)" in err
    assert "alarm 0x0401" in err and "hil script" in err
    # before the E-stop they are fine, and an event after it that is no recovery stays a run-time matter
    code, c = run(tmp_path, CUT, "--at", "t=0.1:feed-hold", "--at", "t=0.2:cycle-start", "--at", "t=0.5:estop",
                  "--at", "t=5:set D21006=1")
    io = capsys.readouterr()
    assert code == 1 and "ALARM 0x0401" in io.out, io.out
    assert "never triggered: t=5:set D21006=1  (the E-stop at t=0.500 s ended the run)" in io.out
    assert "applied" in io.out and "cycle-start (pulse M21000)   [t=0.2]" in io.out
    assert "(the E-stop at t=0.500 s ended the run)" in io.err


RECOVER = """def main(machine):
    machine.jog("Z", -1, 0.3)
    machine.estop()
    machine.wait(0.3)
    machine.estop({release})
    machine.reset()
    machine.wait(0.2)
    machine.jog("Z", 1, 0.2)
"""


def test_a_script_that_recovers_from_its_estop_ends_ok_and_says_the_alarm_was_cleared(tmp_path, capsys):
    # NC5: E-stop → 0x0401; released and reset, the alarm is gone and the axes jog again (decision B59)
    script = tmp_path / "recover.py"
    script.write_text(RECOVER.format(release="False"))
    code = main(["script", str(script)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "ALARM 0x0401 -- emergency stop signal is triggered (M2x013) (cleared by reset at t=0.6" in out
    z = next(ln for ln in out.splitlines() if ln.startswith("Z ")).split()
    end, low = float(z[3]), float(z[7].split("…")[0])
    assert end - low > 3.0, z  # after the recovery Z jogged back up 3.3 mm from where the E-stop braked it
    # the E-stop still pressed at the reset: nothing is cleared, the alarm stands, exit 1
    script.write_text(RECOVER.format(release="True"))
    code = main(["script", str(script)])
    out = capsys.readouterr().out
    assert code == 1 and "cleared by reset" not in out and "ALARM 0x0401" in out, out


def test_a_campaign_fault_with_recovery_after_its_estop_is_a_bad_campaign_file(tmp_path, capsys):
    # each case would have refused it at run time, reported as an internal-error alarm: refused with the file
    import shutil

    shutil.copytree(ROOT / "tests" / "data" / "campaign", tmp_path / "c")
    spec = tmp_path / "c" / "recover.toml"
    spec.write_text('[campaign]\nprograms = ["short_turn.nc"]\nbenches = ["bench.toml"]\nfaults = ["recover"]\n'
                    '[faults]\nrecover = ["t=0.3:estop", "t=0.6:estop-off", "t=0.7:reset"]\n')
    code = main(["campaign", str(spec), "--out", str(tmp_path / "out"), "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "fault 'recover'" in err and "'t=0.6:estop-off' comes after the E-stop 't=0.3:estop'" in err, err
    assert "Traceback" not in err and not (tmp_path / "out" / "results.parquet").exists()


def test_limits_judge_an_estop_mid_deceleration_by_its_quick_stop_not_the_coast(tmp_path, capsys):
    # the E-stop at 0.3 s hits X while it decelerates: until the drive takes its quick stop the bench lets the
    # setpoint coast at the drive's speed (B12) — a step of the acceleration that is no planned path (decision B82)
    code, c = run(tmp_path, (ROOT / "tests" / "data" / "campaign" / "short_turn.nc").read_text(), "--at", "t=0.3:estop",
                  bench=str(ROOT / "benches" / "lathe-2axis.toml"))
    assert code == 1
    capsys.readouterr()
    assert main(["check", str(tmp_path / "t.csv"), "--limits"]) == 0
    out = capsys.readouterr().out
    assert "ok    jerk X: " in out and "ok    quick stop deceleration X: " in out and "0 failed" in out, out
    # the coast is there (what the jerk check flagged before): the setpoint's third difference across the
    # E-stop's row is far over X's 1.5e5 mm/s^3, with the drive still in Operation Enabled
    stop = int(np.flatnonzero(c["t"] >= 0.3)[0])
    jerk = np.abs(np.diff(c["X_cmd"][stop - 3:stop + 3], n=3)) / 0.001 ** 3
    assert jerk.max() > 5 * 1.5e5 and int(c["X_sw"][stop]) & 0x6F == 0x27, jerk


def test_a_reset_that_aborts_the_program_says_so_in_the_summary_and_the_end_record(tmp_path, capsys):
    # RESET flushes the program (NC5 App. B M2x004, decision B58): the run ends there without an alarm; the
    # summary said only `STOPPED` and the trace's end record `completed`
    from hil.trace_read import TraceFile

    prog = tmp_path / "p.nc"
    prog.write_text(CUT)
    trace = tmp_path / "t.parquet"
    code = main(["run", str(prog), "--bench", MILL, "--trace", str(trace), "--no-check", "--at", "t=0.5:reset"])
    out = capsys.readouterr().out
    assert code == 1 and "alarms         none" in out, out
    assert "result         STOPPED: the program was aborted before its end (a reset flushes it)" in out, out
    end = TraceFile(trace).meta["end"]
    assert end["reason"] == "aborted" and end["alarm"] is None and end["complete"], end
    x = TraceFile(trace).arrays(["X_cmd"])["X_cmd"]
    assert 10.0 < x[-1] < 40.0  # it stopped on the way to X100, at 0.5 s of 50 mm/s
