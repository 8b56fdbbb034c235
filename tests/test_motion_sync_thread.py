"""Issue 5 §4: spindle-synchronised threading and feed per revolution from the spindle's ACTUAL
speed, run in lock-step on the simulated bench (virtual CSP axes + CSV spindle drive)."""

from __future__ import annotations

import numpy as np
import pytest

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program

LEAD = 1.5


def passes_program(xs: list[float], q: list[float] | None = None, lead: float = LEAD, rpm: int = 600,
                   k: float | None = None) -> str:
    """Repeated G32 passes at different X (a hand-written multi-pass thread), optional Q per pass."""
    out = ["G21 G18 G99", f"S{rpm} M03", "G00 X30. Z5."]
    for i, x in enumerate(xs):
        qw = f" Q{int(q[i] * 1000)}" if q else ""
        code = f"G34 Z-20. F{lead} K{k}" if k is not None else f"G32 Z-20. F{lead}{qw}"
        out += [f"G00 X{x}", code, "G00 X30.", "Z5."]
    out.append("M30")
    return "\n".join(out) + "\n"


def run_bench(text: str, **drive):
    bench = default_lathe()
    for key, v in drive.items():
        setattr(bench.spindles[0].drive, key, v)
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    rows = []

    def grab(r):
        if r.channel is not None:
            rows.append((r.line, r._commands[0], r._commands[1], r.actual[1], r.spindle_actual_angle(),
                         r.spindle_actual_rpm()))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    return result, np.array(rows), runner


def thread_rows(rows: np.ndarray, line: int) -> np.ndarray:
    return rows[rows[:, 0] == line]


def locked(m: np.ndarray, lo: float = -15.0, hi: float = 0.0, col: int = 2) -> np.ndarray:
    return m[(m[:, col] > lo) & (m[:, col] < hi)]


def phase(m: np.ndarray, col: int, lead: float = LEAD) -> np.ndarray:
    """Thread phase: spindle angle less the angle Z's travel from the start accounts for."""
    return (m[:, 4] - 360.0 * (5.0 - m[:, col]) / lead) % 360.0


def circ_spread(deg: np.ndarray) -> float:
    ref = deg[0]
    d = (deg - ref + 180.0) % 360.0 - 180.0
    return float(d.max() - d.min())


def test_every_pass_starts_on_the_same_spindle_phase():
    xs = [19.4, 19.0, 18.6, 18.3]
    result, rows, runner = run_bench(passes_program(xs))
    assert result.ok, result.alarms
    lines = [5 + 4 * i for i in range(len(xs))]
    # the sync angles the planner locked each pass to: index + Q, whole revolutions apart
    log = runner.channel.planner.thread_log
    assert [ln for ln, _, _ in log] == lines
    assert circ_spread(np.array([sync % 360.0 for _, sync, _ in log])) < 0.5
    # the spindle's measured angle when each pass starts moving
    starts = []
    for ln in lines:
        m = thread_rows(rows, ln)
        moving = np.flatnonzero(np.abs(np.diff(m[:, 2])) > 0)
        starts.append(m[moving[0], 4] % 360.0)
    assert circ_spread(np.array(starts)) < 0.5
    # the commanded and the actual Z meet the thread at the same phase on every pass
    cmd = np.concatenate([phase(locked(thread_rows(rows, ln)), 2) for ln in lines])
    act = np.concatenate([phase(locked(thread_rows(rows, ln), col=3), 3) for ln in lines])
    assert circ_spread(cmd) < 0.5
    assert circ_spread(act) < 0.5


def test_z_advances_one_lead_per_spindle_revolution():
    result, rows, _ = run_bench(passes_program([19.4]))
    assert result.ok, result.alarms
    m = locked(thread_rows(rows, 5))
    assert len(m) > 500
    revs = (m[-1, 4] - m[0, 4]) / 360.0
    assert abs((m[0, 2] - m[-1, 2]) / revs - LEAD) < 1e-6
    # and cycle by cycle
    dz = -np.diff(m[:, 2])
    drev = np.diff(m[:, 4]) / 360.0
    assert np.allclose(dz / drev, LEAD, atol=1e-6)


def test_start_angle_q_shifts_the_phase():
    result, rows, _ = run_bench(passes_program([19.4, 19.4], q=[0.0, 90.0]))
    assert result.ok, result.alarms
    p0 = phase(locked(thread_rows(rows, 5)), 2)
    p1 = phase(locked(thread_rows(rows, 9)), 2)
    shift = (np.median(p1) - np.median(p0)) % 360.0
    assert abs(shift - 90.0) < 0.5


def test_g34_lead_grows_per_revolution():
    result, rows, _ = run_bench(passes_program([19.4], lead=1.0, k=0.1))
    assert result.ok, result.alarms
    m = locked(thread_rows(rows, 5), lo=-18.0, hi=2.0)
    dz = -np.diff(m[:, 2])
    drev = np.diff(m[:, 4]) / 360.0
    lead_now = dz / drev
    # the lead rises by K = 0.1 mm per spindle revolution
    slope = np.polyfit(np.cumsum(drev), lead_now, 1)[0]
    assert abs(slope - 0.1) < 0.005


