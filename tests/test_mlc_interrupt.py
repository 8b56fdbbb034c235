"""M96 program interruption through the channel and the MLC relays (NC5 §3.11.4.6): M2x019 stops the
running move on its path, the interrupt program runs from there with M3x031 ON, and its M99 goes on
in a straight line to the suspended block's end. Positions are checked in simulated time."""

from __future__ import annotations

import numpy as np
import pytest

from hil.bench_file import load_bench_file
from hil.scripting import Machine
from hil.session import make_link
from mlc.machine import Mlc
from nc.channel import RunState
from nc.interp import Interpreter
from nc.interrupt import m96_link
from nc.motion.offline import Stream, run
from nc.profiles import make_profile
from nc.store import ProgramStore
from tests.conftest import ROOT
from tests.motion_helpers import mill_cfg, worst_ratio

# line 3 cuts X0→X100 at 50 mm/s; O0050 lifts Z by 10 and lowers it again (incremental)
PROGRAM = ("G90 G17 G21 G94\nM96 P50\nG01 X100. F3000\nY50.\nX0\nM30\n"
           "O0050\nG91 G01 Z10. F2000\nZ-10.\nM99\n")
TRIGGER = 1000  # cycle of the M2x019 edge: X ≈ 48.9, half way along line 3


def stream(text: str = PROGRAM, trigger: int | None = TRIGGER, **cfg_kw):
    store = ProgramStore()
    prog = store.add_text(text)[0]
    it = Interpreter(make_profile("nc5-mill"), store=store)
    cfg = mill_cfg(**cfg_kw)
    seen: dict[str, list] = {"active": [], "trigger_x": []}

    def on_cycle(n, ch):
        if n == 0:
            ch.m96 = m96_link(it)
        if n == trigger:
            seen["trigger_x"].append(float(ch.planner.position[0]))
            ch.interrupt()
        seen["active"].append(ch.interrupt_active)

    st = run(it.run(prog), cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0}, on_cycle=on_cycle)
    return st, cfg, np.array(seen["active"]), seen["trigger_x"]


def test_m2x019_suspends_the_move_runs_o0050_and_returns_to_the_block_end():
    st, cfg, active, trig = stream()
    assert st.state is RunState.FINISHED and not st.alarms
    p, lines = st.positions, st.lines
    x_trig = trig[0]
    assert 48.0 < x_trig < 50.0
    # the cut stopped on its path a braking distance after the trigger, far from its end X100
    o50 = np.flatnonzero(np.isin(lines, (8, 9)))
    stop = p[o50[0] - 1]
    assert x_trig < stop[0] < x_trig + 1.5 and stop[1] == 0.0 and stop[2] == 0.0
    # braking began at once: no cycle after the trigger was faster than the one before it
    v = np.abs(np.diff(p[TRIGGER:o50[0], 0]))
    assert np.all(np.diff(v) <= 1e-12)
    # O0050 ran from the stop point: Z up 10 and back, X/Y standing still
    assert np.allclose(p[o50, 0], stop[0]) and np.allclose(p[o50, 1], 0.0)
    assert abs(p[o50, 2].max() - 10.0) < 1e-4 and abs(p[o50[-1], 2]) < 1e-9
    # M3x031 (interrupt_active) is ON exactly while O0050 moves, OFF before and after
    on = np.flatnonzero(active)
    assert on[0] <= o50[0] and on[-1] >= o50[-1] and not active[TRIGGER - 1]
    assert not active[-1] and np.all(active[on[0]:on[-1] + 1])
    # M99: line 3 goes on from the stop point to X100, then lines 4 and 5 as programmed
    after = lines[o50[-1] + 1:]
    rest = p[o50[-1] + 1:]
    l3 = rest[after == 3]
    assert np.allclose(l3[:, 1:], 0.0, atol=1e-3) and abs(l3[:, 0].max() - 100.0) < 1e-3 and l3[0, 0] >= stop[0]
    assert abs(rest[after == 4][:, 1].max() - 50.0) < 1e-3
    assert np.allclose(p[-1], (0.0, 50.0, 0.0), atol=1e-9)
    # every cycle, also the stop and the restart, within the axis limits
    worst = worst_ratio(st, cfg)
    assert max(worst.values()) <= 1.0 + 1e-6, worst


