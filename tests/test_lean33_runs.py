"""B173 (issue 17): the lean lane's runs (nc.interp.lean_run) read the plain lines after a line of one shape a chunk at a
time and hand the Moves out one by one. At every event, not only at the end, the interpreter stands where stepping
block by block leaves it: the event, the position, the last target, the program counter, the block counter, the
block, the program, the modal state, the # variables. Runs of one shape (N, G, F, lower case, blanks, tabs) of up to
200 lines meet what stops a run: a line of another shape, a word without a point, a block the parser keeps (a
comment, '/'), a macro call, a variable or offset written by the program or from outside between two events, a
mode change, radius compensation and its cancel, a ,C/,R corner, an alarm, a statement budget, an M96 interrupt
through a channel; with and without the preview window (which reads a run past the corner and compensation stages
while both are idle). `SoftLimits.check`'s box test (straight-line code) gives the full check's alarm on a run of
moves checked one after the other."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.budget import StatementBudget
from nc.interp import Interpreter
from nc.moves import Busy, Move
from nc.profiles import make_profile
from nc.softlimits import SoftLimits
from nc.store import ProgramStore
from tests.test_lean25_equivalence import _setpoints
from tests.test_softlimits_inside import _same_alarm

AXES = ("X", "Y", "Z")


def _snapshot(ip: Interpreter) -> tuple:
    fr = ip.stack[-1] if ip.stack else None
    return (dict(ip.position), dict(ip.last_target), None if fr is None else (fr.program.name, fr.pc), ip._executed,
            repr(ip.block), ip.program_name, repr(ip.state), ip.unit_locked, ip.variable(100), ip.variable(1))


def _trace(text: str, lean: bool, outside: dict[int, tuple[int, float]] | None = None, budget: int | None = None,
           preview: bool = False) -> tuple[list, str | None, int]:
    """Every event with the interpreter's state right after it; `outside`: after the k-th event, write # n = v (as an
    MLC or a script between two cycles). Returns the trace, the alarm and how many chunks the lane's runs read."""
    store = ProgramStore()
    store.add_text(text, "p.nc")
    ip = Interpreter(make_profile("nc5-mill"), store=store)
    ip.lean = lean
    if budget is not None:
        ip.budget = StatementBudget(budget)
    out: list = []
    alarm = None
    try:
        for k, ev in enumerate(ip.run(store.loaded[1000], preview=preview)):
            out.append((repr(ev), _snapshot(ip)))
            if isinstance(ev, Busy):
                ip.budget.new_cycle()  # type: ignore[union-attr]
            if outside and k in outside:
                ip.vars.set(*outside[k])
    except NcAlarm as exc:
        alarm = repr(exc.alarm)
    return out, alarm, (ip._lean.runs if ip._lean is not None else 0)


def _same(text: str, **kw) -> tuple[list, str | None, int]:
    lean = _trace(text, True, **kw)
    general = _trace(text, False, **kw)
    assert lean[:2] == general[:2]
    return lean


def _num(v: float, point: bool = True) -> str:
    return f"{v:.4f}" if point else str(int(v))


@st.composite
def run_of_one_shape(draw) -> list[str]:
    """A run of lines of one shape (the letters, their order, case and blanks fixed; the numbers free)."""
    axes = draw(st.lists(st.sampled_from(AXES), min_size=1, max_size=3, unique=True))
    g = draw(st.sampled_from([None, None, "G1", "G01", "G0", "g1"]))
    f = draw(st.sampled_from([None, None, "F"]))
    n = draw(st.booleans())
    sep = draw(st.sampled_from([" ", "", "\t", "  "]))
    lead = draw(st.sampled_from(["", "", " "]))
    lower = draw(st.integers(0, 8)) == 0
    count = draw(st.integers(1, 200))
    lines = []
    for i in range(count):
        words = ([f"N{i + 1}"] if n else []) + ([g] if g else [])
        words += [a + _num(draw(st.floats(-400, 400, allow_nan=False)), draw(st.integers(0, 60)) != 0) for a in axes]
        if f:
            words.append("F" + draw(st.sampled_from(["1200", "3000.", "250.5", "0", "-5"]) if draw(st.integers(0, 30)) == 0
                                    else st.just("1500.")))
        line = lead + sep.join(words)
        lines.append(line.lower() if lower else line)
    return lines


