"""A lathe cycle interprets its P–Q contour on a twin of the interpreter (nc/interp/contour.py): what
the contour's blocks set stays on the twin. The twin shares the 70 work offsets of its interpreter
until either side writes one (issue 16: copying them was a third of each twin); these tests pin that a
write on either side never shows on the other."""

from __future__ import annotations

from cycles_helpers import run
from nc.interp.state import Frames

AXES = ("X", "Z")


def test_a_copy_and_its_frames_write_their_own_offsets() -> None:
    f = Frames(AXES)
    f.writable_offsets()[0]["Z"] = -1.0
    g = f.copy()
    assert g.work_offsets[0] == {"X": 0.0, "Z": -1.0}
    g.writable_offsets()[0]["Z"] = -5.0  # the twin's G10 L2 P1 Z-5.
    assert f.work_offsets[0]["Z"] == -1.0 and g.origins(0, AXES)["Z"] == -5.0
    f.writable_offsets()[5 + 3]["X"] = 2.0  # the interpreter's own G10 L20 P3 X4. (radius 2)
    assert g.work_offsets[5 + 3]["X"] == 0.0 and f.work_offsets[5 + 3]["X"] == 2.0
    assert f.origins(0, AXES) == {"X": 0.0, "Z": -1.0}


CONTOUR_G10 = """G21 G99
G00 X42. Z2.
G71 U1.5 R0.5
G71 P10 Q20 U0.4 W0.1 F0.25
N10 G00 X10.
G10 L2 P1 Z-5.
G01 Z-10. F0.1
X20. Z-20.
N20 X42.
G70 P10 Q20
G00 X50. Z10.
M30
"""


def test_a_g10_inside_the_contour_acts_on_the_cycles_alone(capsys, tmp_path) -> None:
    p = run(capsys, tmp_path, CONTOUR_G10)
    assert p.code == 0, p.alarm
    finish = [m for m in p.tagged("G70", "finish") if m["line"] == 7]
    # the G70 pass runs the contour's G10: work Z-10. is machine Z-15. there ...
    assert finish and finish[0]["end"]["Z"] == -15.0 and finish[0]["work"]["Z"] == -10.0
    rough = [m for m in p.tagged("G71", "profile") if m["line"] == 4]
    assert min(m["end"]["Z"] for m in rough) == -25.0 + 0.1  # X20. Z-20. at G54 Z-5, W0.1 allowance
    # ... while the program itself never ran it: its G54 is still zero after both cycles
    last = p.moves[-1]
    assert last["line"] == 11 and last["end"] == {"X": 25.0, "Z": 10.0} and last["work"] == {"X": 50.0, "Z": 10.0}


def test_the_programs_g10_between_the_cycles_reaches_the_g70_twin(capsys, tmp_path) -> None:
    text = CONTOUR_G10.replace("G10 L2 P1 Z-5.\n", "").replace("G70 P10 Q20\n", "G10 L2 P1 Z-2.\nG70 P10 Q20\n")
    p = run(capsys, tmp_path, text)
    assert p.code == 0, p.alarm
    rough = [m for m in p.tagged("G71", "profile") if m["block"] == "G71 P10 Q20 U0.4 W0.1 F0.25"]
    assert min(m["end"]["Z"] for m in rough) == -20.0 + 0.1  # G71 ran before the G10
    finish = [m for m in p.tagged("G70", "finish") if m["block"] == "G01 Z-10. F0.1"]
    assert finish[0]["end"]["Z"] == -12.0  # the G70 twin was made after it
    assert p.moves[-1]["end"]["Z"] == 8.0