def test_feed_per_rev_follows_the_measured_spindle_speed():
    # A slow spindle ramp (csv_accel) makes the measured speed lag the commanded S by seconds:
    # the feed must follow what the spindle really does.
    text = "G21 G18 G99\nS600 M03\nG00 X30. Z5.\nG01 Z-40. F0.2\nM30\n"
    result, rows, _ = run_bench(text, csv_accel=2.0e6)  # counts/s²: ≈ 94 rpm/s
    assert result.ok, result.alarms
    m = thread_rows(rows, 4)
    v = -np.diff(m[:, 2]) / 0.001
    rpm = m[1:, 5]
    mid = (rpm > 100) & (rpm < 500) & (np.abs(np.diff(v, prepend=v[0])) < 0.05)
    mid[-200:] = False  # not the stop at the block end
    assert mid.sum() > 200  # the cut ran while the spindle was still coming up to speed
    expected = 0.2 * rpm[mid] / 60.0
    assert np.all(np.abs(v[mid] - expected) <= 0.03 * expected + 0.01)


def test_g76_phase_check_from_the_command_line(hil, program, tmp_path):
    prog = program("G21 G18 G99\nS800 M03\nG00 X28. Z5.\nG76 P020060 Q100 R0.05\n"
                   "G76 X21.4 Z-22. P1300 Q400 F2.\nG00 X60. Z20.\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--trace", trace)
    assert r.code == 0, r.out + r.err
    r = hil("check", trace, "--program", prog, "--thread-phase", "0.5", "--limits")
    assert r.code == 0, r.out
    assert "ok    thread phase" in r.out


# ---- the spindle settles before a thread arms (motion decisions 33) --------------------------------

def run_lathe_mlc(text: str, percent: int = 100, **drive):
    """Run with the Delta lathe MLC (M03 ends on "speed reached", 2 %) and the spindle override D21026;
    per cycle (time, line, X cmd, Z cmd, Z actual, spindle angle, measured rpm, waiting, drive's rpm command)."""
    from hil.scripting import build_mlc

    bench = default_lathe()
    for key, v in drive.items():
        setattr(bench.spindles[0].drive, key, v)
    mlc = build_mlc(bench, "lathe")
    mlc.put("D21026", percent)
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle), mlc=mlc)
    rows = []

    def grab(r):
        if r.channel is not None:
            rows.append((r.time, r.line, r._commands[0], r._commands[1], r.actual[1], r.spindle_actual_angle(),
                         r.spindle_actual_rpm(), float(r.channel.spindle_wait), r.spindle_command_rpm()))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    assert result.ok, result.alarms
    return np.array(rows), runner.channel.planner


def check_settled_passes(rows: np.ndarray, planner, rpm: float = 600.0) -> None:
    """Every pass: armed only after a wait-free or finished settle, at the commanded speed, and Z is
    start − lead × revolutions since the sync angle on every locked cycle; one phase for all passes."""
    from nc.motion.threading import SETTLE_BAND, SETTLE_CYCLES

    moving_rpm, cmd_phase, act_phase = [], [], []
    for line, sync, ramp_start in planner.thread_log:
        m = rows[rows[:, 1] == line]
        go = m[np.flatnonzero(np.abs(m[:, 3] - 5.0) > 1e-9)[0]:]  # Z has left the start point: the ramp runs
        go = go[: int(np.argmin(go[:, 3])) + 1]  # up to the thread's end (not G92's return)
        moving_rpm.append(go[:, 6])
        lk = go[(go[:, 3] < 0.0) & (go[:, 3] > -15.0)]  # locked, before the pull-out
        revs = (lk[:, 5] - sync) / 360.0
        assert len(lk) > 500
        assert np.allclose(lk[:, 3], 5.0 - LEAD * revs, atol=1e-6)  # lead × revolutions, exact
        cmd_phase.append((lk[:, 5] - 360.0 * (5.0 - lk[:, 3]) / LEAD) % 360.0)
        act_phase.append((lk[:, 5] - 360.0 * (5.0 - lk[:, 4]) / LEAD) % 360.0)
    moving = np.concatenate(moving_rpm)
    assert np.all(np.abs(moving - rpm) <= SETTLE_BAND * rpm)  # no pass ran on a spindle still speeding up
    assert circ_spread(np.concatenate(cmd_phase)) < 0.5
    assert circ_spread(np.concatenate(act_phase)) < 0.5
    assert all(w == 0 or w >= SETTLE_CYCLES for _, w in planner.thread_waits)


TWO_PASSES_AFTER_M03 = ("G21 G18 G99\nG00 X19.4 Z5.\nS600 M03\nG32 Z-20. F1.5\nG00 X30.\nZ5.\n"
                        "X19.0\nG32 Z-20. F1.5\nG00 X30.\nZ5.\nM30\n")


