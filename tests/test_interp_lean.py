"""The lean lane (nc.interp.lean, issue 17) gives the events the general block path gives, bit for bit,
and leaves the same state: random programs mixing plain motion lines (N, G0/G1, F, axis words, numbers
with and without a point, lower case) with blocks the lane must not take (G91, offsets, G10, comments,
macro statements reading the state, expressions, arcs, ,C, G61, G41, polar, G96, alarms), on a mill
and a lathe profile, with and without a channel's statement budget."""

from __future__ import annotations

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.budget import StatementBudget
from nc.interp import Interpreter
from nc.interp.lean import LineBlock
from nc.moves import Busy, Move
from nc.profiles import make_profile
from nc.program.blocks import parse_block, parse_program
from nc.store import ProgramStore
from tests.test_interp_bulk import plain

READS = "#100 = #5001 + #4001 * 10 + #4109 + #4003 + #5041"  # position, G01/G00, F, G90/G91, work X


def other(axes: tuple[str, ...], lathe: bool) -> st.SearchStrategy[str]:
    a, b = axes[0], axes[-1]
    common = ["G91", "G90", "G90", "G54", "G55", "G10 L2 P2 " + a + "1.25 " + b + "-0.3", READS, READS,
              "(a comment) G1 " + a + "1.", "G1 " + a + "2. (why)", "#1 = #1 + 0.5", "G1 " + a + "#1 F800",
              "G2 " + a + "3. " + b + "3. R5.", "G1 " + a + "4. ,C0.5", "G04 P100", "M3 S500", "M5", "G61",
              "G64", "G1 " + a + "1. " + a + "2.", "G0 G1 " + a + "1.", "F-1", "G1 " + a + "3000000000.",
              "G94", "G95", "N5 G1 " + a + "7.5 F300", "/G1 " + a + "9.", "G09 G1 " + a + "2.", "F0"]
    if lathe:
        common += ["G96 S100", "G97 S500", "G98", "G99", "U1.", "W-1.", "G41", "G40"]
    else:
        common += ["G41 D1", "G40", "G16", "G15", "G68 X0 Y0 R30.", "G69", "G51 X0 Y0 P2000", "G50",
                   "G92 X1. Y1.", "G52 X5. Y-2.", "G43 H1", "G49"]
    return st.sampled_from(common)


@st.composite
def programs(draw, axes: tuple[str, ...], lathe: bool) -> str:
    lines = ["O1000", draw(st.sampled_from(["", "G10 L2 P1 " + " ".join(f"{a}{0.1 * (i + 1) - 0.25:.2f}"
                                                                       for i, a in enumerate(axes))]))]
    for _ in range(draw(st.integers(1, 6))):
        lines += draw(st.lists(plain(axes), min_size=0, max_size=8))
        lines += draw(st.lists(other(axes, lathe), min_size=0, max_size=3))
    lines.append("M30")
    return "\n".join(lines) + "\n"


def _run(profile_name: str, text: str, lean: bool, budget: int | None = None, params: dict | None = None,
         store: ProgramStore | None = None) -> tuple:
    """Every event (repr: each field, floats bit for bit), the alarm if any, and the state left."""
    ip = Interpreter(make_profile(profile_name, None, params or {}, ()), store=store)
    ip.lean = lean
    if budget is not None:
        ip.budget = StatementBudget(budget)
    out: list[str] = []
    alarm = None
    prog = store.loaded[1000] if store is not None else parse_program(text, "p.nc")
    try:
        for ev in ip.run(prog):
            out.append(repr(ev))
            if isinstance(ev, Busy):
                ip.budget.new_cycle()  # type: ignore[union-attr]  # as the channel does every cycle
    except NcAlarm as exc:
        alarm = repr(exc.alarm)
    st_ = ip.state
    state = (ip.position, ip.last_target, repr(st_), ip._executed, repr(ip.block), ip.program_name,
             ip.unit_locked, ip.variable(100), ip.variable(1), [repr(r) for r in ip.preview_log])
    return out, alarm, state


def _same(profile: str, text: str, budget: int | None = None) -> None:
    assert _run(profile, text, True, budget) == _run(profile, text, False, budget)


@settings(max_examples=60, deadline=None)
@given(text=programs(("X", "Y", "Z"), False), budget=st.sampled_from([None, None, 1, 3]))
def test_mill_programs_run_the_same_in_the_lean_lane(text: str, budget: int | None) -> None:
    _same("nc5-mill", text, budget)


@settings(max_examples=60, deadline=None)
@given(text=programs(("X", "Z"), True), budget=st.sampled_from([None, 2]),
       profile=st.sampled_from(["nc5-lathe-a", "nc5-lathe-b", "nc5-lathe-c", "lathe-2018"]))
