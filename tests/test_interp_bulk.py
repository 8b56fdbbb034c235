"""The bulk lane (nc.interp.bulk, issue 16) prints what the block-by-block interpreter prints, line
for line, and leaves the same state behind: random programs mixing runs of plain G0/G1 blocks with
blocks the lane must not take (G91, G54 with offsets, G10, comments, N numbers, macro statements and
expressions, arcs, ,C chamfers, F changes, blocks that raise alarms), on a mill and a lathe profile.
The run lengths are lowered so that short programs cross many batch boundaries. The default suite
runs a few dozen programs; `-m slow` runs 1,500."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hil.commands.path import _human, batch_text
from hil.path_json import _coord, _num, batch_json, fmt, move_json
from nc.alarms import NcAlarm
from nc.interp import Interpreter, bulk
from nc.moves import Move, MoveBatch
from nc.profiles import make_profile
from nc.program.blocks import parse_program

coord = st.one_of(st.integers(-99999, 99999).map(lambda v: f"{v / 1000:.3f}"),
                  st.integers(-5000, 5000).map(str),  # no point: µm (N8.018 Bit10 = 0)
                  st.sampled_from(["0", "-0.", ".5", "-.25", "1.", "0.0001", "12345.6789", "2000000000."]))
feed = st.sampled_from(["F1200", "F600.", "F0", "F-5", "F1.5", ""])
gword = st.sampled_from(["G1", "G01", "G0", "G00", "g1", "", "", "G001"])


@st.composite
def plain(draw, axes: tuple[str, ...]) -> str:
    words = [draw(gword)]
    for a in draw(st.lists(st.sampled_from(axes), min_size=0, max_size=len(axes), unique=True)):
        words.append(a + draw(coord))
    words.append(draw(feed))
    if draw(st.booleans()):
        words.insert(0, f"N{draw(st.integers(1, 99))}")
    line = draw(st.sampled_from([" ", "  ", "\t", ""])).join(w for w in words if w)
    return draw(st.sampled_from(["", " "])) + (line.lower() if draw(st.integers(0, 9)) == 0 else line)


def other(axes: tuple[str, ...]) -> st.SearchStrategy[str]:
    a, b = axes[0], axes[-1]
    return st.sampled_from([
        "G91", "G90", "G90", "G54", "G55", "G10 L2 P2 " + a + "1.25 " + b + "-0.3", "G10 L2 P1 " + a + "0.1",
        "(a comment) G1 " + a + "1.", "G1 " + a + "2. (why)", "#1 = #1 + 0.5", "G1 " + a + "#1 F800",
        "G2 " + a + "3. " + b + "3. R5.", "G1 " + a + "4. ,C0.5", "G1 " + b + "-1.", "G04 P100", "M3 S500",
        "M5", "G61", "G64", "G1 " + a + "1. " + a + "2.", "G0 G1 " + a + "1.", "F-1", "G1 " + a + "3000000000.",
        "G98", "G99", "G94", "G95", "N5 G1 " + a + "7.5 F300", "/G1 " + a + "9.",
    ])


@st.composite
def programs(draw, axes: tuple[str, ...]) -> str:
    lines = ["O1000", draw(st.sampled_from(["", "G10 L2 P1 " + " ".join(f"{a}{0.1 * (i + 1) - 0.25:.2f}"
                                                                       for i, a in enumerate(axes))]))]
    for _ in range(draw(st.integers(1, 6))):
        lines += draw(st.lists(plain(axes), min_size=0, max_size=12))
        lines += draw(st.lists(other(axes), min_size=0, max_size=3))
    lines.append("M30")
    return "\n".join(lines) + "\n"


def _listing(profile_name: str, text: str, lane: bool, json: bool) -> tuple[list[str], object, dict]:
    """What `hil path` prints for the moves, the alarm (code, line) if any, and the state left."""
    profile = make_profile(profile_name, None, {}, ())
    ip = Interpreter(profile)
    ip.bulk = lane
    ip.lean = lane  # the reference runs every block through the general path (not nc.interp.lean either)
    out: list[str] = []
    alarm = None
    try:
        for ev in ip.run(parse_program(text, "p.nc")):
            if type(ev) is MoveBatch:
                chunk = batch_json(ev) if json else batch_text(ev)
                out += chunk.split("\n") if chunk else []
            elif isinstance(ev, Move):
                out.append(move_json(ev) if json else _human(ev, profile.diameter_axes))
    except NcAlarm as exc:
        alarm = (exc.alarm.code, exc.alarm.line, exc.alarm.block)
    st_ = ip.state
    state = dict(position=ip.position, last_target=ip.last_target, feed=st_.feed, motion=st_.motion,
                 groups=dict(st_.groups), executed=ip._executed, block=ip.block.line if ip.block else None,
                 var1=ip.variable(1), unit_locked=ip.unit_locked)
    return out, alarm, state


@pytest.fixture
def small_runs(monkeypatch):  # the same for every example: one fixture for all of them is what is meant
    monkeypatch.setattr(bulk, "MIN_RUN", 1)
    monkeypatch.setattr(bulk, "MAX_RUN", 5)


def _same(profile: str, text: str, json: bool = True) -> None:
    general = _listing(profile, text, False, json)
    lane = _listing(profile, text, True, json)
    assert lane == general


FAST = dict(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@settings(max_examples=25, **FAST)
@given(text=programs(("X", "Y", "Z")), json=st.booleans())
def test_mill_programs_print_the_same_either_lane(small_runs, text: str, json: bool) -> None:
    _same("nc5-mill", text, json)


@settings(max_examples=20, **FAST)
@given(text=programs(("X", "Z")), json=st.booleans())
def test_lathe_programs_print_the_same_either_lane(small_runs, text: str, json: bool) -> None:
    _same("nc5-lathe-a", text, json)  # X in diameter, G99 feed per revolution


@pytest.mark.slow
@settings(max_examples=1500, **FAST)
@given(text=st.one_of(programs(("X", "Y", "Z")).map(lambda t: ("nc5-mill", t)),
                      programs(("X", "Z")).map(lambda t: ("nc5-lathe-a", t))), json=st.booleans())
def test_many_programs_print_the_same_either_lane(small_runs, text: tuple[str, str], json: bool) -> None:
    """The same on many more programs (`-m slow`, a few minutes)."""
    _same(text[0], text[1], json)


def test_a_cam_run_goes_through_in_batches(small_runs) -> None:
    """The lane is taken (not silently skipped): a CAM run comes as batches, with a work offset."""
    text = "G10 L2 P1 X0.1 Y-0.3 Z0.7\nG54 G90\n" + "".join(
        f"G1 X{10 * math.cos(i / 7):.3f} Y{10 * math.sin(i / 7):.3f} F{1000 + i}\n" for i in range(40)) + "M30\n"
    profile = make_profile("nc5-mill", None, {}, ())
    ip = Interpreter(profile)
    ip.bulk = True
    events = list(ip.run(parse_program(text)))
    assert sum(len(e) for e in events if type(e) is MoveBatch) == 40
    _same("nc5-mill", text)


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.floats(-2e7, 2e7), st.integers(-10**8, 10**8).map(lambda v: v / 1000),
                 st.sampled_from([0.0, -0.0, 1e-5, -4.99999e-8, 9999999.9999999, 1e7, -1e7, 123.45678905])))
def test_bulk_number_is_the_general_number(v: float) -> None:
    assert _coord(v) == _num(fmt(v))


@pytest.mark.parametrize("text", [
    "O1000\n\ng1 f1200\nG1 X4. ,C0.5\ng1 f1200\nM30\n",  # hypothesis found these: a run that moves nothing
    "O1000\n\ng1 f1200\ng1 f1200\nG1 X4. ,C0.5\ng1 f1200\ng1 x0.000 f1200\ng1 f1200\nM30\n",  # after ,C
])
def test_a_run_without_moves_after_a_corner_block_is_as_block_by_block(small_runs, text: str) -> None:
    _same("nc5-lathe-a", text, False)


def test_a_long_run_of_blocks_without_moves_writes_no_line(tmp_path, capsys) -> None:
    """`hil path --json`: 100 `G1 F1200` lines (one bulk run that moves nothing) print nothing, not an
    empty line; after a ,C block they leave the corner without its motion block (0x0207), as
    block by block, not an internal error."""
    from hil.cli import main

    still = "G1 F1200\n" * 100
    p = tmp_path / "still.nc"
    p.write_text("O1000\nG1 X1 F1200\n#1=1\n" + still + "M30\n")
    assert main(["path", "--json", str(p)]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and '"line": 2' in out
    p.write_text("O1000\nG1 F1200\nG1 X4. ,C0.5\n" + still + "M30\n")
    assert main(["path", "--json", str(p)]) == 1
    alarm = capsys.readouterr().out.strip().splitlines()[-1]
    assert '"code": "0x0207"' in alarm and '"line": 3' in alarm
