"""Worked examples of seed-catalog §7 not pinned elsewhere, each run through `hil path --json`.

Side annotations of the listings (`// ...`, `Main program`, text after `;`) are stripped or wrapped in
`( )` as §7 explains; everything else is verbatim.
"""

from __future__ import annotations

import pytest

LA = "nc5-lathe-a"
MILL = "nc5-mill"
MOVES = ("rapid", "line", "arc", "thread", "dwell")


@pytest.fixture
def path(hil, program):
    """Run `hil path --json --profile P`; return (exit code, moves, other records)."""

    def run(text: str, profile: str = LA, *args: str):
        r = hil("path", program(text), "--json", "--profile", profile, *args)
        recs = r.json_lines()
        moves = [d for d in recs if d["kind"] in MOVES]
        return r.code, moves, [d for d in recs if d["kind"] not in MOVES]

    return run


def work(m: dict, *axes: str) -> tuple[float, ...]:
    return tuple(round(m["work"][a], 4) for a in axes)


def tagged(moves: list[dict], *tags: str) -> list[dict]:
    return [m for m in moves if all(t in m.get("tags", []) for t in tags)]


# ---------------------------------------------------------------- lathe manual


def test_e_l15_g34_variable_lead_through_g66(path):
    main = """T0101
M03 S600
G0 X50. Z5.
G66 P0034 L1
X17.65
X17.45
X17.25
X17.05
G67
G0 X50. Z5.
M5
M30
O0034
G34 Z-30. K0.5 F1
X50.
Z5.
M99
"""
    code, moves, _ = path(main)
    assert code == 0
    cuts = [m for m in tagged(moves, "G34") if m["work"]["Z"] == -30.0 and m["start"]["Z"] == 5.0]
    # four passes, one per depth block; G66 does not re-fire on the subprogram's own motion blocks
    assert [m["work"]["X"] for m in cuts] == [17.65, 17.45, 17.25, 17.05]
    assert {(m["lead"], m["lead_change"]) for m in cuts} == {(1.0, 0.5)}
    assert work(moves[-1], "X", "Z") == (50.0, 5.0)


def test_e_l22_g71_roughing_only(path):
    prog = """G54 X40.0 Z5.0
M03 S1000
G71 U2. R3.
G71 P50 Q60 U0.2 W0.0 F0.2 S1000
N50 G01 X5.0 Z0.0 F0.15 (1)
Z-5. (2)
X10. (3)
G02 X20. Z-15. R10. (4)
G01 Z-20. (5)
N60 X40. (6)
M5
M30
"""
    code, moves, _ = path(prog)
    assert code == 0
    rough = tagged(moves, "G71", "rough")
    xs = [m["work"]["X"] for m in rough]
    assert len(rough) == 9  # stock radius 17.5 at 2.0 mm a pass (Fanuc type I)
    assert all(a - b == pytest.approx(4.0) for a, b in zip(xs, xs[1:-1]))  # 2.0 mm radius depth
    assert min(xs) == pytest.approx(5.2)  # U0.2 diameter left on the X faces
    cutting = [m for m in tagged(moves, "G71") if m["kind"] != "rapid"]
    assert {m["feed"] for m in cutting} == {0.2}  # roughing feed, not the F0.15 inside P–Q
    prof = tagged(moves, "G71", "profile")
    assert [work(m, "X", "Z") for m in prof][-5:] == [(5.2, -5.0), (10.2, -5.0), (20.2, -15.0), (20.2, -20.0),
                                                      (40.2, -20.0)]
    assert not tagged(moves, "G70")  # no finishing without G70
    assert work(moves[-1], "X", "Z") == (40.0, 5.0)


# ---------------------------------------------------------------- NC5 manual


def test_e_n04_fillet(path):
    code, moves, _ = path("G91 G01 X100.0,R10. F100\nX100.0 Y100.0\n", MILL)
    assert code == 0
    assert [work(m, "X", "Y") for m in moves] == [(95.8579, 0.0), (102.9289, 2.9289), (200.0, 100.0)]
    assert moves[1]["kind"] == "arc" and moves[1]["center"]["X"] == pytest.approx(95.857864)
    assert moves[1]["center"]["Y"] == pytest.approx(10.0)


def test_e_n05_chamfer_space_before_comma(path):
    code, moves, _ = path("G91 G01 X100.0 , C10. F100\nX100.0 Y100.0\n", MILL)
    assert code == 0
    assert [work(m, "X", "Y") for m in moves] == [(90.0, 0.0), (107.0711, 7.0711), (200.0, 100.0)]


