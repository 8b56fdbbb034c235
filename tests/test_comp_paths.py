"""Tool radius / nose radius compensation through `hil path --json`.

The check a machinist makes: sampled along the compensated path, the cutter centre (lathe: the
output minus the imaginary-tip vector) stays exactly one radius away from the programmed contour;
outer corners get an arc of that radius, inner corners are trimmed, interference raises 0x12xx.
"""

from __future__ import annotations

import math

import pytest

from cycles_helpers import distance_to, run, samples, seg_of
from nc.compensation.nose import tip_vector
from nc.cycles.geometry import Seg

MILL = """G17 G21 G90 G94
G10 L12 P1 R4.
G00 X-20. Y-20. Z5.
G01 Z-2. F500
G41 G01 X0. Y0. D1
Y40.
G02 X20. Y60. R20.
G01 X60.
Y0.
X0.
G40 G01 X-20. Y-20.
M30
"""
MILL_CONTOUR = [Seg((0.0, 0.0), (0.0, 40.0)), Seg((0.0, 40.0), (20.0, 60.0), (20.0, 40.0), True),
                Seg((20.0, 60.0), (60.0, 60.0)), Seg((60.0, 60.0), (60.0, 0.0)), Seg((60.0, 0.0), (0.0, 0.0))]


def body(moves):
    """Compensated moves between start-up and cancel."""
    comp = [m for m in moves if "comp" in m.get("tags", [])]
    return [m for m in comp[1:] if "cancel" not in m["tags"]]


def test_mill_outside_contour_keeps_radius(capsys, tmp_path):
    r = run(capsys, tmp_path, MILL, profile="nc5-mill")
    assert r.code == 0, r.alarm
    moves = body(r.moves)
    assert moves
    for m in moves:
        for p in samples(m, 24, ("X", "Y")):
            assert distance_to(MILL_CONTOUR, p) == pytest.approx(4.0, abs=1e-6), (m["line"], p)
    corners = [m for m in moves if "corner" in m["tags"]]
    assert len(corners) == 2  # the two convex 90° corners get an arc of the tool radius
    for m in corners:
        c = (m["center"]["X"], m["center"]["Y"])
        assert c in ((60.0, 60.0), (60.0, 0.0)) and seg_of(m, ("X", "Y")).radius == pytest.approx(4.0)
    # G41 on this clockwise walk puts the tool outside: X = −4 on the first side
    assert moves[0]["start"]["X"] == -4.0 and moves[0]["end"]["X"] == -4.0
    # the programmed (work) coordinates are untouched
    assert moves[0]["work"]["X"] == 0.0


def test_mill_pocket_inner_corners_trimmed(capsys, tmp_path):
    # G42 inside the same contour: start-up onto the middle of a wall, overlap it before G40
    # (type A start-up and cancel are normal to their blocks, decisions A53)
    prog = """G17 G21 G90 G94
G10 L12 P1 R4.
G00 X30. Y30. Z5.
G01 Z-2. F500
G42 G01 X0. Y20. D1
Y40.
G02 X20. Y60. R20.
G01 X60.
Y0.
X0.
Y30.
G40 G01 X30. Y30.
M30
"""
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    assert r.code == 0, r.alarm
    moves = body(r.moves)
    assert not [m for m in moves if "corner" in m["tags"]]
    for m in moves:
        for p in samples(m, 24, ("X", "Y")):
            assert distance_to(MILL_CONTOUR, p) == pytest.approx(4.0, abs=1e-6)
    # the inner corner at (60, 60) is the intersection of the two offset lines
    ends = [(m["end"]["X"], m["end"]["Y"]) for m in moves]
    assert (56.0, 56.0) in ends and (56.0, 4.0) in ends


def test_lookahead_over_z_moves(capsys, tmp_path):
    prog = MILL.replace("Y40.\n", "Y40.\nG01 Z-3.\nG04 P100\nZ-2.\n")
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    assert r.code == 0, r.alarm
    z = [m for m in r.moves if m["line"] in (7, 9)]
    # the Z moves between Y40. and the arc stay on the compensated corner point (X−4, Y40)
    assert all((m["end"]["X"], m["end"]["Y"]) == (-4.0, 40.0) for m in z)
    for m in body(r.moves):
        if m["kind"] != "dwell" and m["line"] not in (7, 9):
            for p in samples(m, 12, ("X", "Y")):
                assert distance_to(MILL_CONTOUR, p) == pytest.approx(4.0, abs=1e-6)


