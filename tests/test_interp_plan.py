"""A block runs only the steps of EXECUTION_ORDER that can act on it (nc.interp.execute.plan, issue
16): the plan leaves out a step only where the step's body finds nothing to do. Random programs of
blocks mixing G, M, F, S, T, D words, expressions, G96/G97, G65/G66 calls, G04/G10/G53, loops and
vacant variables give the same events, the same alarm and the same state with the plan as with
every step run for every block; so does a block the motion step skips as having nothing to move
(`_still`: M99, M05, T0101 …)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.interp import Interpreter, execute
from nc.profiles import make_profile
from nc.program.blocks import parse_program
from nc.store import ProgramStore

COMMON = ["G0", "G1", "G01", "G2 R5.", "G04 P100", "G96", "G97", "G40", "G54", "G55", "G53", "G61", "G64",
          "G80", "G10 L2 P1", "G67", "M3", "M4", "M5", "M8", "M9", "M0", "M19", "M3 M8", "S500", "S#5", "T0101",
          "T2", "D1", "F100", "F#4", "F0", "F-1", "X1.", "X#1", "Z-2.", "Z[#2 + 1]", "X#9", "N10", "B1.",
          "G03 I1. K0", "G1 X2. ,A30", "G1 ,A45", "G81 Z-1. R1.", "I2.",
          "G65 P9100 A1.", "G66 P9100"]
WORDS = {"nc5-mill": COMMON + ["G17", "G18", "G90", "G91", "G94", "G95", "Y3.", "G43 H1", "G49", "G16", "G15",
                                "G2.4 X1. Y1.", "J1."],
         "nc5-lathe-a": COMMON + ["G18", "G98", "G99", "G50 S2000", "U1.", "W-1.", "G71 U1. R0.5"]}


@st.composite
def programs(draw, name: str) -> str:
    lines = ["O1000", "#1 = 2.5", "#2 = -1", "#4 = 300", "#5 = 800", "F100"]
    body = [" ".join(draw(st.lists(st.sampled_from(WORDS[name]), min_size=1, max_size=3)))
            for _ in range(draw(st.integers(1, 12)))]
    if draw(st.booleans()):  # a loop runs the body again: plans remembered from the first pass
        body = ["#20 = 0", "WHILE [#20 LT 2] DO1", *body, "#20 = #20 + 1", "END1"]
    return "\n".join(lines + body + ["M30"]) + "\n"


MACRO = "O9100\nG1 X#1 F200\nM99\n"  # what G65 / G66 P9100 call


def _run(text: str, profile, everything: bool) -> tuple:
    plan, still = execute.plan, execute._still
    if everything:  # every step for every block, and the motion step never skipped as having nothing to do
        execute.plan = lambda shape: execute.ALL_STEPS
        execute._still = lambda ip, run: False
    try:
        store = ProgramStore()
        store.loaded[9100] = parse_program(MACRO, "O9100")
        ip = Interpreter(profile, store=store)
        events, alarm = [], None
        try:
            for ev in ip.run(parse_program(text, "P.nc")):
                events.append(repr(ev))
        except NcAlarm as exc:
            alarm = (exc.alarm.code, exc.alarm.line, exc.alarm.message)
        return events, alarm, repr(ip.state), repr(ip.position), ip.macro_modal
    finally:
        execute.plan, execute._still = plan, still


@pytest.mark.parametrize("name", sorted(WORDS))
@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_the_plan_runs_what_every_step_would(name, data) -> None:
    text = data.draw(programs(name))
    profile = make_profile(name, None, {}, ())
    assert _run(text, profile, False) == _run(text, profile, True)


def test_a_plain_motion_block_runs_three_steps_and_a_spindle_block_four() -> None:
    shape = execute.Shape(frozenset("GXZF"), frozenset({"G01"}), frozenset({1}))
    assert execute.plan(shape) == (execute.step_modal, execute.step_feed_d, execute.step_motion,
                                   execute.step_g66_call)
    shape = execute.Shape(frozenset("GS"), frozenset({"G96"}), frozenset({17}))
    assert execute.step_spindle in execute.plan(shape)