def test_thread_right_after_m03_waits_for_the_spindle_to_settle():
    # A slow spindle (≈ 94 rpm/s): M03 ends at 2 % short of S600 ("speed reached"), 125 ms before
    # the spindle really turns at 600; the first pass waits for that, the axes standing still.
    rows, planner = run_lathe_mlc(TWO_PASSES_AFTER_M03, csv_accel=2.0e6)
    waits = dict(planner.thread_waits)
    assert [ln for ln, _, _ in planner.thread_log] == [4, 8]
    assert waits[4] > 100 and waits[8] == 0
    wait = rows[rows[:, 7] > 0]
    assert len(wait) == waits[4] and np.all(wait[:, 1] == 4)  # the trace shows the thread's line waiting
    assert np.ptp(wait[:, 2]) == 0.0 and np.ptp(wait[:, 3]) == 0.0  # no creeping
    assert wait[0, 6] < 0.99 * 600.0 < 600.0 * (1 - 1e-3) < 1.0 * wait[-1, 6]
    check_settled_passes(rows, planner)


def test_g92_thread_waits_for_the_override_to_come_back_to_100_percent():
    text = "G21 G18 G99\nS600 M03\nG00 X30. Z5.\nG04 P300\nG92 X19.4 Z-20. F1.5\nX19.0\nG00 X60.\nM30\n"
    rows, planner = run_lathe_mlc(text, 80, csv_accel=2.0e6)
    # S600 M03 before any move: its line 2 is the current one while the MLC waits for the speed (bench B79)
    m03 = rows[(rows[:, 1] == 2) & (rows[:, 8] > 0.0)]
    assert np.allclose(m03[:, 8], 480.0) and m03[-1, 6] == pytest.approx(480.0, rel=0.02)  # at 80 %
    assert np.allclose(rows[rows[:, 1] == 5, 8], 600.0)  # 100 % once the thread is in the look-ahead
    waits = [w for _, w in planner.thread_waits]
    assert len(waits) == 2 and waits[0] > 300 and waits[1] == 0  # 480 → 600 rpm at ≈ 94 rpm/s
    wait = rows[rows[:, 7] > 0]
    assert np.ptp(wait[:, 2]) == 0.0 and np.ptp(wait[:, 3]) == 0.0
    check_settled_passes(rows, planner)


# When the first pass's Z leaves the start point, measured on main before the settle check was added.
START_AT_SPEED = 0.862


def test_no_wait_when_the_spindle_is_already_at_speed():
    rows, planner = run_lathe_mlc(passes_program([19.4, 19.0]))
    assert planner.thread_waits == [(5, 0), (9, 0)]
    assert not np.any(rows[:, 7])
    m = rows[rows[:, 1] == 5]
    start = m[np.flatnonzero(np.abs(m[:, 3] - 5.0) > 1e-9)[0], 0]
    assert start == pytest.approx(START_AT_SPEED, abs=1e-9)  # the same cycle as before the settle check
    check_settled_passes(rows, planner)


def test_spindle_settle_wait_from_the_command_line(hil, program, tmp_path):
    """`hil run` with the lathe MLC: G32 right after S600 M03 waits for the spindle (M03 ends at 2 %
    short), the summary says how long, the trace shows the axes standing on the thread's line."""
    import csv

    from conftest import ROOT

    prog = program("G21 G18 G99\nG00 X19.4 Z5.\nS600 M03\nG32 Z-20. F1.5\nG00 X30.\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--bench", ROOT / "benches" / "lathe-2axis.toml", "--trace", trace)
    assert r.code == 0, r.out + r.err
    assert "spindle settle line 4 " in r.out
    rows = [row for row in csv.DictReader(trace.open()) if row["line"] == "4"]
    moving = next(i for i, row in enumerate(rows) if abs(float(row["Z_cmd"]) - 5.0) > 1e-9)
    assert moving > 10  # stood still on line 4 for the settle cycles at least
    assert abs(float(rows[moving]["S1_rpm_act"]) - 600.0) <= 0.6
    assert abs(float(rows[0]["S1_rpm_act"]) - 600.0) > 0.6  # line 4 began before the spindle settled


@pytest.mark.parametrize("stop_at", [None, 2500])
def test_threading_flag_counts_the_thread_blocks_the_queue_holds(stop_at):
    """Channel.threading (spindle override held at 100 %) reads a count kept by the planner (issue 17), not a
    scan of the look-ahead queue: every cycle of four passes it equals the scan, as the passes leave the
    queue one by one, and a stop (reset) in the second pass clears it."""
    bench = default_lathe()
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    seen = []

    def check(r):
        ch = r.channel
        if ch is None:
            return
        pl = ch.planner
        scanned = pl._thread is not None or any(b.kind == "thread" for b in pl.blocks)
        seen.append((ch.threading, scanned))
        if r.cycle == stop_at:
            r.request_stop("test")  # stop along the path, then flush the queue (the NC's reset)

    runner.on_cycle = check
    runner.run_program(parse_program(passes_program([19.4, 19.0, 18.7, 18.5])))
    assert all(flag == scanned for flag, scanned in seen)
    assert sum(flag for flag, _ in seen) > 2000 and not seen[-1][0]
    assert runner.channel.planner.threads_queued == 0
