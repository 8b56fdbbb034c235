"""Worked lathe examples of seed-catalog §7 (E-L04 … E-L28, E-N11, E-N28, E-N56 … E-N66), each run as the
manual prints it through `hil path --json` (or `hil run` where the claim is about time or the spindle).

Printing conventions undone here, as in tests/test_lang_examples_catalog.py: side annotations that the
manuals set next to a block without parentheses (`(1) 1 st thread depth.`, `Thread offset angle (1)`) are
kept inside `( )` so that they stay comments; `.....` (lines the manual elides) become a `G04 P500` dwell;
symbolic figure values (`I-R.`) get the one number the figure allows. Everything else is verbatim,
including the unclosed `(` comments of the NC5 tables.
"""

from __future__ import annotations

import csv
import math
import statistics
from pathlib import Path

import pytest

from cycles_helpers import assert_outside, distance_to, polyline, run, samples, seg_of, zx
from nc.cycles.geometry import Seg
from nc.cycles.profile import shifted
from nc.cycles.threading import g34_check

ROOT = Path(__file__).resolve().parent.parent


# the frame the NC5 single-cycle examples (E-N60, E-N61, E-N65) share
NC5_START = "G00 X50.000\nG00 Z20.000\n{tool}\nG99 F0.500\nG97 S2000\nM3\nM8\nG40\n"
NC5_END = "G00 X50.000\nG00 Z20.000\nM09\nM05\n"


def work(m: dict) -> tuple[float, float]:
    """(X diameter, Z) in work coordinates, rounded to 0.1 µm."""
    return (round(m["work"]["X"], 4), round(m["work"]["Z"], 4))


def cutting(moves: list[dict]) -> list[dict]:
    return [m for m in moves if m["kind"] in ("line", "arc", "thread")]


def levels(moves: list[dict], axis: str) -> list[float]:
    """Distinct end values of `axis` (machine units), highest first."""
    return sorted({round(m["end"][axis], 6) for m in moves}, reverse=True)


def r_centre(p0: tuple[float, float], p1: tuple[float, float], r: float, ccw: bool) -> tuple[float, float]:
    """Centre of the ≤ 180° arc of radius r from p0 to p1 in the (Z, X radius) plane (+Z right, +X up)."""
    mz, mx = (p0[0] + p1[0]) / 2, (p0[1] + p1[1]) / 2
    dz, dx = p1[0] - p0[0], p1[1] - p0[1]
    c = math.hypot(dz, dx)
    h = math.sqrt(max(r * r - c * c / 4, 0.0))
    lz, lx = -dx / c, dz / c  # left of the chord
    s = 1.0 if ccw else -1.0
    return (mz + s * h * lz, mx + s * h * lx)


def sweep_deg(m: dict) -> float:
    """Swept angle of an arc move in the (Z, X) plane, positive in its own direction."""
    c = m["center"]
    a0 = math.atan2(m["start"]["X"] - c["X"], m["start"]["Z"] - c["Z"])
    a1 = math.atan2(m["end"]["X"] - c["X"], m["end"]["Z"] - c["Z"])
    d = math.degrees(a1 - a0) % 360.0
    return d if m["dir"] == "ccw" else (360.0 - d) % 360.0


# ---------------------------------------------------------------- lathe manual (L)


@pytest.mark.parametrize("block, centre", [
    ("G3 X-10. Z-5. I-R.", (0.0, -5.0)), ("G2 X-10. Z5. I-R.", (0.0, -5.0)),
    ("G2 X10. Z-5. IR.", (0.0, 5.0)), ("G3 X10. Z5. IR.", (0.0, 5.0)),
    ("G2 X10. Z5. KR.", (5.0, 0.0)), ("G3 X-10. Z5. KR.", (5.0, 0.0)),
    ("G3 X10. Z-5. K-R.", (-5.0, 0.0)), ("G2 X-10. Z-5. K-R.", (-5.0, 0.0)),
])
def test_E_L04_g18_centre_format_quarter_arcs(capsys, tmp_path, block, centre):
    # The figure is lost; X±10. (diameter) with Z±5. from the origin and I/K = ±R fit one radius only,
    # R = 5 (I/K are radius values, decisions A6). With G02 = clockwise seen from +Y (+Z right, +X up,
    # A29) every one of the eight is the quarter arc the figure shows, never the 270° one.
    r = run(capsys, tmp_path, f"G18 G00 X0. Z0.\n{block.replace('R.', '5.')} F0.1\nM30\n")
    assert r.code == 0, r.alarm
    arc = r.moves[-1]
    assert arc["kind"] == "arc" and arc["dir"] == ("cw" if block.startswith("G2") else "ccw")
    assert (arc["center"]["Z"], arc["center"]["X"]) == centre
    assert sweep_deg(arc) == pytest.approx(90.0)
    xs, zs = block.split()[1:3]
    assert work(arc) == (float(xs[1:]), float(zs[1:]))