def test_e_n06_linear_angle_lathe_diameter(path):
    code, moves, _ = path("G90 G00 X50.0 Z50.0\nG01 Z100.0,A45.0 F100\n", LA)
    assert code == 0 and work(moves[-1], "X", "Z") == (150.0, 100.0)  # |dX| radius 50 = diameter 100
    code, moves, _ = path("G18 G90 G00 X50.0 Z50.0\nG01 Z100.0,A45.0 F100\n", MILL)
    assert code == 0 and work(moves[-1], "X", "Z") == (100.0, 100.0)


def test_e_n06_linear_angle_mill_g17_not_dropped(path):
    code, moves, other = path("G90 G00 X50.0 Z50.0\nG01 Z100.0,A45.0 F100\n", MILL)
    alarmed = code != 0 and any(d["kind"] == "alarm" for d in other)
    assert alarmed or (len(moves) == 2 and moves[-1]["work"]["Z"] == 100.0)
    # decided: ,A with only an out-of-plane axis is an instruction error on its own line
    assert [d["code"] for d in other if d["kind"] == "alarm"] == ["0x0207"]
    assert [d["line"] for d in other if d["kind"] == "alarm"] == [2]


def test_held_linear_angle_without_partner_alarms(path):
    code, moves, other = path("G90 G00 X50.0 Y0.\nG01 ,A30. F100\nM30\n", MILL)
    assert code == 1
    assert [(d["code"], d["line"]) for d in other if d["kind"] == "alarm"] == [("0x0207", 2)]


def test_e_n07_arc_radius_sign(path):
    for r, long_way in (("R50.0", False), ("R-50.0", True)):
        # the start is only in the figure: any start with chord <= 100 (here 60 to the left)
        code, moves, _ = path(f"G90 G00 X40.0 Y80.0\nG90 G03 X100.0 Y80.0 {r} F80\n", MILL)
        assert code == 0 and work(moves[1], "X", "Y") == (100.0, 80.0)
        c = moves[1]["center"]
        assert ((c["X"] - 100.0) ** 2 + (c["Y"] - 80.0) ** 2) ** 0.5 == pytest.approx(50.0)
        # G03 from (40,80) to (100,80): the <=180° arc has its centre left of the chord direction (+X), i.e. above
        cross = 60.0 * (c["Y"] - 80.0)
        assert (cross < 0) == long_way
    assert path("G90 G03 X100.0 Y80.0 R50.0 F80\n", MILL)[0] == 1  # chord 128 > 2R: alarm


def test_e_n09_combination_arcs(path):
    prog = """G90 G54 X0 Y0 S500 M3 (Original point)
G90 G01 Y15.0 F80 (A point)
G02 X41.0 Y40.0 R41.0 (B point)
G91 G01 X40.0 (C point)
G02 X10.0 Y-10.0 R10.0 (D point)
G01 Y-20.0 (E point)
X-15.0 Y-10.0 (F point)
X-20. (G point)
G90 G03 X20.0 R18.0 (H point)
G01 X0.0 (Original point)
"""
    code, moves, _ = path(prog, MILL)
    assert code == 0
    assert [work(m, "X", "Y") for m in moves[1:]] == [(0, 15), (41, 40), (81, 40), (91, 30), (91, 10), (76, 0),
                                                      (56, 0), (20, 0), (0, 0)]
    centres = [(round(m["center"]["X"], 3), round(m["center"]["Y"], 3)) for m in moves if m["kind"] == "arc"]
    assert centres == [(37.802, -0.875), (81.0, 30.0), (38.0, 0.0)]


def test_e_n10_polar_drilling(path):
    prog = "G90 G16 (Enable polar coordinate)\nG81X100.0Y30.0Z-20.0R-5.0F200.0\nX100.0Y150.0\nX100.0Y270.0\n" \
           "G15G80 (Cancel polar coordinate)\nM30\n"
    code, moves, _ = path(prog, MILL)
    assert code == 0
    cuts = tagged(moves, "G81", "cut")
    assert [work(m, "X", "Y", "Z") for m in cuts] == [(86.6025, 50.0, -20.0), (-86.6025, 50.0, -20.0),
                                                      (0.0, -100.0, -20.0)]
    assert {m["feed"] for m in cuts} == {200.0}
    assert {m["work"]["Z"] for m in tagged(moves, "G81", "approach")} == {-5.0}