BETWEEN = ["G91", "G90", "G55", "G54", "G10 L2 P1 X0.5 Y-0.25", "#100 = #5001 + #4001", "#1 = #1 + 0.5",
           "X#1 Y2.", "(a comment)", "X1. Y2. (why)", "/X3. Y3.", "", "G65 P9000 A1.", "M98 P9001", "G1 X3000000000.",
           "F-1", "G0", "G1 F2000", "G61", "G64", "N7 G1 X1. F800", "G04 P10", "M3 S500", "X5 Y5", "G10 L2 P2 Z1.",
           "G10 L12 P1 R2.\nG41 D1 X10. Y10.\nX20.\nG40 X0 Y0", "G10 L12 P1 R2.\nG42 D1 X5. Y5.\nG40",
           "X10. Y10. ,C1.", "X20. Y10. ,R2.", "G17", "G18\nG17"]


@st.composite
def programs(draw) -> str:
    lines = ["O1000", "G90 G17 G94 G01 F3000"]
    for _ in range(draw(st.integers(1, 4))):
        lines += draw(run_of_one_shape())
        lines += draw(st.lists(st.sampled_from(BETWEEN), max_size=3))
    lines.append("M30")
    return "\n".join(lines) + "\nO9000\n#100 = #100 + #1\nG91 G1 Z0.1\nG90\nM99\nO9001\nG1 X1. Y1.\nX2.\nM99\n"


@settings(max_examples=80, deadline=None)
@given(text=programs(), outside=st.dictionaries(st.integers(0, 300), st.tuples(st.sampled_from([100, 22002, 22003, 1]),
                                                                               st.floats(-5, 5, allow_nan=False)),
                                                max_size=2),
       budget=st.sampled_from([None, None, 1]), preview=st.booleans())
def test_runs_give_stepping_state_at_every_event(text: str, outside: dict, budget: int | None, preview: bool) -> None:
    _same(text, outside=outside, budget=budget, preview=preview)


def _cam(n: int, first: int = 1) -> str:
    return "\n".join(f"X{0.05 * i:.4f} Y{5.0 * math.sin(i / 40.0):.4f}" for i in range(first, first + n))


def test_a_cam_program_reads_its_lines_in_runs_with_stepping_state() -> None:
    trace, alarm, runs = _same("O1000\nG90 G17 G94 G01 F3000\n" + _cam(1000) + "\nM30\n")
    assert alarm is None and sum(e.startswith("Move(") for e, _ in trace) == 1000
    assert runs >= 1000 // 64  # the runs read them (a chunk of 64 lines at a time)


def test_a_subprogram_called_twice_is_read_in_runs_both_times() -> None:
    """A chunk refused at the subprogram's end (its M99) does not keep the next call from runs at its start."""
    sub = "M30\nO9002\n" + _cam(150) + "\nM99\n"
    once = _same("O1000\nG90 G1 F2000\nM98 P9002\n" + sub, preview=True)
    trace, alarm, runs = _same("O1000\nG90 G1 F2000\nM98 P9002\nG10 L2 P1 X1.\nM98 P9002\n" + sub, preview=True)
    assert alarm is None and sum(e.startswith("Move(") for e, _ in trace) == 300
    assert once[2] >= 3 and runs == 2 * once[2]  # as many chunks the second time


def test_an_offset_written_from_outside_mid_chunk_stops_the_run_there() -> None:
    """G54 X (#22002) written after the 70th move: the 71st line and after are read with the new origin, as
    stepping reads them; the run read the first lines."""
    trace, _, runs = _same("O1000\nG90 G1 F2000\n" + _cam(200) + "\nM30\n", outside={69: (22002, 10.0)})  # after the 70th event
    moves = [e for e, _ in trace if e.startswith("Move(")]
    assert runs > 0 and len(moves) == 200
    ends = [state[0]["X"] for e, state in trace if e.startswith("Move(")]
    assert ends[69] == pytest.approx(0.05 * 70) and ends[70] == pytest.approx(0.05 * 71 + 10.0)


def test_an_alarm_in_a_run_names_its_line_as_stepping() -> None:
    """A target out of range on line 91 (the 89th of a run of 100): the moves before it, then 0x120E at that
    line and block, as stepping gives them."""
    lines = _cam(100).split("\n")
    lines[88] = "X3000000000. Y1.0000"
    trace, alarm, runs = _same("O1000\nG90 G1 F2000\n" + "\n".join(lines) + "\nM30\n")
    assert alarm is not None and "code=4622" in alarm and "line=91" in alarm and "X3000000000. Y1.0000" in alarm
    assert runs > 0 and sum(e.startswith("Move(") for e, _ in trace) == 88  # 0x120E; the run read the first lines


