"""G71 / G72 / G73 / G70 through `hil path --json`: the geometry a machinist checks.

Every roughing move stays outside the finished contour + allowance, every layer is at most the
programmed depth, the profile pass and G70 lie on the contour, the cycle ends at its start point.
"""

from __future__ import annotations

import math

from cycles_helpers import assert_outside, contour_x, distance_to, polyline, run, samples, seg_of, zx
from nc.cycles.geometry import Seg

TYPE_I = """G21 G99
G00 X42. Z2.
G71 U1.5 R0.5
G71 P10 Q20 U0.4 W0.1 F0.25
N10 G00 X10.
G01 Z-10. F0.1
X20. Z-20.
Z-30.
X30. ,C1.
Z-40.
N20 X42.
G70 P10 Q20
M30
"""
# the finished contour in machine coordinates (Z, X radius), from the P block's end point
TYPE_I_PTS = [(2.0, 5.0), (-10.0, 5.0), (-20.0, 10.0), (-30.0, 10.0), (-30.0, 14.0), (-31.0, 15.0), (-40.0, 15.0),
              (-40.0, 21.0)]  # ,C1. at the shoulder

TYPE_II = """G21 G99
G00 X42. Z1.
G71 U2. R0.5
G71 P10 Q20 U0.4 W0.1 F0.25
N10 G00 X30. Z0.
G01 Z-10. F0.1
X20. Z-20.
Z-25.
X30. Z-35.
Z-45.
N20 X42.
M30
"""
TYPE_II_PTS = [(0.0, 15.0), (-10.0, 15.0), (-20.0, 10.0), (-25.0, 10.0), (-35.0, 15.0), (-45.0, 15.0), (-45.0, 21.0)]


def shifted(pts, dz, dx):
    return [(z + dz, x + dx) for z, x in pts]


def rough_levels(moves):
    return sorted({round(m["end"]["X"], 9) for m in moves}, reverse=True)


def test_g71_type1_passes_outside_contour_plus_allowance(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_I)
    assert r.code == 0, r.alarm
    g71 = r.tagged("G71")
    contour = polyline(shifted(TYPE_I_PTS, 0.1, 0.2))
    assert_outside(g71, contour)
    rough = r.tagged("G71", "rough")
    assert rough and all(m["kind"] == "line" for m in rough)
    # each layer is parallel to Z and at most U1.5 (radius) below the previous one
    assert all(abs(m["start"]["X"] - m["end"]["X"]) < 1e-9 for m in rough)
    levels = [21.0] + rough_levels(rough)
    assert all(a - b <= 1.5 + 1e-9 for a, b in zip(levels, levels[1:]))
    assert levels[1] == 21.0 - 1.5
    # the deepest layer reaches the lowest point of the contour + allowance
    assert math.isclose(levels[-1], 5.2, abs_tol=1e-6)
    # layers stop at the contour: each ends on the shifted contour or at its last Z
    for m in rough:
        z, x = zx(m["end"])
        assert distance_to(contour, (z, x)) < 1e-6


def test_g71_profile_pass_and_end_position(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_I)
    contour = polyline(shifted(TYPE_I_PTS, 0.1, 0.2))
    prof = r.tagged("G71", "profile")
    assert prof, "H1 (default) ends with a pass along the contour + allowance"
    for m in prof:
        for p in samples(m, 8):
            assert distance_to(contour, p) < 1e-6
    # the whole contour (less the chamfer, which the profile also follows) is covered
    length = sum(seg_of(m).length() for m in prof)
    assert length > 0.95 * sum(s.length() for s in contour[:-1])
    last = r.tagged("G71")[-1]
    assert zx(last["end"]) == (2.0, 21.0), "G71 ends at its start point (decisions A45)"