def test_e_n33_if_then(path):
    code, _, other = path("#1=1\nIF[#1==1]THEN\n#100 = 0\nENDIF\n", MILL, "--vars", "100")
    assert code == 0 and other[-1]["values"] == {"100": 0.0}
    code, _, other = path("IF[#1==1]THEN\n#100 = 0\nENDIF\n", MILL, "--vars", "100")
    assert code == 0 and other[-1]["values"] == {"100": None}  # #1 vacant: the THEN block does not run


def test_e_n44_mirror(path):
    prog = ("N00G00G90G40G49\nN01G55X0Y0\nN02G01X5.Y10.F1000\nN03X35.Y10.\nN04X5.Y70.\nN05X5.Y10.\nN06G00X0Y0\n"
            "N07G24X0\nN08G01X5.Y10.F1000\nN09X35.Y10.\nN10X5.Y70.\nN11X5.Y10.\nN12G00X0Y0\nN13G25X0\n"
            "N14G01X5.Y10.\nN99M30\n")
    code, moves, _ = path(prog, MILL)
    assert code == 0
    ends = [(m["end"]["X"], m["end"]["Y"]) for m in moves]
    assert ends[1:5] == [(5, 10), (35, 10), (5, 70), (5, 10)]
    assert ends[6:10] == [(-5, 10), (-35, 10), (-5, 70), (-5, 10)]  # mirrored about X = 0
    assert ends[-1] == (5, 10)  # N13 G25 cancels the mirror (N14 added to show it)


def test_e_n45_rotation(path):
    code, moves, _ = path("O1000\nG00 G90 G55 X0 Y0\nG68 X0 Y0 R90.0\nG00 X100.0 Y50.0\nX0.0 Y0.0\nM30\n", MILL)
    assert code == 0
    assert [(m["end"]["X"], m["end"]["Y"]) for m in moves] == [(0, 0), (-50, 100), (0, 0)]
    assert work(moves[1], "X", "Y") == (100.0, 50.0)


def test_e_n46_g73_mill_peck(path):
    prog = """M03S1000
G17 G90 G00 G54 X0. Y0.
G00 Z100.
G99 G73 X0. Y0. Z-30. R10. Q4. K1 F100. (1)
X-15. (2)
X-30. (3)
X-30. Y15. (4)
G80
G91 G28 X0. Y0. Z0.
M05
M30
"""
    code, moves, _ = path(prog, MILL)
    assert code == 0
    pecks = tagged(moves, "G73", "peck")
    holes = sorted({(m["work"]["X"], m["work"]["Y"]) for m in pecks})
    assert holes == [(-30.0, 0.0), (-30.0, 15.0), (-15.0, 0.0), (0.0, 0.0)]
    assert len(pecks) == 40  # 40 mm from R10 to Z-30 at Q4: 10 pecks a hole
    assert min(m["work"]["Z"] for m in pecks) == -30.0 and {m["feed"] for m in pecks} == {100.0}
    assert {m["work"]["Z"] for m in tagged(moves, "G73", "return")} == {10.0}  # G99: back to R between holes
    assert [m["end"] for m in moves[-1:]] == [{"X": 0.0, "Y": 0.0, "Z": 0.0}]  # G91 G28 X0 Y0 Z0: reference


def test_e_l29_g92_threading_o0010(path):
    # `; comment` annotations of the listing stripped
    prog = ("O0010\nT0202\nM03 S2000\nG0 Z5.\nX30.\nG92 X17.65 Z-25.0 F1.5\nX17.45\nX17.25\nX17.05\nX16.85\n"
            "X16.65\nX16.45\nX16.25\nX16.05\nX15.9\nM5\nG0X50.\nZ10.\nM30\n")
    code, moves, _ = path(prog)
    assert code == 0
    body = [m for m in tagged(moves, "G92", "thread") if "chamfer" not in m["tags"]]
    assert [m["work"]["X"] for m in body] == [17.65, 17.45, 17.25, 17.05, 16.85, 16.65, 16.45, 16.25, 16.05, 15.9]
    assert {m["lead"] for m in body} == {1.5}
    chamfers = tagged(moves, "G92", "chamfer")
    assert len(chamfers) == 10 and {m["work"]["Z"] for m in chamfers} == {-25.0}
    assert {work(m, "X", "Z") for m in tagged(moves, "G92", "return")} == {(30.0, 5.0)}
    assert len(tagged(moves, "G92", "approach")) == 10  # `M5` alone does not repeat the cycle
    assert [work(m, "X", "Z") for m in moves[-2:]] == [(50.0, 5.0), (50.0, 10.0)]  # G0X50. cancels G92