def test_E_L04_symbolic_arc_without_address_is_an_alarm(capsys, tmp_path):
    # third picture, (4) `G2 X_ Z_ -B F_`: the K address is missing (documentation error); a bare value
    # is an instruction error on its line, not silently dropped
    r = run(capsys, tmp_path, "G18 G00 X0. Z0.\nG2 X10. Z5. -5. F0.1\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x0206" and r.alarm["line"] == 2


def test_E_L16_g41_g40_nose_centre_left_of_travel(capsys, tmp_path):
    # the figure's nose radius and tip are lost: tool 1 gets R0.8, tip 0 (the output is the nose centre)
    prog = """G10 L10 P1 R0.8 Q0
T0101
G0 X40. Z20. (Start point)
G41 G1 X20. Z0. F0.25 (Enable tool compensation)
Z-30.
X40.
G40 G0 X60. Z-20. (End point of tool compensation)
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    by_line = {n: [m for m in r.moves if m["line"] == n] for n in (3, 4, 5, 6, 7)}
    assert "comp" not in by_line[3][0].get("tags", [])
    # (2) start-up: ends offset normal to the start of (3), which runs toward -Z: left of travel is -X
    assert zx(by_line[4][0]["end"]) == pytest.approx((0.0, 9.2))
    # (3) Z-30.: the nose centre 0.8 below the programmed X20. (radius 10), then an outer-corner arc
    line3, corner = by_line[5]
    assert zx(line3["start"]) == pytest.approx((0.0, 9.2)) and zx(line3["end"]) == pytest.approx((-30.0, 9.2))
    assert corner["kind"] == "arc" and (corner["center"]["Z"], corner["center"]["X"]) == (-30.0, 10.0)
    # (4) X40. runs toward +X: left of travel is -Z
    assert zx(by_line[6][0]["start"]) == pytest.approx((-30.8, 10.0))
    assert zx(by_line[6][0]["end"]) == pytest.approx((-30.8, 20.0))
    for m in by_line[5] + by_line[6]:
        assert m["comp"] == "G41" and m["comp_radius"] == 0.8
    # (5) G40 G0: cancelled on the way to the programmed end point
    cancel = by_line[7][0]
    assert cancel["kind"] == "rapid" and "cancel" in cancel["tags"] and work(cancel) == (60.0, -20.0)
    assert zx(cancel["end"]) == (-20.0, 30.0)


E_L23 = """G54 X40.0 Z5.0
M03 S1000
G01 X45. Z5. F0.2
G72 W2. R3.
G72 P50 Q60 U0.2 W0.0 F0.15
N50 G01 X40. Z-20.          (1)
X30.                      (2)
Z-15.                     (3)
G03 X20. Z-5. R10.        (4)
G01 X5.                   (5)
N60 Z0.                   (6)
M5
M30
"""


def test_E_L23_g72_facing_example_1(capsys, tmp_path):
    r = run(capsys, tmp_path, E_L23)
    assert r.code == 0, r.alarm  # the R10 arc dips 0.08 mm under its end X20.: accepted (decisions A45)
    g72 = r.tagged("G72")
    rough = r.tagged("G72", "rough")
    # facing layers parallel to X, W2. apart from the start Z5., the last one clamped at the contour's Z-20.
    assert all(m["start"]["Z"] == m["end"]["Z"] for m in rough)
    assert levels(rough, "Z") == [3.0, 1.0, -1.0, -3.0, -5.0, -7.0, -9.0, -11.0, -13.0, -15.0, -17.0, -19.0, -20.0]
    # escape R3. at 45° after each layer
    for m in r.tagged("G72", "retract"):
        assert m["end"]["Z"] - m["start"]["Z"] == pytest.approx(3.0)
        assert m["end"]["X"] - m["start"]["X"] == pytest.approx(3.0)
    # roughing feed F0.15 of the cycle block, not the G01 F0.2 before it
    assert {m["feed"] for m in cutting(g72)} == {0.15}
    # the finished contour + U0.2 (diameter): the profile pass follows it corner by corner
    prof = r.tagged("G72", "profile")
    assert [work(m) for m in prof] == [(40.2, -20.0), (30.2, -20.0), (30.2, -15.0), (20.2, -5.0), (5.2, -5.0),
                                       (5.2, 0.0)]
    arc = prof[3]
    c = r_centre((-15.0, 15.1), (-5.0, 10.1), 10.0, ccw=True)
    assert arc["kind"] == "arc" and arc["dir"] == "ccw"
    assert (arc["center"]["Z"], arc["center"]["X"]) == pytest.approx(c)
    # no roughing move enters the part + allowance (its radius is a function of Z here); the layer at Z-7.
    # ends on the arc
    contour = polyline([(-20.0, 20.1), (-20.0, 15.1), (-15.0, 15.1)]) + [Seg((-15.0, 15.1), (-5.0, 10.1), c, False)] \
        + polyline([(-5.0, 10.1), (-5.0, 2.6), (0.0, 2.6)])
    assert_outside(g72, contour)
    z7 = [m for m in rough if m["end"]["Z"] == -7.0]
    assert distance_to(contour, zx(z7[0]["end"])) < 1e-6 and 10.0 < z7[0]["end"]["X"] < 10.1
    assert zx(g72[-1]["end"]) == (5.0, 22.5)  # back at the start point X45. Z5.


def assert_g73_o0007(r) -> None:
    """E-L24 / E-N58: five passes of the contour, each 2.5 mm (radius) and 2.5 mm in Z nearer than the last."""
    assert r.code == 0, r.alarm
    contour = [(2.0, 10.0), (-20.0, 10.0), (-25.0, 15.0), (-30.0, 15.0), (-30.0, 20.5)]
    for n in range(1, 6):
        moves = r.tagged("G73", "pass", str(n))
        cuts = cutting(moves)
        shift = 2.5 * (5 - n)
        dz, dx = shift + 0.2, shift + 0.2  # W0.2, U0.4 diameter
        assert moves[0]["kind"] == "rapid"  # N50 G0 X20.
        assert work(cuts[0]) == (round(20.0 + 2 * dx, 4), round(-20.0 + dz, 4))
        segs = polyline([(z + dz, x + dx) for z, x in contour])
        for m in cuts:
            for p in samples(m, 4):
                assert distance_to(segs, p) < 1e-6
        assert {m["feed"] for m in cuts} == {0.25}  # F0.25 of the cycle, not F0.12 in the contour
    assert not r.tagged("G73", "pass", "6")
    assert [zx(m["end"]) for m in r.tagged("G73", "return")] == [(2.0, 20.5)] * 5


def test_E_L24_g73_o0007(capsys, tmp_path):
    prog = """O0007
M3 S1600
T3
G0 X41. Z2.
G73 U10. W10. R5.
G73 P50 Q60 U0.4 W0.2 F0.25
N50 G0 X20.
G1 Z-20. F0.12
X30. Z-25.
W-5.
N60 X41.
G0 X50. Z10.
M5
M30
"""
    r = run(capsys, tmp_path, prog)
    assert_g73_o0007(r)
    assert work(r.moves[-1]) == (50.0, 10.0)


def test_E_L25_g71_g70_with_fillet_and_chamfer(capsys, tmp_path):
    prog = """M3 S1000
T3
G0 X41. Z2.
G71 U2. R3. (rough turning)
G71 P50 Q60 U0.2 W0.2 F0.25
N50 G0 X10. Z0.5
G1 Z-5. F0.12
G03X20. W-5. R5.
G01Z-15.,R2.
U10.Z-20.,C1.
Z-30.
X20.Z-35.
W-3.
N60 X40.2
G70 P50 Q60 (finish turning)
M5
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    fin = r.tagged("G70", "finish")
    assert [work(m) for m in fin] == [(10.0, 0.5), (10.0, -5.0), (20.0, -10.0), (20.0, -14.1716), (21.1716, -15.5858),
                                      (28.5858, -19.2929), (30.0, -21.0), (30.0, -30.0), (20.0, -35.0),
                                      (20.0, -38.0), (40.2, -38.0)]
    assert fin[0]["kind"] == "rapid" and {m["feed"] for m in cutting(fin)} == {0.12}
    g03, fillet = fin[2], fin[4]
    assert g03["dir"] == "ccw" and (g03["center"]["Z"], g03["center"]["X"]) == pytest.approx((-10.0, 5.0))
    # ,R2. tangent to Z-15. and to the 45° line; ,C1. with 1 mm legs from the virtual corner X30. Z-20.
    assert fillet["dir"] == "cw" and (fillet["center"]["Z"], fillet["center"]["X"]) == pytest.approx((-14.1716, 12.0),
                                                                                                     abs=1e-4)
    assert "chamfer" not in fin[6]["tags"] and ",C" in fin[6]["tags"]
    # after G70 the tool returns to the start point in rapid traverse
    ret = r.tagged("G70", "return")
    assert ret[-1]["kind"] == "rapid" and work(ret[-1]) == (41.0, 2.0)
    # roughing: 2.0 mm (radius) layers down to X10. + U0.2, the pocket X30. → X20. included
    rough = r.tagged("G71", "rough")
    assert [2 * x for x in levels(rough, "X")] == [37.0, 33.0, 29.0, 25.0, 21.0, 17.0, 13.0, 10.2]
    assert len(r.tagged("G71", "plunge")) == 3  # X29. X25. X21. come down into the pocket behind X30.
    assert {m["feed"] for m in cutting(r.tagged("G71"))} == {0.25}
    contour = shifted([seg_of(m) for m in fin[1:]], 0.2, 0.1)
    assert_outside(r.tagged("G71"), contour)


def test_E_L26_several_g70_after_all_roughing(capsys, tmp_path):
    # the manual prints the structure only; the `...` are filled with two OD steps
    prog = """G0 X41. Z2.
G71 U2. R1.
G71 P10 Q20 U0.2 W0.1 F0.25
N10 G0 X30.
G1 Z-20. F0.1
N20 X41.
G71 U2. R1.
G71 P30 Q40 U0.2 W0.1 F0.25
N30 G0 X20.
G1 Z-10. F0.12
N40 X41.
G0 X41. Z2.
G70 P10 Q20
G70 P30 Q40
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    order = [next(t for t in ("G71", "G70") if t in m.get("tags", [])) for m in r.moves if
             {"G70", "G71"} & set(m.get("tags", []))]
    first70 = order.index("G70")
    assert set(order[first70:]) == {"G70"}  # both roughing cycles first, then the finishing passes
    assert [levels(r.tagged("G71", "rough")[:4], "X")[0], min(m["end"]["X"] for m in r.tagged("G71", "rough"))] \
        == [18.5, 10.1]  # the second cycle roughs down to X20. + U0.2
    fin = [m for m in r.tagged("G70", "finish") if m["kind"] == "line"]
    # first G70 runs N10–N20 at F0.1, the second N30–N40 at F0.12, in program order
    assert [(m["line"], work(m), m["feed"]) for m in fin] == [(5, (30.0, -20.0), 0.1), (6, (41.0, -20.0), 0.1),
                                                              (10, (20.0, -10.0), 0.12), (11, (41.0, -10.0), 0.12)]
    assert [work(m) for m in r.tagged("G70", "return")] == [(41.0, 2.0), (41.0, 2.0)]


def test_E_L27_g74_g75_peck_grooving(capsys, tmp_path):
    prog = """T0404
M3 S2000
G0X30.Z5. (Start point of G74 cycle)
G74 R1.
G74 X20. Z-5. P3000 Q5000 R0. F0.3
G0X20.Z5.
G74 R1.
G74 X12. Z-10. P3000 Q5000 R0. F0.3 (Start point of G74 cycle)
G0Z5.
X50.
T0505
G0 Z-18. (Start point of G75 cycle)
G75 R1.
G75 X30. Z-20. P5000 Q3000 R0. F0.3
G0Z-20.
G75 R1.
G75 X20.Z-30.P5000 Q3000R0. F0.3
G0 X50.
Z5.
M5
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm

    def grooves(line: int, code: str, across: str, along: str) -> dict[float, list[float]]:
        out: dict[float, list[float]] = {}
        for m in r.tagged(code, "peck"):
            if m["line"] == line:
                out.setdefault(round(m["work"][across], 4), []).append(round(m["work"][along], 4))
        return out

    # G74: P3000 = 3 mm (radius) X shift, Q5000 = 5 mm Z pecks, the last position/peck clamped at the target
    assert grooves(5, "G74", "X", "Z") == {30.0: [0.0, -5.0], 24.0: [0.0, -5.0], 20.0: [0.0, -5.0]}
    assert grooves(8, "G74", "X", "Z") == {20.0: [0.0, -5.0, -10.0], 14.0: [0.0, -5.0, -10.0], 12.0: [0.0, -5.0, -10.0]}
    # G75: P5000 = 5 mm (radius) X pecks, Q3000 = 3 mm Z shift
    assert grooves(14, "G75", "Z", "X") == {-18.0: [40.0, 30.0], -20.0: [40.0, 30.0]}
    assert grooves(17, "G75", "Z", "X") == {z: [40.0, 30.0, 20.0] for z in (-20.0, -23.0, -26.0, -29.0, -30.0)}
    # R1. of the first block: back off 1 mm after each peck
    for m in r.tagged("G74", "retract"):
        assert m["end"]["Z"] - m["start"]["Z"] == pytest.approx(1.0)
    for m in r.tagged("G75", "retract"):
        assert m["end"]["X"] - m["start"]["X"] == pytest.approx(1.0)
    assert {m["feed"] for m in r.tagged("peck")} == {0.3}
    # each cycle ends at its start point
    ends = {line: [work(m) for m in r.moves if m["line"] == line][-1] for line in (5, 8, 14, 17)}
    assert ends == {5: (30.0, 5.0), 8: (20.0, 5.0), 14: (50.0, -18.0), 17: (50.0, -20.0)}
    assert work(r.moves[-1]) == (50.0, 5.0)


def test_E_L28_g76_p_word_m_r_a(capsys, tmp_path):
    # "P011160: the number of the finish turning time is 1, chamfering amount is 1.1 L, tool nose angle 60°"
    prog = "G00 X28. Z5.\nG76 P011160 Q100 R0.05\nG76 X21.4 Z-22. P1300 Q400 F2.\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    main = [m for m in r.tagged("G76") if m["kind"] == "thread" and "chamfer" not in m["tags"]]
    assert len([m for m in main if "finish" in m["tags"]]) == 1  # m = 01
    for m in r.tagged("G76", "chamfer"):  # r = 11: 1.1 × lead 2. = 2.2 mm pulled out at 45°
        assert m["end"]["Z"] == -22.0 and m["start"]["Z"] - m["end"]["Z"] == pytest.approx(2.2)
    for m in main:  # a = 60: right-flank infeed along the 30° half angle
        height = m["start"]["X"] - 10.7
        assert m["start"]["Z"] - 5.0 == pytest.approx(height * math.tan(math.radians(30.0)), abs=1e-6)


# ---------------------------------------------------------------- NC5 manual (N)


def test_E_N28_spindle_clamp_holds_under_g96_and_g97(hil, program, tmp_path):
    text = ("G92 S200 (Apply G92 to limit the spindle maximum speed to 200RPM)\n"
            "G96 S130 M03 (Cutting speed remains at 130 m/min)\n"
            "G04 P500\n"
            "G97 S1300 M03 (Represents the spindle speed remaining at 1300 RPM)\n"
            "G04 P500\n"
            "M30\n")

    def rpm_by_line(prog_text: str) -> dict[int, float]:
        trace = tmp_path / "t.csv"
        res = hil("run", program(prog_text), "--profile", "nc5-lathe-b", "--trace", trace)
        assert res.code == 0, res.out + res.err
        by_line: dict[int, list[float]] = {}
        for row in csv.DictReader(open(trace)):
            by_line.setdefault(int(row["line"]), []).append(float(row["S1_rpm_cmd"]))
        # the speed during each G04 (the trace keeps a dwell's line until the next move, so the next
        # block's S, which takes effect at once, ends its rows)
        out = {line: statistics.median(v) for line, v in by_line.items()}
        out[-1] = max(max(v) for v in by_line.values())  # the highest command of the run
        return out

    # G92 S is the clamp on lathe type B. At the bench's X60 (radius) 130 m/min would need 345 rpm.
    rpm = rpm_by_line(text)
    assert rpm[3] == pytest.approx(200.0, abs=0.01)
    # the manual's "remaining at 1300 RPM" under a 200 rpm clamp is taken as a documentation error (A39)
    assert rpm[5] == pytest.approx(200.0, abs=0.01) and rpm[-1] == pytest.approx(200.0, abs=0.01)
    free = rpm_by_line(text.replace("G92 S200", "(G92 S200)"))
    assert free[3] == pytest.approx(1000.0 * 130.0 / (math.pi * 120.0), rel=1e-3) and free[5] == pytest.approx(1300.0)


def test_E_N56_g71_example_2(capsys, tmp_path):
    prog = """G00 X70.000
G00 Z20.000
T0101
G98 F1000
G50 S1000
G50 S1000 M3
G00 X65.000 Z10.000
G42 G71 U1.000 R0.5
G71 P210 Q250 U0.300 W0.300
N210 G01 X0.000 Z0.000
G01 X18.000 Z0.000 ,C1.000
G01 X18.000 Z-20.000
G01 X25.000 Z-20.000
G01 X30.000 Z-45.000
G01 X30.000 Z-55.000
G01 X36.000 Z-55.000 ,C1.000
G01 X36.000 Z-75.000
G01 X40.000 Z-75.000 ,C1.000
G01 X40.000 Z-90.000
G02 X40.000 Z-126.000 R80.000
G01 X40.000 Z-136.000
G01 X45.000 Z-136.000
G01 X45.000 Z-151.000
G01 X50.000 Z-151.000
G01 X50.000 Z-190.000
G01 X55.000 Z-190.000
N250 G00 X70.000
G00 Z20.000
M5
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g71 = r.tagged("G71")
    # G98 F1000 is modal: the roughing feed is 1000 mm/min (no F in the cycle), per minute
    assert {(m["feed"], m.get("per_rev", False)) for m in cutting(g71)} == {(1000.0, False)}
    # G42 in the G71 block: tool nose compensation does not act in the cycle
    assert not any("comp" in m for m in g71)
    # U1. R0.5: 1 mm (radius) layers from X65., escape 0.5 mm at 45°
    rough = r.tagged("G71", "rough")
    # (the layer at X0. + U0.3 would only touch the face: nothing left to cut there)
    assert levels(rough, "X") == [31.5 - k for k in range(32)]
    for m in r.tagged("G71", "retract"):
        assert m["end"]["X"] - m["start"]["X"] == pytest.approx(0.5)
    # profile pass: the contour + U0.3 W0.3 with the three ,C1. chamfers (1 mm legs, radius)
    prof = [work(m) for m in r.tagged("G71", "profile")]
    assert prof[:5] == [(0.3, 0.3), (16.3, 0.3), (18.3, -0.7), (18.3, -19.7), (25.3, -19.7)]
    assert prof[7:12] == [(34.3, -54.7), (36.3, -55.7), (36.3, -74.7), (38.3, -74.7), (40.3, -75.7)]
    # the R80 arc over a 36 mm chord is a groove 2.05 mm (radius) deep: roughed as a pocket
    arc = [m for m in r.tagged("G71", "profile") if m["kind"] == "arc"][0]
    assert arc["dir"] == "cw" and arc["center"]["X"] - 20.15 == pytest.approx(math.sqrt(80.0 ** 2 - 18.0 ** 2))
    pocket = [m for m in rough if m["end"]["Z"] > -125.7 and m["start"]["Z"] < -89.7 and m["end"]["X"] < 20.15]
    assert pocket and min(m["end"]["X"] for m in pocket) == pytest.approx(18.5)
    assert_outside(g71, [seg_of(m) for m in r.tagged("G71", "profile")])
    # the cycle ends at its start point; execution goes on after N250 (G00 Z20.)
    assert zx(g71[-1]["end"]) == (10.0, 32.5)
    assert work(r.moves[-1]) == (65.0, 20.0)


def test_E_N57_g72_example_2(capsys, tmp_path):
    prog = """G00 X90.000
G00 Z20.000
T0101
G99 F0.500
G50 S2000
G97 S1000 M3
G00 X85.000 Z10.000
G40
G72 W2.000 R0.5
G72 P210 Q250 U0.500 W0.500 F0.500
N210 G01 X80.000 Z-30.000 F0.200
G01 X80.000 Z-20.000 ,C1.000
G01 X70.000
G01 X65.000 Z-10.000
G01 X60.000
G03 X40.000 R5.000
G01 X30.000
G01 Z0.000 ,R5.000
G01 X0.000 Z0.000
N250 G00 X90.000
G00 Z20.000
M09
M05
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g72 = r.tagged("G72")
    # roughing at F0.5 mm/rev of the cycle block; the F0.2 in N210 is for G70
    assert {(m["feed"], m.get("per_rev")) for m in cutting(g72)} == {(0.5, True)}
    rough = r.tagged("G72", "rough")
    assert all(m["start"]["Z"] == m["end"]["Z"] for m in rough)
    assert levels(rough, "Z") == [8.0 - 2.0 * k for k in range(19)]  # W2. from Z10.
    for m in r.tagged("G72", "retract"):
        assert m["end"]["Z"] - m["start"]["Z"] == pytest.approx(0.5)
    # profile pass: contour + U0.5 (diameter) W0.5 with ,C1. at X80. Z-20. and ,R5. at X30. Z0.
    prof = r.tagged("G72", "profile")
    assert [work(m) for m in prof] == [(80.5, -29.5), (80.5, -20.5), (78.5, -19.5), (70.5, -19.5), (65.5, -9.5),
                                       (60.5, -9.5), (40.5, -9.5), (30.5, -9.5), (30.5, -4.5), (20.5, 0.5),
                                       (0.5, 0.5)]
    semi, fillet = prof[6], prof[9]
    # G03 X40. R5. from X60. is an exact semicircle (radial chord 10 = 2R): a groove down to Z-15.
    assert semi["dir"] == "ccw" and sweep_deg(semi) == pytest.approx(180.0)
    assert (semi["center"]["Z"], semi["center"]["X"]) == pytest.approx((-9.5, 25.25))
    assert fillet["kind"] == "arc" and (fillet["center"]["Z"], fillet["center"]["X"]) == pytest.approx((-4.5, 10.25))
    # the groove is roughed as a pocket: layers Z-12. and Z-14. between its walls
    groove = [m for m in rough if m["end"]["Z"] in (-12.0, -14.0) and m["start"]["X"] < 30.25]
    assert len(groove) == 2
    assert_outside(g72, [seg_of(m) for m in prof[1:]], face=True)  # prof[0] is N210 from the start point
    assert zx(g72[-1]["end"]) == (10.0, 42.5)
    assert work(r.moves[-1]) == (85.0, 20.0)


def test_E_N58_g73_lathe(capsys, tmp_path):
    prog = """T0101
M03 S1600
G00 X41.000 Z2.000
G73 U10.000 W10.000 R5.000 (X,Z total removal 10mm, cycle times 5
G73 P50 Q60 U0.400 W0.200 F0.250
N50 G00 X20.000
G01 Z-20.000 F0.12
G01 X30.000 Z-25.000
G01 W-5.000
N60 X41.000
"""
    assert_g73_o0007(run(capsys, tmp_path, prog))


def test_E_N59_g74_lathe(capsys, tmp_path):
    prog = """G00Z20.000
G00X50.000 (A: X50.0, Z20.0)
T0101
G99 F0.500 (Feed rate setting
G50 S1500 (Spindle Max. speed setting
G97 S1000 (Spindle speed setting
M03
M08
G40 (Disable tool compensation
G00 X30.000 Z5.000
G01 Z5.000 (Cycle initial position
(B:X30.000, Z5.000)
G74 R0.500 (Withdraw in Z axis direction
(X axis feeding 2.5mm, Z axis peck feeding 2.0mm
(Cycle target position C (X20.0, Z-20.0)
G74 X20.000 Z-20.000 P2500 Q2000 R0.000
G01 Z5.000
G00 Z5.000
G00 Z20.000
G00 X50.000
M09
M05
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    pecks = r.tagged("G74", "peck")
    # P2500: X step 2.5 mm in radius → grooves at X30., X25., X20. (the last at the target C)
    cols = sorted({work(m)[0] for m in pecks}, reverse=True)
    assert cols == [30.0, 25.0, 20.0]
    for x in cols:  # Q2000: 2 mm pecks from Z5., twelve full and a last 1 mm one to Z-20.
        assert [work(m)[1] for m in pecks if work(m)[0] == x] == [5.0 - 2.0 * k for k in range(1, 13)] + [-20.0]
    for m in r.tagged("G74", "retract"):  # R0.5 of the first block
        assert m["end"]["Z"] - m["start"]["Z"] == pytest.approx(0.5)
    assert {(m["feed"], m["per_rev"]) for m in pecks} == {(0.5, True)}  # modal G99 F0.5
    assert zx(r.tagged("G74")[-1]["end"]) == (5.0, 15.0)  # back at B
    assert work(r.moves[-1]) == (50.0, 20.0)  # A


def test_E_N60_g90_taper_turning(capsys, tmp_path):
    prog = NC5_START.format(tool="T0303") + """G00 X37.000 Z5.000
G90 X35.000 Z-40.000 R-5.000     (End of cycle turning (1)
X33.000                          (End of cycle turning (2)
X31.000                          (End of cycle turning (3)
X29.000                          (End of cycle turning (4)
""" + NC5_END + "M30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g90 = r.tagged("G90")
    assert len(g90) == 16
    for n, xe in enumerate((35.0, 33.0, 31.0, 29.0)):
        app, cut, out, back = g90[4 * n: 4 * n + 4]
        # (radius) at the start Z: rapid to X(end) − 10 at Z5., taper cut to the end point, out, back
        assert [m["kind"] for m in (app, cut, out, back)] == ["rapid", "line", "line", "rapid"]
        assert [work(m) for m in (app, cut, out, back)] == [(xe - 10.0, 5.0), (xe, -40.0), (37.0, -40.0), (37.0, 5.0)]
        assert cut["feed"] == 0.5 and cut["per_rev"]  # 0.5 mm/rev × 2000 rpm = 1000 mm/min
    assert work(r.moves[-1]) == (50.0, 20.0)


def test_E_N61_g94_example_printed_with_g90(capsys, tmp_path):
    prog = NC5_START.format(tool="T0101") + """G00X45.0 Z5.0
G90X12.0 Z-7.0R-5. (End of cycle turning 1)
Z-8.000 (End of cycle turning 2)
Z-9.000 (End of cycle turning 3)
Z-10.000 (End of cycle turning 4)
""" + NC5_END + "M30\n"
    # as printed (decisions A49): G90 is what runs: an OD taper turning cycle, the Z words step its length
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g = r.tagged("G90")
    for n, ze in enumerate((-7.0, -8.0, -9.0, -10.0)):
        assert [work(m) for m in g[4 * n: 4 * n + 4]] == [(2.0, 5.0), (12.0, ze), (45.0, ze), (45.0, 5.0)]
    # as the section means it (G94 face cycle): rapid to Z(end) + R, face to X12., out along Z, back
    r = run(capsys, tmp_path, prog.replace("G90X12.0", "G94X12.0"))
    assert r.code == 0, r.alarm
    g = r.tagged("G94")
    for n, ze in enumerate((-7.0, -8.0, -9.0, -10.0)):
        assert [work(m) for m in g[4 * n: 4 * n + 4]] == [(45.0, ze - 5.0), (12.0, ze), (12.0, 5.0), (45.0, 5.0)]


def test_E_N62_g32_five_passes(capsys, tmp_path):
    prog = """T0101
M03 S1000
G00 X40.000 Z15.000
X17.450 (1) (1 st thread depth.)
G32 Z-30.000 F1.5 (2) (Threading.)
G00 X40.000 (3) (X axis fast withdraw.)
G00 Z15.000 (4) (Z axis fast withdraw.)
G00 X17.200 (1) (2 nd thread depth.)
G32 Z-30.000 F1.5 (2) (Threading.)
G00 X40.000 (3) (X axis fast withdraw.)
G00 Z15.000 (4) (Z axis fast withdraw.)
X17.000 (1) (3 rd thread depth.)
G32 Z-30.000 F1.5 (2) (Threading.)
G00 X40.000 (3) (X axis fast withdraw.)
G00 Z15.000 (4) (Z axis fast ithdraw.)
G00 X16.850 (1) (4 th thread depth.)
G32 Z-30.000 F1.5 (2) (threading.)
G00 X40.000 (3) (X axis fast withdraw.)
G00 Z15.000 (4) (Z axis fast withdraw.)
G00 X16.800 (1) (5 th thread depth.)
G32 Z-30.000 F1.5 (2) (Threading.)
G00 X40.000 (3) (X axis fast withdraw.)
G00 Z15.000 (4) (Z axis fast withdraw.)
M05
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    threads = [m for m in r.moves if m["kind"] == "thread"]
    assert [work(m)[0] for m in threads] == [17.45, 17.2, 17.0, 16.85, 16.8]
    assert {zx(m["start"])[0] for m in threads} == {15.0} and {work(m)[1] for m in threads} == {-30.0}
    # lead 1.5 at 1000 rpm = 1500 mm/min, every pass on the same helix (Q0)
    assert {(m["lead"], m["start_angle"]) for m in threads} == {(1.5, 0.0)}
    # the third depth `X17.000` has no G code: G00 is modal after `G00 Z15.000`
    assert [m["kind"] for m in r.moves if m["line"] == 12] == ["rapid"]
    assert work(r.moves[-1]) == (40.0, 15.0)


def test_E_N63_multi_start_thread_via_g66(capsys, tmp_path):
    prog = """T0202
M03 S1000
G00 X45.000
G00 Z10.000
G66 P0001 A0 (Thread offset angle) (1)
X17.45
X17.20
X17.00
G67
G66 P0001 A120000 (Thread offset angle) (2)
X17.45
X17.20
X17.00
G67
G66 P0001 A240000 (Thread offset angle) (3)
X17.45
X17.20
X17.00
G67
G00 X45.000
G00 Z10.000
M30
O0001
(G66 P0001 A_ argument value inserted into the subprogram #1)
(#1 means thread offset angle)
G32 Z-30.000 F3.000 Q#1
G00 X45.000
G00 Z10.000
M99
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    threads = [m for m in r.moves if m["kind"] == "thread"]
    # 3 starts × 3 depths; A120000 reaches Q#1 unscaled: 120.000°; lead = 3 starts × pitch 1
    assert [(work(m)[0], m["start_angle"]) for m in threads] == [(x, a) for a in (0.0, 120.0, 240.0)
                                                                for x in (17.45, 17.2, 17.0)]
    assert {m["lead"] for m in threads} == {3.0} and {work(m)[1] for m in threads} == {-30.0}
    assert work(r.moves[-1]) == (45.0, 10.0)
    # the annotation wrapped whole, `(Thread offset angle (1))`, is not a comment: parentheses do not nest
    r = run(capsys, tmp_path, prog.replace("(Thread offset angle) (1)", "(Thread offset angle (1))"))
    assert r.code == 1 and r.alarm["code"] == "0x0206" and r.alarm["line"] == 5


def test_E_N64_g92_threading_cycle(capsys, tmp_path):
    prog = """T0101 (Select tool 1 compensation)
M03 S2000 (Spindle positive rotation 2000 RPM)
G00 Z5.000 (1) (Z axis threading initial point.)
X30.000 (2) (X axis withdraw distance.)
(3) (thread depth 17.65 mm.)
(4) (length 25 mm.)
(5) (thread lead value 1.5 mm.)
G92 X17.65 Z-25.0 F1.5
X17.45 (Thread depth)
X17.25 (Thread depth)
X17.05 (Thread depth)
X16.85 (Thread depth)
X16.65 (Thread depth)
X16.45 (Thread depth)
X16.25 (Thread depth)
X16.05 (Thread depth)
X15.9 (Thread depth)
M05 (Spindle stop)
G00 X50.000 (Tool return to a safe distance)
G00 Z10.000 (Tool return to a safe distance)
M30 (Program finish)
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    body = [m for m in r.tagged("G92", "thread") if "chamfer" not in m["tags"]]
    assert [work(m)[0] for m in body] == [17.65, 17.45, 17.25, 17.05, 16.85, 16.65, 16.45, 16.25, 16.05, 15.9]
    assert {(m["lead"], m["start_angle"]) for m in body} == {(1.5, 0.0)}  # 3000 mm/min at 2000 rpm
    # the end chamfer (N1.178 = 1.0 lead, N1.177 = 45°) ends at Z-25.
    ch = r.tagged("G92", "chamfer")
    assert len(ch) == 10 and all(m["end"]["Z"] == -25.0 and m["start"]["Z"] == pytest.approx(-23.5) for m in ch)
    assert {work(m) for m in r.tagged("G92", "return")} == {(30.0, 5.0)}
    assert len(r.tagged("G92", "approach")) == 10  # `M05` alone does not repeat the cycle
    assert [work(m) for m in r.moves[-2:]] == [(50.0, 5.0), (50.0, 10.0)]


def test_E_N65_g76_depths_chamfer_taper(capsys, tmp_path):
    prog = NC5_START.format(tool="T0303") + """G00 X37.000 Z5.000
G76 P10160 Q200 R0.100
G76 X30.600 Z-40.000 R-5. P2200 Q500 L0 F2.000
""" + NC5_END
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    main = [m for m in r.tagged("G76") if m["kind"] == "thread" and "chamfer" not in m["tags"]]
    slope = 5.0 / 45.0  # R-5.: the root (radius) rises 5 mm from Z5. to Z-40.

    def root(z: float) -> float:
        return 15.3 - (z + 40.0) * slope

    depths = [round(2.2 - (m["end"]["X"] - root(m["end"]["Z"])), 4) for m in main]
    # Δd√n from Q500 (0.5 mm), each step at least Δdmin Q200 (0.2 mm), last rough at k − d = 2.1, 1 finish at k
    assert depths == [0.5, 0.7071, 0.9071, 1.1071, 1.3071, 1.5071, 1.7071, 1.9071, 2.1, 2.2]
    assert [("finish" in m["tags"]) for m in main] == [False] * 9 + [True]
    assert {(m["lead"], m["start_angle"], m["per_rev"]) for m in main} == {(2.0, 0.0, True)}  # 4000 mm/min
    # every pass runs along the taper, parallel to the root line
    for m in main:
        dz = m["end"]["Z"] - m["start"]["Z"]
        assert (m["end"]["X"] - m["start"]["X"]) / dz == pytest.approx(-slope)
    # the final pass starts on the programmed root: X30.6 + 2·R = X20.6 at Z5.
    assert work(r.tagged("G76", "infeed")[-1]) == (20.6, 5.0)
    # L0: infeed along the right flank, a = 60 → start shifted by (k − depth)·tan 30°
    for m, d in zip(main, depths):
        assert m["start"]["Z"] - 5.0 == pytest.approx((2.2 - d) * math.tan(math.radians(30.0)), abs=1e-4)
    # r = 01: chamfer 0.1 × 1 × lead 2. = 0.2 mm in Z, ending at Z-40., 45° off the taper line
    for m in r.tagged("G76", "chamfer"):
        assert m["end"]["Z"] == -40.0 and m["start"]["Z"] - m["end"]["Z"] == pytest.approx(0.2)
        assert m["end"]["X"] - m["start"]["X"] - 0.2 * slope == pytest.approx(0.2)
    assert work(r.moves[-1]) == (50.0, 20.0)


E_N66 = """(Main program)
T0101 (Select tool 1)
M03 S600 (Spindle positive rotate 600 RPM)
G00 X50.000 Z5.000 (Rapidly move to engage point)
G66 P0001 L1 (Macro call instruction: (Execute once sub-program O0001
X17.65 (Thread depth)
X17.45 (Thread depth)
X17.30 (Thread depth)
X17.20 (Thread depth)
X17.10 (Thread depth)
X17.05 (Thread depth)
G67 (Macro call instruction finish)
G00 X50.000 Z5.000 (Rapidly move to tool withdraw)
M05 (Spindle stop)
M30 (Program finish)
(Sub-program)
O0001
(Thread length Z-30.)
(Thread pitch increase 0.5 mm/rev, initial thread pitch 1 mm)
G34 Z-30.000 K0.5 F1.000
G00 X50.000
G00 Z5.000
M99 (Return to main program)
"""


def test_E_N66_g34_variable_lead_passes(capsys, tmp_path):
    r = run(capsys, tmp_path, E_N66)
    assert r.code == 0, r.alarm
    threads = [m for m in r.moves if m["kind"] == "thread"]
    # one pass per depth block; the modal G66 does not fire again on the subprogram's own motion
    assert [work(m)[0] for m in threads] == [17.65, 17.45, 17.3, 17.2, 17.1, 17.05]
    assert {(m["lead"], m["lead_change"], zx(m["start"])[0], work(m)[1]) for m in threads} == {(1.0, 0.5, 5.0, -30.0)}
    # 35 mm = F·t + ½K·t² → exactly 10 turns; the lead grows from F to F + K·t = 6 mm/rev
    assert g34_check(35.0, 1.0, 0.5) == pytest.approx(10.0)
    assert work(r.moves[-1]) == (50.0, 5.0)


def test_E_N66_g34_pass_takes_ten_turns_on_the_bench(hil, program, tmp_path):
    trace = tmp_path / "t.csv"
    res = hil("run", program(E_N66), "--trace", trace)
    assert res.code == 0, res.out + res.err
    rows = list(csv.DictReader(open(trace)))
    passes: list[list[dict]] = []  # per G34 block (line 20), the cycles in which Z moved
    for prev, row in zip(rows, rows[1:]):
        if row["line"] == "20" and prev["line"] != "20":
            passes.append([])
        if row["line"] == "20" and row["Z_cmd"] != prev["Z_cmd"]:
            passes[-1].append(row)
    assert len(passes) == 6
    for p in passes:
        # 10 turns at 600 rpm = 1.0 s (+ the stop at the end of the block), ending at 6 mm/rev = 60 mm/s
        assert float(p[-1]["t"]) - float(p[0]["t"]) == pytest.approx(1.0, abs=0.05)
        assert 55.0 < max(abs(float(r["Z_vel"])) for r in p) <= 60.5


def test_E_N11_g99_feed_per_rev_is_35_mm_per_min(hil, program, tmp_path):
    text = "M3S100 (Spindle positive rotate 100RPM)\nG99 G01 Z-20. F0.35 (Feed 0.35 mm/rev)\n"
    # the shipped lathe bench with Z starting 3 mm before the end point, so the cut takes a few seconds
    bench = tmp_path / "lathe.toml"
    bench.write_text((ROOT / "benches" / "lathe-2axis.toml").read_text().replace("start = 100.0", "start = -17.0"))
    trace = tmp_path / "t.csv"
    # G01 follows M3 at once: the feed waits for the spindle's run-up instead of alarming 0x1001
    res = hil("run", program(text), "--bench", bench, "--trace", trace)
    assert res.code == 0, res.out + res.err
    rows = [row for row in csv.DictReader(open(trace)) if row["line"] == "2"]
    assert float(rows[-1]["Z_cmd"]) == pytest.approx(-20.0)
    a, b = rows[len(rows) // 4], rows[3 * len(rows) // 4]
    feed = (float(a["Z_cmd"]) - float(b["Z_cmd"])) / (float(b["t"]) - float(a["t"])) * 60.0
    assert feed == pytest.approx(100 * 0.35, rel=1e-6)  # 100 rev/min × 0.35 mm/rev = 35 mm/min
    # 3 mm at 35 mm/min = 5.14 s, plus the start while the spindle runs up from standstill
    moving = [row for row in rows if float(row["Z_cmd"]) != -17.0]
    assert 3.0 / 35.0 * 60.0 < float(moving[-1]["t"]) - float(moving[0]["t"]) < 3.0 / 35.0 * 60.0 + 0.15