def test_interrupt_with_the_position_filter_on():
    st, cfg, active, trig = stream(filter_time=0.016, filter_scurve=0.008)
    assert st.state is RunState.FINISHED and not st.alarms
    p = st.positions
    assert 9.9 < p[:, 2].max() < 10.0 + 1e-9 and p[np.argmax(p[:, 2]), 0] < 51.0  # the filter rounds the reversal
    assert np.allclose(p[-1], (0.0, 50.0, 0.0), atol=1e-9)
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_m97_or_no_m96_makes_the_trigger_do_nothing():
    plain, _, _, _ = stream(trigger=None)
    for text in (PROGRAM.replace("M96 P50\n", "M96 P50\nM97\n"), PROGRAM.replace("M96 P50\n", "")):
        st, _, active, _ = stream(text)
        assert st.state is RunState.FINISHED and not active.any()
        assert st.positions[:, 2].max() == 0.0  # O0050 never ran
        assert len(st.positions) == len(plain.positions) and np.allclose(st.positions, plain.positions)


def test_interrupt_of_an_arc_returns_in_a_straight_line():
    text = ("G90 G17 G21 G94\nM96 P50\nG02 X20. Y0 R10. F1200\nM30\n"
            "O0050\nG91 G01 Z5. F2000\nZ-5.\nM99\n")
    st, cfg, _, _ = stream(text, trigger=400)
    assert st.state is RunState.FINISHED and not st.alarms
    p, lines = st.positions, st.lines
    o50 = np.flatnonzero(np.isin(lines, (6, 7)))
    stop = p[o50[0] - 1]
    assert abs(np.hypot(stop[0] - 10.0, stop[1]) - 10.0) < 1e-6 and 0.5 < stop[0] < 19.5  # on the arc
    back = p[o50[-1] + 1:]
    # straight from the stop point to X20 Y0 (N§3.11.4.6 note 2): every point on that chord
    d = np.array([20.0, 0.0]) - stop[:2]
    cross = (back[:, 0] - stop[0]) * d[1] - (back[:, 1] - stop[1]) * d[0]
    assert np.abs(cross).max() < 1e-6 and np.allclose(p[-1], (20.0, 0.0, 0.0), atol=1e-9)
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_interrupt_with_g41_active_raises_0x0005():
    text = ("G90 G17 G21 G94\nM96 P50\nG41 D1 G01 X20. F3000\nX100.\nG40 X110.\nG01 Y10.\nM30\n"
            "O0050\nG91 G01 Z5. F2000\nM99\n")
    st, _, _, _ = stream(text, trigger=600)
    assert st.state is RunState.ALARM and [a.code for a in st.alarms] == [0x0005]


@pytest.fixture
def mill_machine():
    bench = load_bench_file(ROOT / "benches" / "mill-3axis.toml")
    mlc = Mlc(axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config())
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    yield m
    m.close()


def test_m21019_relay_interrupts_on_the_bench_and_m31031_shows_it(mill_machine):
    m = mill_machine
    ch = m.start_program(PROGRAM.replace("G90 G17", "G90 G54 G17"), "m96")
    m.wait_until(lambda: m.position("X") > 40.0, 5.0, "X past 40")
    assert m.get("M31031") == 0
    m.set("M21019", 1)
    m.wait_until(lambda: m.get("M31031") == 1, 1.0, "M31031 ON")
    stop_x = m.command("X")
    assert 40.0 < stop_x < 60.0  # stopped on line 3, nowhere near X100
    m.wait_until(lambda: m.command("Z") > 109.9, 2.0, "O0050 lifts Z")
    assert abs(m.command("X") - stop_x) < 1e-9 and m.get("M31031") == 1
    m.wait_until(lambda: m.get("M31031") == 0, 2.0, "M31031 OFF")
    # M3x031 drops in the cycle the way back to X100 starts (the MLC sees it one scan later)
    assert abs(m.command("Z") - 100.0) < 1e-9 and 0.0 < m.command("X") - stop_x < 1e-4
    m.set("M21019", 0)
    m.wait_until(lambda: not ch.busy or ch.state is RunState.WAIT_AUX, 10.0, "program end")
    m.wait_until(lambda: not ch.busy, 2.0, "M30 finish")
    assert [round(m.command(a), 6) for a in "XYZ"] == [0.0, 50.0, 100.0]  # the bench starts at Z100
    assert m.get("M31031") == 0 and not ch.alarms


