"""B121 (issue 17): the lean lane's lines run as code built per shape, with its plain state and work origin kept
until something may have changed them. Whatever a program does around its plain lines, the lane on and off give
the same Moves field by field, the same alarm at the same line and block, the same events in the same order and
the same state; through a channel (preview window, look-ahead, M96) the same setpoints bit for bit. The programs
below leave the lane on purpose: radius compensation, ,C/,R corners, G66, macros, offsets written by G10, G92,
G52 and # variables between plain lines, an M96 interrupt program that changes the modal state, a bad word."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.interp import Interpreter
from nc.interrupt import m96_link
from nc.moves import Move
from nc.motion.offline import run
from nc.profiles import make_profile
from nc.program.blocks import parse_program
from nc.store import ProgramStore
from tests.motion_helpers import mill_cfg
from tests.test_interp_lean import _run

AXES = ("X", "Y", "Z")


def _same(text: str, profile: str = "nc5-mill") -> tuple:
    """Both paths on `text` (its first program O1000 the main one when it holds several): equal, returned."""
    stores = []
    for _ in range(2):
        store = ProgramStore()
        store.add_text(text, "p.nc")
        stores.append(store if text.startswith("O1000") else None)
    lean, general = _run(profile, text, True, store=stores[0]), _run(profile, text, False, store=stores[1])
    assert lean == general
    return lean


# ---- CAM-like programs: the shapes a post-processor writes -----------------------------------------------

coord = st.floats(-400.0, 400.0, allow_nan=False).map(lambda v: f"{v:.4f}") | st.integers(-9999, 9999).map(str)


@st.composite
def cam_line(draw) -> str:
    """Only the axes that change (a subset, in order or not), sometimes G0/G1 or F, N, lower case, no spaces."""
    axes = draw(st.lists(st.sampled_from(AXES), min_size=0, max_size=3, unique=True))
    words = [a + draw(coord) for a in axes]
    if draw(st.integers(0, 5)) == 0:
        words.insert(0, draw(st.sampled_from(["G0", "G1", "G01", "G00"])))
    if draw(st.integers(0, 4)) == 0:
        words.insert(draw(st.integers(0, len(words))), "F" + draw(st.sampled_from(["1200", "3000.", "0", "250.5"])))
    if draw(st.integers(0, 6)) == 0:
        words.insert(0, f"N{draw(st.integers(1, 9999))}")
    line = draw(st.sampled_from([" ", "", "\t"])).join(words)
    return line.lower() if draw(st.integers(0, 12)) == 0 else line


@settings(max_examples=60, deadline=None)
@given(lines=st.lists(cam_line(), min_size=1, max_size=40), start=st.sampled_from(["G90 G17 G94 G01 F3000", "G90 G00",
                                                                                  "G90 G54 G1", "G90 G55 G1 F800"]))
def test_cam_programs_same_events_alarms_and_state(lines: list[str], start: str) -> None:
    _same("\n".join(["G10 L2 P1 X1.5 Y-2. Z0.25", "G10 L2 P2 X-10. Y3.", start] + lines + ["M30"]) + "\n")


# ---- programs that leave the lane, between runs of plain lines ---------------------------------------------

PLAIN = "X1.5 Y2.25\nX3. Y-1.\nZ-0.5\nX4.125 Y0.5 Z-0.25\nY7\n"  # `Y7`: no point, 0.007 mm (N8.018 Bit10 = 0)

LEAVING = {
    "offsets written between plain lines": "G90 G1 F2000\n" + PLAIN + "G10 L2 P1 X5. Y-3.\n" + PLAIN
    + "#22002 = -7.5\n#22080 = 1.25\n" + PLAIN + "G92 X0 Y0\n" + PLAIN + "G52 X2. Y2.\n" + PLAIN
    + "G55\n" + PLAIN + "G54\nG10 L10 P1 R3.\nG43 H1 Z5.\n" + PLAIN + "G49\n" + PLAIN + "M30\n",
    "radius compensation": "G90 G17 G1 F1000\nG10 L12 P1 R2.\n" + PLAIN + "G41 D1 X10. Y10.\nX20.\nY20.\nX10.\n"
    "G40 X0 Y0\n" + PLAIN + "G42 D1 X5. Y5.\nX15.\nG40 X0 Y0\n" + PLAIN + "M30\n",
    "corners ,C and ,R": "G90 G1 F1500\n" + PLAIN + "X10. Y10. ,C1.\nX20. Y10.\nX20. Y20. ,R2.\nX0 Y20.\n" + PLAIN
    + "M30\n",
    "modal macro G66 and a macro call": "O1000\nG90 G1 F1000\n" + PLAIN + "G66 P9010 A1.\nX5. Y5.\nX6.\nG67\n" + PLAIN
    + "G65 P9011 B2.\n" + PLAIN + "M30\n"
    "O9010\n#100 = #100 + #1\nG91 G1 Z0.1\nG90\nM99\n"
    "O9011\n#22002 = #2\nG1 X#2 Y#2\nM99\n",
    "incremental blocks": "G90 G1 F1000\n" + PLAIN + "G91\n" + PLAIN + "G90\n" + PLAIN
    + "M30\n",
    "a bad word mid-run": "G90 G1 F1000\n" + PLAIN + "G987 X1.\n" + PLAIN + "M30\n",
    "a target out of range mid-run": "G90 G1 F1000\n" + PLAIN + "X3000000000.\n" + PLAIN + "M30\n",
    "a cutting line without F": "G90 G0\n" + PLAIN + "G1 X2.\n" + PLAIN + "M30\n",
    "F0 then a cutting line": "G90 G1 F1000\n" + PLAIN + "F0\n" + PLAIN + "M30\n",
}


@pytest.mark.parametrize("name", sorted(LEAVING))
def test_programs_leaving_the_lane(name: str) -> None:
    events, alarm, state = _same(LEAVING[name])
    moves = [e for e in events if e.startswith("Move(")]
    if name.startswith(("a bad", "a target", "a cutting", "F0")):
        assert alarm is not None and moves  # raised at the offending block, the same on both paths
    else:
        assert alarm is None and moves


def test_the_alarm_names_the_line_and_block_on_both_paths() -> None:
    text = "G90 G1 F1000\n" + PLAIN + "G987 X1.\n" + PLAIN + "M30\n"
    for lean in (True, False):
        ip = Interpreter(make_profile("nc5-mill"))
        ip.lean = lean
        with pytest.raises(NcAlarm) as exc:
            list(ip.run(parse_program(text, "p.nc")))
        assert (exc.value.alarm.line, exc.value.alarm.block) == (7, "G987 X1.")


def test_an_offset_written_from_outside_between_two_moves_moves_the_next_line() -> None:
    """A system variable written while the interpreter stands between two plain lines (an MLC, a script) is
    seen by the next line: the lane finds its origin again after any system variable write."""
    text = "G90 G1 F1000\nX1. Y1.\nX2. Y2.\nX3. Y3.\nM30\n"
    ends = []
    for lean in (True, False):
        ip = Interpreter(make_profile("nc5-mill"))
        ip.lean = lean
        out = []
        for ev in ip.run(parse_program(text, "p.nc"), preview=False):
            if isinstance(ev, Move):
                out.append(dict(ev.end))
                if len(out) == 1:
                    ip.vars.set(22002, 10.0)  # G54 X (#22000 + 78 a + 2)
        ends.append(out)
    assert ends[0] == ends[1]
    assert ends[0][1]["X"] == 12.0 and ends[0][0]["X"] == 1.0


# ---- through a channel: the preview window, the look-ahead, M96 --------------------------------------------

def _setpoints(text: str, lean: bool, trigger: int | None = None) -> tuple:
    store = ProgramStore()
    prog = store.add_text(text)[0]
    ip = Interpreter(make_profile("nc5-mill"), store=store)
    ip.lean = lean

    def on_cycle(n, ch):
        if n == 0:
            ch.m96 = m96_link(ip)
        if n == trigger:
            ch.interrupt()

    s = run(ip.run(prog), mill_cfg(), {"X": 0.0, "Y": 0.0, "Z": 0.0}, on_cycle=on_cycle)
    return s.positions, s.lines, s.state, [repr(a) for a in s.alarms], [repr(r) for r in ip.preview_log]


def _cam(n: int) -> str:
    return "\n".join(f"X{0.05 * i:.4f} Y{5.0 * np.sin(i / 40.0):.4f}" for i in range(1, n + 1))


@pytest.mark.parametrize("trigger", [None, 150, 400])
def test_m96_interrupt_that_changes_the_modal_state_same_setpoints(trigger: int | None) -> None:
    """The interrupt program leaves G91 and G55 in force (N§3.11.4.6: its modal changes stay): the plain lines
    after it are read in the new state on both paths; statements mid-run are logged by the preview window at
    the same executing block."""
    text = ("G90 G17 G94 G01 F3000\nG10 L2 P2 X1. Y-1.\nM96 P50\n" + _cam(120) + "\n#100 = #5001\n" + _cam(60)
            + "\nM30\nO0050\nG55\nG91 G01 Z1. F2000\nZ-1.\nM99\n")
    a, b = _setpoints(text, True, trigger), _setpoints(text, False, trigger)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert a[2:] == b[2:]
    assert a[4]  # the statement was logged


def test_cam_program_with_statements_and_corners_same_setpoints() -> None:
    text = ("G90 G17 G94 G01 F3000\n" + _cam(80) + "\n#1 = 0.5\nG1 X10. Y10. ,C#1\nX12. Y8.\n" + _cam(40)
            + "\nG10 L2 P1 X0.5\n" + _cam(40) + "\nM30\n")
    a, b = _setpoints(text, True), _setpoints(text, False)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) and a[2:] == b[2:]


def test_a_shape_kept_for_all_interpreters_reads_each_profile_its_own_way() -> None:
    """The same line texts in one process through profiles that read them differently (mill, lathe X in
    diameter, the decimal-point rule N8.018 Bit10 on and off): a shape built for one is never another's."""
    text = "G90 G1 F500\nX1 Z2\nX1.5 Z-2\nx3 z.5\nX4. Z-1\nM30\n"
    ends = {}
    for profile, params in (("nc5-mill", {}), ("nc5-lathe-a", {}), ("nc5-mill", {"N8.018 Bit10": 1.0}),
                            ("nc5-lathe-a", {"N8.018 Bit10": 1.0}), ("nc5-mill", {})):
        lean, general = (_run(profile, text, on, params=params) for on in (True, False))
        assert lean == general
        ends.setdefault((profile, tuple(params.items())), lean[0])
    assert len({tuple(v) for v in ends.values()}) == 4  # four readings of the same text