def test_g70_follows_contour_with_chamfer(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_I)
    fin = [m for m in r.tagged("G70", "finish") if m["kind"] != "rapid"]
    contour = polyline(TYPE_I_PTS)
    for m in fin:
        for p in samples(m, 8):
            assert distance_to(contour, p) < 1e-6
    # ,C1. at the shoulder Z-30 X30: a 45° chamfer of 1 mm legs replaces the corner
    chamfers = [m for m in fin if abs(abs(m["end"]["Z"] - m["start"]["Z"]) - 1.0) < 1e-6
                and abs(abs(m["end"]["X"] - m["start"]["X"]) - 1.0) < 1e-6]
    assert len(chamfers) == 1
    assert zx(chamfers[0]["start"]) == (-30.0, 14.0) and zx(chamfers[0]["end"]) == (-31.0, 15.0)
    ret = r.tagged("G70", "return")
    assert zx(ret[-1]["end"]) == (2.0, 21.0) or zx(r.tagged("G70")[-1]["end"]) == zx(r.tagged("G70")[0]["start"])


def test_g71_type2_pocket(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_II)
    assert r.code == 0, r.alarm
    contour = polyline(shifted(TYPE_II_PTS, 0.1, 0.2))
    g71 = r.tagged("G71")
    assert_outside(g71, contour)
    rough = r.tagged("G71", "rough")
    levels = [21.0] + rough_levels(rough)
    assert all(a - b <= 2.0 + 1e-9 for a, b in zip(levels, levels[1:]))
    # the pocket between Z-20 and Z-25 is roughed down to its bottom + allowance
    pocket = [m for m in rough if m["start"]["Z"] >= -20.2 and m["end"]["Z"] <= -24.8]
    assert min(m["end"]["X"] for m in pocket) == 10.2
    # layers below the shoulder (X15.2) start inside the pocket: the tool plunges where the
    # contour crosses the layer, never through the shoulder
    for m in r.tagged("G71", "plunge"):
        assert m["end"]["X"] < 15.2 and m["end"]["Z"] < -9.9
    assert len(r.tagged("G71", "plunge")) == len([lv for lv in levels if lv < 15.2])
    assert zx(g71[-1]["end"]) == (1.0, 21.0)


def test_g72_facing(capsys, tmp_path):
    prog = """G21 G99
G00 X42. Z2.
G72 W2. R0.5
G72 P10 Q20 U0.2 W0.1 F0.2
N10 G00 Z-20.
G01 X30. F0.1
X20. Z-10.
Z-5.
N20 X0. Z0.
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    # the face contour as Z = c(X): swap the axes and reuse the X-of-Z helper
    pts = [(-20.0, 21.0), (-20.0, 15.0), (-10.0, 10.0), (-5.0, 10.0), (0.0, 0.0)]
    sw = polyline([(x + 0.1, z + 0.1) for z, x in pts])
    rough = r.tagged("G72", "rough")
    assert rough
    for m in r.tagged("G72"):
        for z, x in samples(m, 8):
            if 0.1 + 1e-9 < x < 21.1 - 1e-9:
                assert z >= contour_x(sw, x) - 1e-6 or distance_to(sw, (x, z)) < 1e-6, (m, z, x)
    # layers are parallel to X, at most W2. apart in Z
    assert all(abs(m["start"]["Z"] - m["end"]["Z"]) < 1e-9 for m in rough)
    levels = sorted({round(m["end"]["Z"], 9) for m in rough}, reverse=True)
    levels = [2.0] + levels
    assert all(a - b <= 2.0 + 1e-9 for a, b in zip(levels, levels[1:]))
    assert math.isclose(levels[-1], -19.9, abs_tol=1e-6)
    assert zx(r.tagged("G72")[-1]["end"]) == (2.0, 21.0)


def test_g71_depth_from_parameters(capsys, tmp_path):
    prog = TYPE_I.replace("G71 U1.5 R0.5\n", "")
    r = run(capsys, tmp_path, prog, "--param", "N1.170=1.0", "--param", "N1.171=0.3")
    assert r.code == 0, r.alarm
    levels = [21.0] + rough_levels(r.tagged("G71", "rough"))
    assert levels[1] == 20.0 and all(a - b <= 1.0 + 1e-9 for a, b in zip(levels, levels[1:]))
    retract = r.tagged("G71", "retract")[0]
    assert math.isclose(retract["end"]["X"] - retract["start"]["X"], 0.3, abs_tol=1e-9)


def test_g71_h0_no_profile_pass(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_I.replace("G71 U1.5 R0.5", "G71 U1.5 R0.5 H0"))
    assert r.code == 0, r.alarm
    assert not r.tagged("G71", "profile")
    assert r.tagged("G71", "rough")


def test_g71_invalid_contour_alarms(capsys, tmp_path):
    # type II contour that turns back in Z
    bad = TYPE_II.replace("X30. Z-35.", "X30. Z-15.")
    r = run(capsys, tmp_path, bad)
    assert r.code == 1 and r.alarm["code"] == "0x0246"
    assert r.alarm["line"] == 4
    # type I (P block moves X only) with a pocket
    bad1 = TYPE_II.replace("N10 G00 X30. Z0.", "N10 G00 X30.")
    r = run(capsys, tmp_path, bad1)
    assert r.code == 1 and r.alarm["code"] == "0x0246"


def test_g71_missing_q_label_alarms(capsys, tmp_path):
    r = run(capsys, tmp_path, TYPE_I.replace("N20 X42.", "X42."))
    assert r.code == 1 and r.alarm["code"] == "0x0264"


def test_g73_pattern_repeat(capsys, tmp_path):
    prog = """G21 G99
