"""Stretches under G96 and feed per revolution (decision bench B103, issue 17): a lathe program turned at a
constant surface speed with the feed per revolution runs most of its cycles in stretches, and every trace column
(MLC devices included), the alarms, handshakes, end record and final positions are those of cycle-by-cycle
stepping (DELTAHIL_STRETCH=0), also where the spindle's speed changes inside what would have been a stretch."""

from __future__ import annotations

import pytest

from benchmarks.trace_ab import compare
from tests.conftest import ROOT
from tests.test_stretch_runner import _both, _states

PART = str(ROOT / "examples" / "lathe_part_g71_g70_g76.nc")

# G96 + G99 on short moves: Z at one diameter (the rpm stands still), X facing (it changes every cycle), a
# taper, an arc, a rapid; then G97 + G99 with an override change and a thread between rapids
TURN = """G21 G18 G99
G50 S2000
T0101
G96 S150 M03
G00 X40. Z2.
G01 Z-12. F0.2
X44.
G00 Z2.
X36.
G01 Z-8. F0.15
X30. Z-14.
G02 X40. Z-19. R5.
G01 X46.
G00 X50. Z5.
G97 S900
G01 Z-10. F0.1
X48. Z-14.
G00 X60. Z5.
G00 X30. Z3.
G92 X29.2 Z-15. F1.5
X28.6
G00 X60. Z20.
M05
M30
"""


@pytest.fixture
def turn(tmp_path):
    p = tmp_path / "turn.nc"
    p.write_text(TURN)
    return str(p)


@pytest.mark.slow  # ≈ 10–26 s each: CI stays under 20 min (run with -m slow; session 30)
def test_the_part_program_in_stretches_equals_stepping(monkeypatch, tmp_path):
    a, b, r = _both(monkeypatch, tmp_path, PART)
    assert compare(a, b) == []
    assert r.run.ok
    # G71/G70 under G96 with G99 and the G76 passes' rapids: before B103 none of its 90,092 cycles went in
    # stretches; what is left stepped is X moving under G96 (the rpm changes every cycle) and the thread passes
    assert r.run.stretched > 0.65 * r.run.cycles


@pytest.mark.parametrize("events", [
    [],
    ["t=1.2:set D21026=80", "t=1.9:set D21026=100"],  # spindle override inside a G96/G99 cut: the feed re-plans
    pytest.param(["t=1.5:feed-hold", "t=1.8:cycle-start", "t=2.4:set D21002=60"],  # hold, resume, feed override
                 marks=pytest.mark.slow),
    ["Z<-6:set D21026=120", "line=16:set D21026=90"],  # by position and line (G97 S900, feed per revolution)
])
def test_g96_and_feed_per_revolution_stretched_equal_stepped(monkeypatch, tmp_path, turn, events):
    a, b, r = _both(monkeypatch, tmp_path, turn, events=events)
    assert compare(a, b) == []
    assert r.run.stretched > 0.3 * r.run.cycles
    if events:
        assert [c for c in b[0]["event"] if c]


@pytest.mark.slow  # ≈ 10–26 s each: CI stays under 20 min (run with -m slow; session 30)
def test_the_machine_after_a_g96_stretch_is_the_stepped_one(monkeypatch, turn):
    """What a stretch ends in (MLC memory, scan counts, clocks, settle count, setpoints) is what stepping reaches
    at the same cycle, with a G96 speed and a feed per revolution running."""
    stepped, a = _states(monkeypatch, "0", turn)
    stretched, b = _states(monkeypatch, "1", turn)
    assert b.run.stretched > 0.3 * b.run.cycles
    for cycle, state in stretched.items():
        assert state == stepped[cycle], cycle
    assert (a.run.cycles, a.run.final, a.run.max_ferr) == (b.run.cycles, b.run.final, b.run.max_ferr)


# G32 with its chamfer pull-out (one chain of two blocks), G76's fifteen passes (its returns and infeeds between)
THREADS = """G21 G18 G99
T0303
G97 S700 M03
G00 X30. Z5.
G32 Z-20. F1.5
G32 X34. Z-21.5 F1.5
G00 X40.
Z5.
G00 X28. Z5.
G76 P021060 Q50 R0.05
G76 X25.6 Z-18. P1200 Q300 F1.5
G00 X60. Z20.
M05
M30
"""


@pytest.mark.parametrize("events", [
    [],
    ["t=4.0:reset"],  # inside the first G76 pass: the chain brakes on along the thread (motion 63)
    ["t=13.5:estop"],  # inside a pass: the drives brake on their own ramps
    pytest.param(["t=1.2:set D21026=80", "t=5.6:feed-hold", "t=6.0:cycle-start"],  # override and hold inside threads
                 marks=pytest.mark.slow),
    pytest.param(["t=0.95:set D21026=120", "Z<-10:feed-hold", "t=9:cycle-start"], marks=pytest.mark.slow),
])
def test_thread_chains_in_stretches_equal_stepping(monkeypatch, tmp_path, events):
    """B104: a spindle-locked chain's cycles go in stretches, its setpoints stepped on the spindle feedback worked
    out first; the trace is stepping's, column by column, with a reset, an E-stop, overrides and holds."""
    p = tmp_path / "threads.nc"
    p.write_text(THREADS)
    a, b, r = _both(monkeypatch, tmp_path, str(p), events=events)
    assert compare(a, b) == []
    assert r.run.stretched > 0.75 * r.run.cycles  # before B103/B104: none (every pass and return stepped)


@pytest.mark.slow  # ≈ 10–26 s each: CI stays under 20 min (run with -m slow; session 30)
def test_the_machine_after_a_thread_stretch_is_the_stepped_one(monkeypatch, tmp_path):
    p = tmp_path / "threads.nc"
    p.write_text(THREADS)
    stepped, a = _states(monkeypatch, "0", str(p))
    stretched, b = _states(monkeypatch, "1", str(p))
    assert b.run.stretched > 0.75 * b.run.cycles
    for cycle, state in stretched.items():
        assert state == stepped[cycle], cycle
    assert (a.run.cycles, a.run.final, a.run.max_ferr) == (b.run.cycles, b.run.final, b.run.max_ferr)


@pytest.mark.parametrize("program", [TURN, THREADS])
def test_the_basic_mlc_stretches_them_as_stepping_does(monkeypatch, tmp_path, program):
    """With the basic MLC (every M/S/T finished at once; its stretches may run the NC's steps inside them, B27):
    G96, feed per revolution and thread chains give stepping's trace too."""
    p = tmp_path / "prog.nc"
    p.write_text(program)
    a, b, r = _both(monkeypatch, tmp_path, str(p), mlc="basic")
    assert compare(a, b) == []
    assert r.run.stretched > 0.5 * r.run.cycles