def test_reset_during_the_interrupt_program_drops_m3x031():

    seen: list[bool] = []
    store = ProgramStore()
    it = Interpreter(make_profile("nc5-mill"), store=store)
    prog = store.add_text(PROGRAM)[0]
    cfg = mill_cfg()

    def hook(n, ch):
        if n == 0:
            ch.m96 = m96_link(it)
        if n == TRIGGER:
            ch.interrupt()
        if n == 1100 and ch.interrupt_active:  # O0050 is lifting Z
            ch.reset()
            seen.append(ch.interrupt_active)

    st = run(it.run(prog), cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0}, on_cycle=hook)
    assert seen == [False] and st.state is RunState.IDLE
    assert 0.0 < st.positions[-1, 2] < 10.0  # stopped on O0050's Z move, never went back to line 3
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_hil_script_example_raises_m21019_mid_cut(capsys):
    from hil.cli import main

    code = main(["script", str(ROOT / "examples" / "scripts" / "m96_interrupt.py"),
                 "--bench", str(ROOT / "benches" / "mill-3axis.toml")])
    out = capsys.readouterr().out
    assert code == 0, out
    taken = next(line for line in out.splitlines() if "M21019 taken" in line)
    assert 50.0 < float(taken.split("X stopped at ")[1].split()[0]) < 53.0
    assert "end: X 0.0000 Y 50.0000 Z 100.0000" in out and "alarms  none" in out


# ---- a trigger while the channel is not moving the program (decision "latched trigger") -----------
# line 3 cuts to X50, line 4 is an M-code / a dwell, line 5 cuts on to X100; O0050 lifts Z by 10 and back
LATCH = ("G90 G17 G21 G94\nM96 P50\nG01 X50. F3000\n{mid}\nX100.\nM30\n"
         "O0050\nG91 G01 Z10. F2000\nZ-10.\nM99\n")


def drive(text: str, act, single_block: bool = False, cycles: int = 20_000, held: tuple[int, ...] = ()):
    """Step a channel by hand: `act(n, ch)` is the MLC/operator of cycle n (hold, cycle start, trigger,
    the finish of the M codes in `held`; every other M/S/T code is finished at once). Returns positions, lines, M3x031 per cycle, the channel and the motion config."""
    from nc.channel import Channel
    from nc.motion.planner import Planner

    store = ProgramStore()
    prog = store.add_text(text)[0]
    it = Interpreter(make_profile("nc5-mill"), store=store)
    cfg = mill_cfg()
    ch = Channel(Planner(cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0}), single_block=single_block)
    ch.m96 = m96_link(it)
    ch.load(it.run(prog))
    ch.cycle_start()
    rows, lines, active = [], [], []
    for n in range(cycles):
        if not ch.busy:
            break
        if ch.pending_aux is not None and ch.pending_aux.value not in held:
            ch.finish_aux()
        act(n, ch)
        sp = ch.step()
        rows.append(sp.positions.copy())
        lines.append(sp.line)
        active.append(ch.interrupt_active)
    st = Stream(np.array(rows), np.array(lines), cfg.cycle, cfg.axes, ch.state, list(ch.alarms))
    return st, np.array(active), ch, cfg


def _o50_ran_from(st, active, x: float) -> np.ndarray:
    p = st.positions
    on = np.flatnonzero(active)
    assert len(on) and np.allclose(p[on, 0], x, atol=1e-9) and np.allclose(p[on, 1], 0.0)
    assert abs(p[on, 2].max() - 10.0) < 1e-4
    assert np.allclose(p[-1], (100.0, 0.0, 0.0), atol=1e-9)  # then on to line 5's end
    return on