G00 X41. Z2.
G73 U10. W10. R5.
G73 P50 Q60 U0.4 W0.2 F0.25
N50 G00 X20.
G01 Z-20. F0.12
X30. Z-25.
W-5.
N60 X41.
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    contour = [(2.0, 10.0), (-20.0, 10.0), (-25.0, 15.0), (-30.0, 15.0), (-30.0, 20.5)]
    for n in range(1, 6):
        passes = [m for m in r.tagged("G73", "pass", str(n)) if m["kind"] == "line"]
        frac = (5 - n) / 4
        dz, dx = 10.0 * frac + 0.2, 10.0 * frac + 0.2
        # the contour repeated, shifted by i·(R−n)/(R−1) + allowance (decisions A46)
        assert math.isclose(passes[0]["start"]["X"], 10.0 + dx, abs_tol=1e-9)
        assert math.isclose(passes[0]["end"]["Z"], -20.0 + dz, abs_tol=1e-9)
        segs = polyline([(z + dz, x + dx) for z, x in contour])
        for m in passes:
            for p in samples(m, 4):
                assert distance_to(segs, p) < 1e-6
    assert not r.tagged("G73", "pass", "6")
    assert zx(r.tagged("G73")[-1]["end"]) == (2.0, 20.5)


def test_g73_one_cut_alarms(capsys, tmp_path):
    prog = "G00 X41. Z2.\nG73 U10. W10. R1.\nG73 P50 Q60 U0.4 W0.2 F0.25\nN50 G00 X20.\nN60 G01 Z-20. F0.1\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 1 and r.alarm["code"] == "0x0246"


def test_rough_geometry_unit_arcs():
    """Pure geometry: a convex arc contour, the layers end exactly on the arc + allowance."""
    from nc.cycles.builder import PathBuilder
    from nc.cycles.turning import RoughSpec, rough

    arc = Seg((-5.0, 5.0), (-15.0, 15.0), (-15.0, 5.0), False)
    segs = [Seg((2.0, 5.0), (-5.0, 5.0)), arc, Seg((-15.0, 15.0), (-25.0, 15.0)), Seg((-25.0, 15.0), (-25.0, 20.0))]
    b = PathBuilder({"X": 20.0, "Z": 2.0}, ("Z", "X"), 1, "", lambda m: dict(m))
    b.feed = 0.2
    rough(b, segs, RoughSpec("G71", 2.0, 0.5, 0.0, 0.0, 1))
    ends = [m for m in b.events if "rough" in m.tags]
    assert len(ends) == 8
    for m in ends:
        z, x = m.end["Z"], m.end["X"]
        if -15 < z < -5:
            assert math.isclose(math.hypot(z + 15.0, x - 5.0), 10.0, abs_tol=1e-9)