def test_a_word_without_a_point_mid_run_is_read_by_n8018() -> None:
    lines = _cam(100).split("\n")
    lines[50] = "X7 Y7"  # 0.007 mm (N8.018 Bit10 = 0)
    trace, alarm, _ = _same("O1000\nG90 G1 F2000\n" + "\n".join(lines) + "\nM30\n")
    assert alarm is None
    assert [s[0] for e, s in trace if e.startswith("Move(")][50] == {"X": 0.007, "Y": 0.007, "Z": 0.0}


@pytest.mark.parametrize("before", ["G10 L12 P1 R2.\nG41 D1 X10. Y10.\nX20.\nG40 X0 Y0",
                                    "G10 L12 P1 R2.\nG42 D1 X5. Y5.\nG40", "Y0.125 ,C0.01", "Y0.125 ,R0.01"])
def test_runs_right_after_compensation_or_a_corner_through_the_preview_window(before: str) -> None:
    """The lines right after a G40 (the compensator still holds the cancel move) or a ,C/,R block (its corner waits
    for the next move) are not read past the stages: the events and the state at each are stepping's."""
    trace, alarm, runs = _same("O1000\nG90 G17 G1 F2000\n" + before + "\n" + _cam(150) + "\nM30\n", preview=True)
    assert alarm is None and runs > 0 and sum(e.startswith("Move(") for e, _ in trace) >= 150


def test_through_a_channel_with_an_m96_interrupt_same_setpoints() -> None:
    """The interrupt mid-run (cycle 150: a chunk is being handed out) changes the modal state (G91, G55): the
    lines after it run in the new state on both paths, setpoint for setpoint."""
    text = ("G90 G17 G94 G01 F3000\nG10 L2 P2 X1. Y-1.\nM96 P50\n" + _cam(300) + "\nM30\nO0050\nG55\nG91 G01 Z1. "
            "F2000\nZ-1.\nM99\n")
    a, b = _setpoints(text, True, 150), _setpoints(text, False, 150)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) and a[2:] == b[2:]


# ---- SoftLimits.check's box test -------------------------------------------------------------------------------

value = st.one_of(st.floats(-600, 600), st.sampled_from([0.0, 500.0, -500.0, 500.0 + 1e-9, 500.0 + 2e-9, math.nan]))


@settings(max_examples=200, deadline=None)
@given(moves=st.lists(st.tuples(st.sampled_from([AXES, AXES, ("X", "Y")]), st.lists(value, min_size=6, max_size=6),
                                st.sampled_from(["line", "rapid", "arc"])), min_size=1, max_size=12),
       change=st.integers(0, 12), what=st.sampled_from(["param", "disable", "first", "none"]))
def test_the_box_test_gives_the_full_checks_alarm_move_after_move(moves: list, change: int, what: str) -> None:
    """One SoftLimits checks a run of moves (its box and straight-line test made at the first); midway a G10 L21
    value, a disabled axis or new bench segments come in: each move's alarm is the full check's."""
    params: dict[str, float] = {}
    sl = SoftLimits({"X": (-500.0, 500.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}, params)
    for k, (axes, vals, kind) in enumerate(moves):
        if k == change:
            if what == "param":
                params["soft limit 1 X"] = 100.0
            elif what == "disable":
                sl.disabled.add("Y")
            elif what == "first":
                sl.first = {"X": (-50.0, 50.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}
        start = dict(zip(AXES, vals[:3]))
        end = dict(zip(axes, vals[3:]))
        mv = Move(kind, 7, "G1 X1.", start, end, dict(end), {"X": 0.0, "Y": 0.0} if kind == "arc" else None, "cw",
                  plane=("X", "Y"))
        _same_alarm(sl, mv)


def test_the_box_test_is_made_and_answers_inside() -> None:
    sl = SoftLimits({"X": (-500.0, 500.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}, {})
    inside = Move("line", 1, "", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 2.0, "Z": 3.0}, {})
    assert sl.check(inside) is None  # the axes' names found
    assert sl.check(inside) is None and sl._fast is not None  # the box found, and its test
    assert sl._fast[3](inside.start, inside.end)
    out = Move("line", 2, "G1 X600.", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 600.0, "Y": 2.0, "Z": 3.0}, {})
    alarm = sl.check(out)
    assert alarm is not None and alarm.code == 0x0A01 and alarm.axis == "X"