def test_trigger_while_an_m_code_waits_runs_right_after_its_finish():
    seen: dict[str, int] = {}

    def act(n, ch):
        if ch.state is RunState.WAIT_AUX and "wait" not in seen:
            seen["wait"] = n
        if "wait" in seen and n == seen["wait"] + 50:
            ch.interrupt()  # M08 still waiting for the MLC's finish
        if "wait" in seen and n == seen["wait"] + 300:
            seen["finish"] = n
            ch.finish_aux()

    st, active, ch, cfg = drive(LATCH.format(mid="M08"), act, held=(8,))
    assert ch.state is RunState.FINISHED and not ch.alarms
    on = _o50_ran_from(st, active, 50.0)
    assert not active[:seen["finish"] + 1].any()  # nothing while the M-code waits
    assert on[0] - seen["finish"] <= 3  # the interrupt program starts in the cycles after the finish
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_trigger_during_feed_hold_runs_when_cycle_start_resumes():
    seen: dict[str, int] = {}

    def act(n, ch):
        if n == 600:
            ch.feed_hold()  # on line 3, X ≈ 20
        if n == 1200:
            ch.interrupt()  # standing in feed hold
        if n == 1500:
            seen["x"] = float(ch.planner.position[0])
            ch.cycle_start()

    st, active, ch, cfg = drive(LATCH.format(mid="M08"), act)
    assert ch.state is RunState.FINISHED and not ch.alarms
    assert 10.0 < seen["x"] < 40.0 and not active[:1501].any()
    on = _o50_ran_from(st, active, seen["x"])  # from where the hold left the axes, not further on
    assert on[0] - 1500 <= 3
    # M99: line 3 goes on from the hold point to X50, then M08 and line 5
    after = st.lines[on[-1] + 1:]
    assert abs(st.positions[on[-1] + 1:][after == 3][:, 0].max() - 50.0) < 1e-6
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_trigger_at_a_single_block_stop_runs_at_the_next_cycle_start():
    seen: dict[str, int] = {}

    def act(n, ch):
        if ch.state is RunState.BLOCK_STOP:
            if abs(ch.planner.position[0] - 50.0) < 1e-9 and "trigger" not in seen:
                seen["trigger"] = n  # stopped after line 3 (X50)
                ch.interrupt()
            elif n >= seen.get("trigger", n) + 200:
                seen.setdefault("start", n)
                ch.cycle_start()

    st, active, ch, cfg = drive(LATCH.format(mid="G04 X0.5"), act, single_block=True)
    assert ch.state is RunState.FINISHED and not ch.alarms
    on = _o50_ran_from(st, active, 50.0)
    assert not active[:seen["start"] + 1].any() and on[0] - seen["start"] <= 3
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_trigger_during_a_dwell_runs_at_once_and_the_dwell_runs_again_whole():
    seen: dict[str, int] = {}

    def act(n, ch):
        act_b = ch.planner.active
        if act_b is not None and act_b.kind == "dwell" and "dwell" not in seen:
            seen["dwell"] = n
        if "dwell" in seen and n == seen["dwell"] + 200:  # 0.2 s into the 0.5 s dwell
            ch.interrupt()

    st, active, ch, cfg = drive(LATCH.format(mid="G04 X0.5"), act)
    assert ch.state is RunState.FINISHED and not ch.alarms
    on = _o50_ran_from(st, active, 50.0)
    assert on[0] - (seen["dwell"] + 200) <= 3  # no waiting the dwell out
    # after M99 the dwell runs its full 0.5 s at X50 before line 5 moves
    rest = st.positions[on[-1] + 1:, 0]
    still = np.flatnonzero(np.abs(rest - 50.0) > 1e-9)[0]
    assert abs(still * st.cycle - 0.5) <= 3 * st.cycle
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6


def test_trigger_latched_after_m97_or_at_m30_does_nothing():
    def act(n, ch):
        if ch.state is RunState.WAIT_AUX:
            ch.interrupt()  # every cycle an M-code (M08, then M30) waits
            if n % 100 == 0:
                ch.finish_aux()

    for text in (LATCH.format(mid="M97\nM08"), LATCH.format(mid="M08")):
        st, active, ch, _ = drive(text, act, held=(8, 30))  # the second: M08's wait latches, M30's ignores
        assert ch.state is RunState.FINISHED and not ch.alarms
        if "M97" in text:
            assert not active.any() and st.positions[:, 2].max() == 0.0
        else:
            assert np.flatnonzero(np.diff(active.astype(int)) == 1).size == 1  # once, after M08 only