def test_lathe_programs_run_the_same_in_the_lean_lane(text: str, budget: int | None, profile: str) -> None:
    _same(profile, text, budget)  # X in diameter, G99 feed per revolution; G90/G91 on types B and C


@pytest.mark.slow
@settings(max_examples=1500, deadline=None)
@given(case=st.one_of(programs(("X", "Y", "Z"), False).map(lambda t: ("nc5-mill", t)),
                      programs(("X", "Z"), True).map(lambda t: ("nc5-lathe-a", t))),
       budget=st.sampled_from([None, 1, 4]))
def test_many_programs_run_the_same_in_the_lean_lane(case: tuple[str, str], budget: int | None) -> None:
    _same(case[0], case[1], budget)


CAM = "G10 L2 P1 X0.1 Y-0.3\nG54 G90 G17 G01 F3000\nX1.5 Y2.25\nN7 X-.5 Z1.\ng0 x2. y0 z0\nG1 X3. F1200\nM30\n"


def test_a_cam_program_takes_the_lane_and_moves_where_it_says(monkeypatch) -> None:
    """The lane is taken (not silently skipped): no plain line reaches `_execute`; the moves end at the
    programmed points plus the G54 offset, at the programmed feeds."""
    executed: list[int] = []
    real = Interpreter._execute

    def counting(self, block):
        executed.append(block.line)
        return real(self, block)

    monkeypatch.setattr(Interpreter, "_execute", counting)
    moves = [ev for ev in Interpreter(make_profile("nc5-mill")).run(parse_program(CAM)) if isinstance(ev, Move)]
    assert executed == [1, 2, 7]  # G10, the modal block, M30
    assert [(m.kind, m.line, m.end, m.feed) for m in moves] == [
        ("line", 3, {"X": 1.6, "Y": 1.95, "Z": 0.0}, 3000.0),
        ("line", 4, {"X": -0.4, "Y": 1.95, "Z": 1.0}, 3000.0),
        ("rapid", 5, {"X": 2.1, "Y": -0.3, "Z": 0.0}, None),
        ("line", 6, {"X": 3.1, "Y": -0.3, "Z": 0.0}, 1200.0)]
    _same("nc5-mill", CAM)


def test_a_g01_code_call_is_not_taken_by_the_lane() -> None:
    """With G01 calling O9100 (N1.200 = 1), a G1 line runs the macro as block by block; a line
    without G still moves in the lane."""
    text = "O1000\nG90 G01 F500\nX1.\nG1 X2. Y3.\nX4.\nM30\nO9100\n#101 = #101 + #24\nM99\n"
    runs = []
    for lean in (True, False):
        store = ProgramStore()
        store.add_text(text, "p.nc")
        ip = Interpreter(make_profile("nc5-mill", None, {"N1.200": 1.0}, ()), store=store)
        ip.lean = lean
        events = [repr(ev) for ev in ip.run(store.loaded[1000])]
        runs.append((events, ip.variable(101), ip.position))
    assert runs[0] == runs[1]
    assert runs[0][1] is not None and runs[0][1] > 0  # the macro ran (G01 blocks called it)


def test_an_alarm_comes_at_the_same_block() -> None:
    """A target out of range and a cutting move without F: the general path raises them, at their line."""
    for text, code, line in (("G90 G01 F100\nX1.\nX3000000000.\nM30\n", 0x120E, 3),
                             ("G90 G00\nX1.\nG1 X2.\nM30\n", 0x1001, 3)):
        out, alarm, _ = _run("nc5-mill", text, True)
        assert alarm == _run("nc5-mill", text, False)[1]
        with pytest.raises(NcAlarm) as exc:
            list(Interpreter(make_profile("nc5-mill")).run(parse_program(text)))
        assert (exc.value.alarm.code, exc.value.alarm.line) == (code, line)


def test_a_line_without_a_point_is_in_microns() -> None:
    moves = [ev for ev in Interpreter(make_profile("nc5-mill")).run(parse_program("G90 G1 F100\nX1500 Y2.\nM30\n"))
             if isinstance(ev, Move)]
    assert moves[0].end == {"X": 1.5, "Y": 2.0, "Z": 0.0}


@pytest.mark.parametrize("profile,text", [
    ("nc5-mill", "G61 G90 G01 F800\nX1. Y2.\nG64\nX2.\nG95 F0.2\nX3.\nG94 F100\nx4.y5.z-1\nN12 G0 X0\nM30\n"),
    ("nc5-lathe-a", "G50 S2000\nG96 S120 M03\nG99 G01 F0.2\nX40. Z-1.\nZ-5.\nG97 S500\nX30.\nN3 G0 X50. Z5.\nM30\n"),
    ("nc5-mill", "G90 G01 F800\nN5 X1.\nN6\nG1 F300\nN8 G1 X2. F200\nM30\n"),
])
def test_modal_cases_run_the_same_in_the_lean_lane(profile: str, text: str) -> None:
    """G61 exact stop, G95 feed per revolution, G96 surface speed, N words, lower case, a line that
    moves nothing: each move and the last block as block by block."""
    lean, general = _run(profile, text, True), _run(profile, text, False)
    assert lean == general
    for stop in range(1, text.count("\n")):  # the state after each line (the last block read, its N)
        cut = "\n".join(text.split("\n")[:stop]) + "\n"
        assert _run(profile, cut, True) == _run(profile, cut, False)