def test_interference_alarms(capsys, tmp_path):
    # a 2 mm step inside a 4 mm cutter: the compensated block would run backwards
    prog = MILL.replace("Y0.\nX0.", "Y0.\nX58.\nY2.\nX0.")
    r = run(capsys, tmp_path, prog.replace("G41", "G42"), profile="nc5-mill")
    assert r.code == 1 and r.alarm["code"] in ("0x120B", "0x1205", "0x1208")
    # an inner arc smaller than the cutter
    small = MILL.replace("G02 X20. Y60. R20.", "G02 X3. Y43. R3.").replace("G01 X60.", "G01 X3. Y60.\nX60.")
    r = run(capsys, tmp_path, small.replace("G41", "G42"), profile="nc5-mill")
    assert r.code == 1 and r.alarm["code"] == "0x120A"


def test_start_and_cancel_on_arc_alarm(capsys, tmp_path):
    r = run(capsys, tmp_path, MILL.replace("G41 G01 X0. Y0. D1", "G41 G02 X0. Y0. R20. D1"), profile="nc5-mill")
    assert r.code == 1 and r.alarm["code"] == "0x1201"
    r = run(capsys, tmp_path, MILL.replace("G40 G01 X-20. Y-20.", "G40 G03 X-20. Y-20. R30."), profile="nc5-mill")
    assert r.code == 1 and r.alarm["code"] == "0x1201"


LATHE = """G21 G99
G10 L10 P1 R0.6 Q{tip}
G10 L11 P1 R0.2
T0101
G00 X50. Z5.
G42 G00 X16. Z2.
G01 Z0. F0.1
X20. Z-2.
Z-15.
G02 X30. Z-20. R5.
G01 X36. Z-30.
Z-40.
X48.
G40 G00 X60. Z10.
M30
"""
LATHE_CONTOUR = [Seg((2.0, 8.0), (0.0, 8.0)), Seg((0.0, 8.0), (-2.0, 10.0)), Seg((-2.0, 10.0), (-15.0, 10.0)),
                 Seg((-15.0, 10.0), (-20.0, 15.0), (-15.0, 15.0), True), Seg((-20.0, 15.0), (-30.0, 18.0)),
                 Seg((-30.0, 18.0), (-40.0, 18.0)), Seg((-40.0, 18.0), (-40.0, 24.0))]


@pytest.mark.parametrize("tip", [3, 0, 8])
def test_lathe_nose_radius_keeps_radius_from_contour(capsys, tmp_path, tip):
    r = run(capsys, tmp_path, LATHE.format(tip=tip))
    assert r.code == 0, r.alarm
    moves = body(r.moves)
    assert moves and all(m.get("comp_radius") == pytest.approx(0.8) for m in moves)  # geometry 0.6 + wear 0.2
    tv = tip_vector(tip, 0.8)
    for m in moves[1:]:
        for z, x in samples(m, 24):
            centre = (z - tv[0], x - tv[1])
            assert distance_to(LATHE_CONTOUR, centre) == pytest.approx(0.8, abs=1e-6), (m["line"], tip)


def test_lathe_tip3_straight_portions_on_contour(capsys, tmp_path):
    """Tip 3 (OD turning tool): on Z-parallel lines the imaginary tip runs on the programmed X."""
    r = run(capsys, tmp_path, LATHE.format(tip=3))
    moves = body(r.moves)
    z_lines = [m for m in moves if m["kind"] == "line" and m["line"] in (9, 12)]
    assert [m["start"]["X"] for m in z_lines] == [10.0, 18.0]
    assert all(m["start"]["X"] == m["end"]["X"] for m in z_lines)
    cancel = [m for m in r.moves if "cancel" in m.get("tags", [])]
    assert len(cancel) == 1 and (cancel[0]["end"]["Z"], cancel[0]["end"]["X"]) == (10.0, 30.0)
    # the last element (X48. up the shoulder) ends offset normal to itself: centre Z−39.2 X24,
    # imaginary tip 3 at Z−40 X23.2
    assert (cancel[0]["start"]["Z"], cancel[0]["start"]["X"]) == pytest.approx((-40.0, 23.2), abs=1e-6)
