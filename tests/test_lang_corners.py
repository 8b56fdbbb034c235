"""`,C` / `,R` next to arcs (A32: the lathe manual allows G01–G03): exact corner points through
`hil path --json`."""

from __future__ import annotations

import math

import pytest

from lang_helpers import run_path


def close(a, b, tol=1e-4):
    return all(abs(x - y) < tol for x, y in zip(a, b))


def test_fillet_line_then_arc_mill(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X0 Y0\nG01 X10. F100 ,R2.\nG02 X20. Y0 R5.\nM30\n")
    assert r.code == 0, r.alarm
    kinds = [m["kind"] for m in r.moves]
    assert kinds == ["rapid", "line", "arc", "arc"]
    s = math.sqrt(45.0)  # fillet centre 7 from the arc centre (15,0), 2 above the line
    assert close(r.ends("X", "Y")[1], (15 - s, 0.0))
    fillet = r.moves[2]
    assert fillet["dir"] == "ccw" and fillet["tags"] == [",R"]
    assert close((fillet["center"]["X"], fillet["center"]["Y"]), (15 - s, 2.0))
    assert close(r.ends("X", "Y")[2], (15 - 5 * s / 7, 10 / 7))
    assert r.moves[3]["start"]["X"] == r.moves[2]["end"]["X"]  # the arc starts on the fillet
    assert r.moves[3]["center"] == {"X": 15.0, "Y": 0.0, "Z": 0.0} and r.ends("X", "Y")[3] == (20.0, 0.0)


def test_chamfer_arc_then_line_and_tangent_join(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X10. Y0\nG02 X20. Y0 R5. F100 ,C2.\nG01 Y-10. ,R1.\n"
                                   "G03 X30. Y-20. R10.\nM30\n")
    assert r.code == 0, r.alarm
    e = r.ends("X", "Y")
    # chamfer point on the arc 2 mm (straight) from the corner (20,0), and 2 mm down the line
    assert close(e[1], (19.6, math.sqrt(4 - 0.16)))
    assert r.moves[2]["tags"] == [",C"] and close(e[2], (20.0, -2.0))
    # line into a tangent arc: ,R has nothing to round, the path is unchanged
    assert e[3] == (20.0, -10.0) and r.moves[4]["kind"] == "arc" and e[4] == (30.0, -20.0)


def test_fillet_arc_to_arc(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X20. Y-10.\nG03 X30. Y-20. R10. F100 ,R3.\n"
                                   "G02 X40. Y-10. R10.\nM30\n")
    assert r.code == 0, r.alarm
    fil = r.moves[2]
    c = (fil["center"]["X"], fil["center"]["Y"])
    assert math.isclose(math.dist(c, (30.0, -10.0)), 7.0, abs_tol=1e-6)  # inside the first arc
    assert math.isclose(math.dist(c, (40.0, -20.0)), 13.0, abs_tol=1e-6)  # outside the second
    assert fil["dir"] == "ccw"
    for pt, centre in ((r.ends("X", "Y")[1], (30.0, -10.0)), (r.ends("X", "Y")[2], (40.0, -20.0))):
        assert math.isclose(math.dist(pt, centre), 10.0, abs_tol=1e-6)
        assert math.isclose(math.dist(pt, c), 3.0, abs_tol=1e-6)


def test_lathe_chamfer_and_fillet_next_to_arcs(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G98 G00 X20. Z0\nG01 Z-10. F100 ,C1.\nG02 X40. Z-20. R10.\n"
                                   "G01 Z-30. ,R2.\nG03 X60. Z-40. R10.\nM30\n", profile="nc5-lathe-a")
    assert r.code == 0, r.alarm
    e = r.ends("X", "Z")  # X as programmed: diameter
    assert close(e[1], (20.0, -9.0))
    assert close(e[2], (20.1, -10.0 - math.sqrt(1 - 0.05 ** 2)))
    q = math.sqrt(140.0)  # fillet centre at radius 22, 12 from the arc centre (X r20, Z-40)
    assert close(e[4], (40.0, -40.0 + q))
    assert r.moves[5]["center"]["X"] == 22.0 and close((r.moves[5]["center"]["Z"],), (-40.0 + q,))
    assert close(e[5], (2 * (20 + 10 * 2 / 12), -40.0 + 10 * q / 12))
    assert e[6] == (60.0, -40.0)


@pytest.mark.parametrize("text,code", [
    ("G17 G90 G94 G00 X0 Y0\nG01 X10. F100 ,R30.\nG02 X20. Y0 R5.\nM30\n", "0x0207"),
    ("G17 G90 G94 G00 X0 Y0\nG01 X10. F100 ,C3.\nG02 X20. Y0 Z5. R5.\nM30\n", "0x021D"),
])
def test_corner_next_to_arc_alarms(capsys, tmp_path, text, code):
    r = run_path(capsys, tmp_path, text)
    assert r.code == 1 and r.alarm["code"] == code and r.alarm["line"] == 2


def test_two_block_linear_angle_lathe(capsys, tmp_path):
    """L l.2449 pattern 2: `,A1` alone, then `X Z ,A2`; angles from +Z, CCW, in ZX (A32)."""
    r = run_path(capsys, tmp_path, "G98 G00 X20. Z0\nG01 F100 ,A180.\nX60. Z-30. ,A135.\nZ-40.\nM30\n",
                 profile="nc5-lathe-a")
    assert r.code == 0, r.alarm
    assert r.ends("X", "Z") == [(20.0, 0.0), (20.0, -10.0), (60.0, -30.0), (60.0, -40.0)]
    assert r.moves[1]["line"] == 2 and r.moves[2]["line"] == 3


def test_two_block_linear_angle_mill_and_alarms(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X0 Y0\nG01 F100 ,A30.\nX20. Y0 ,A-30.\nM30\n")
    assert r.code == 0, r.alarm
    assert close(r.ends("X", "Y")[1], (10.0, 10.0 * math.tan(math.radians(30.0))))
    assert r.ends("X", "Y")[2] == (20.0, 0.0)
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X0 Y0\nG01 F100 ,A30.\nX20. Y0 ,A30.\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x0207"
    r = run_path(capsys, tmp_path, "G17 G90 G94 G00 X0 Y0\nG01 F100 ,A30.\nX20. Y5.\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x0207" and r.alarm["line"] == 2