@settings(max_examples=200, deadline=None)
@given(line=plain(("X", "Y", "Z")))
def test_the_block_of_a_lane_line_is_the_parsers_block(line: str) -> None:
    """`Interpreter.block` after a line the lane ran reads as the parser's block: words, N, text, equal
    and printed the same; a line the lane does not take (a repeated letter, F < 0) is the parser's."""
    assume(line.strip())  # a blank line is no block
    ip = Interpreter(make_profile("nc5-mill"))
    try:
        list(ip.run(parse_program(f"G90 G1 F100\n{line}\n")))
    except NcAlarm:  # F-5 and the like: the general path raised it
        assert not isinstance(ip.block, LineBlock)
    parsed = parse_block(2, line)
    if isinstance(ip.block, LineBlock):
        assert ip.block == parsed and parsed == ip.block and repr(ip.block) == repr(parsed)
        assert (ip.block.words, ip.block.n, ip.block.text) == (parsed.words, parsed.n, parsed.text)
    else:
        assert ip.block == parsed


def test_a_bench_run_traces_the_same_with_the_lane(tmp_path, monkeypatch) -> None:
    """`hil run` on the mill bench, lane on and off: every trace column the same, every cycle, and the
    axes end where the program's last line says (work offset G54 = 0)."""
    from pathlib import Path

    from hil import api

    lines = ["G90 G17 G94 G01 F3000"] + [f"X{0.05 * k:.4f} Y{(-1) ** k * 0.02 * k:.4f}" for k in range(1, 60)]
    lines += ["G0 Z2.", "N10 G1 X1. Y1. F1200", "M30"]
    prog = tmp_path / "cam.nc"
    prog.write_text("\n".join(lines) + "\n")
    bench = str(Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml")
    tables = []
    for lean in (True, False):
        monkeypatch.setattr(Interpreter, "lean", lean)
        trace = tmp_path / f"t{lean}.parquet"
        res = api.run(str(prog), bench, trace=str(trace))
        assert res.run.ok
        tables.append(api.load_trace(trace))
    assert tables[0].column_names == tables[1].column_names and tables[0].num_rows == tables[1].num_rows
    assert [c for c in tables[0].column_names if not tables[0][c].equals(tables[1][c])] == []
    ends = {a: tables[0][f"{a}_cmd"][-1].as_py() for a in "XYZ"}
    assert ends == pytest.approx({"X": 1.0, "Y": 1.0, "Z": 2.0}, abs=1e-6)


def test_a_lane_moves_points_are_its_own_when_the_position_is_changed_in_place() -> None:
    """A lane line's Move starts at the dict that was the interpreter's position (no copy, bench B167): what the
    channel (an M96 interrupt's stop) or the MLC writes into `Interpreter.position` in place after a move was read
    changes neither that move's start or end nor those before it, and the next move starts where it was written,
    as on the general path."""
    ip = Interpreter(make_profile("nc5-mill"))
    events = ip.run(parse_program("G90 G17 G94 G01 F3000\nX1. Y2.\nX3. Y4.\nX5. Y6.\nM30\n"), preview=False)
    first = next(events)
    second = next(events)
    assert type(first) is Move and type(second) is Move and type(ip.block) is LineBlock  # the lane ran them
    ip.position.update({"X": 2.5, "Y": 3.5})  # as nc/channel.py writes an interrupt's stop point
    third = next(events)
    assert (first.start, first.end) == ({"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 2.0, "Z": 0.0})
    assert (second.start, second.end) == ({"X": 1.0, "Y": 2.0, "Z": 0.0}, {"X": 3.0, "Y": 4.0, "Z": 0.0})
    assert (third.start, third.end) == ({"X": 2.5, "Y": 3.5, "Z": 0.0}, {"X": 5.0, "Y": 6.0, "Z": 0.0})
    assert ip.position == {"X": 5.0, "Y": 6.0, "Z": 0.0} and ip.position is not third.end
    third.start["X"] = -1.0  # a consumer's own change of a move's dict reaches no other move nor the interpreter
    assert second.end == {"X": 3.0, "Y": 4.0, "Z": 0.0} and ip.position["X"] == 5.0
