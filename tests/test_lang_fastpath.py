"""The parser's and interpreter's fast paths read a block exactly as the general paths do."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.program.blocks import _parse_general, parse_block

LETTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
number = st.one_of(
    st.integers(-10**13, 10**13).map(str),
    st.decimals(-10**7, 10**7, places=4, allow_nan=False, allow_infinity=False).map(str),
    st.sampled_from([".5", "-.25", "+3.", "1.", "0", "-0", "007", "+12", "1.2.3", "1 2", "- 4", "1e5"]),
)
word = st.tuples(st.sampled_from(list(LETTERS)), number).map(lambda t: t[0] + t[1])
sep = st.sampled_from(["", " ", "  ", "\t"])
block_text = st.lists(st.tuples(sep, word), min_size=1, max_size=6).map(
    lambda ws: "".join(s + w for s, w in ws)) | st.text(alphabet="GXYZNO0123456789.-+ #=[]();/%,", max_size=20)


def _outcome(parse, text):
    try:
        return parse(7, text)
    except NcAlarm as exc:
        return ("alarm", exc.alarm)


@settings(max_examples=600, deadline=None)
@given(block_text)
def test_plain_blocks_parse_as_the_general_parser_does(text):
    assert _outcome(parse_block, text) == _outcome(_parse_general, text)


@pytest.mark.parametrize("text", ["G01 X12.5 Y-3", "N10 G1 X.5", "x1y2", "N1 N2 X3", "X1 N5", "N-5 X1",
                                  "N1.5 X1", "O12 X1", "X1234567890123", "X-123456789.123", "G01X1.Y2."])
def test_examples_parse_as_the_general_parser_does(text):
    assert _outcome(parse_block, text) == _outcome(_parse_general, text)


# ---- interpreter: blocks of plain axis words skip straight to the motion step ---------------------
from nc.interp import Interpreter  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402

MILL_MODAL = ["G90", "G91", "G00", "G01 F1200", "G02 R20. F300", "G03 I5. J0 F300", "G17", "G18", "G19",
              "G20", "G21", "G55", "G54 P2", "G52 X5. Y-2.", "G92 X0 Y0", "G81 Z-1. R1. F100", "G80",
              "G41 D1", "G40", "G68 X0 Y0 R30.", "G69", "G51 X0 Y0 P2000", "G50", "G51.1 X0", "G50.1 X0",
              "G16", "G15", "G61", "G64", "G09 X1.", "G94", "G95 F0.1", "M03 S1000", "#1=2.5", "#1=#0",
              "G01 X1. ,C0.3", "G01 X3. ,R0.2", "G01 ,A30.", "G43 H1", "G49", "M98 P9", "F0", "G04 X1."]
LATHE_MODAL = ["G00", "G01 F0.2", "G02 R20. F0.1", "G03 R15.", "G98", "G99", "G96 S100", "G97 S500",
               "G18", "G54", "G55", "G50 X0 Z0", "G90 X10. Z-5. F0.1", "G80", "G01 X10. ,C0.5",
               "G41", "G40", "T0101", "U1.", "W-1.", "M03 S800", "#1=1.5", "G09 Z1.", "G04 X1."]
coord = st.one_of(st.integers(-20000, 20000).map(str),
                  st.decimals(-50, 50, places=3, allow_nan=False, allow_infinity=False).map(lambda d: f"{d:.3f}"),
                  st.just("#1"))


def _axis_block(axes):
    return st.lists(st.tuples(st.sampled_from(axes), coord), min_size=1, max_size=len(axes)).map(
        lambda ws: " ".join(a + v for a, v in ws))


def _events(profile, text, fast: bool):
    with pytest.MonkeyPatch.context() as m:
        m.setattr(Interpreter, "lean", False)  # the `_axis_block` path, not the lane before it (nc.interp.lean)
        if not fast:
            m.setattr(Interpreter, "_axis_block", lambda self, block: False)
        interp = Interpreter(profile)
        out = []
        try:
            for ev in interp.run(parse_program(text)):
                out.append(ev)
        except NcAlarm as exc:
            out.append(("alarm", exc.alarm))
        return out, interp.position, interp.state, [(r.line, r.ahead_of_line) for r in interp.preview_log]


def _program(modal, axes):
    block = st.one_of(st.sampled_from(modal), _axis_block(axes), _axis_block(axes), _axis_block(axes))
    return st.lists(block, min_size=1, max_size=14).map(lambda bs: "\n".join(bs) + "\nM30\n")


@settings(max_examples=150, deadline=None)
@given(text=_program(MILL_MODAL, ["X", "Y", "Z"]))
def test_mill_axis_blocks_fast_path_gives_the_general_paths_events(text):
    prof = make_profile("nc5-mill")
    assert _events(prof, text, True) == _events(prof, text, False)


@settings(max_examples=150, deadline=None)
@given(text=_program(LATHE_MODAL, ["X", "Z"]))
def test_lathe_axis_blocks_fast_path_gives_the_general_paths_events(text):
    prof = make_profile("nc5-lathe-b")
    assert _events(prof, text, True) == _events(prof, text, False)


def test_cam_block_takes_the_fast_path_and_makes_the_same_move():
    text = "G90 G17 G94 G01 F3000\nX0.0512 Y0.0013\nX.1 Y-.2 Z1\nM30\n"
    fast, _, _, _ = _events(make_profile("nc5-mill"), text, True)
    slow, _, _, _ = _events(make_profile("nc5-mill"), text, False)
    assert fast == slow
    moves = [e for e in fast if type(e).__name__ == "Move"]
    assert [m.end for m in moves] == [{"X": 0.0512, "Y": 0.0013, "Z": 0.0}, {"X": 0.1, "Y": -0.2, "Z": 0.001}]
    assert Interpreter(make_profile("nc5-mill"))._axis_block(parse_program(text).blocks[1])
