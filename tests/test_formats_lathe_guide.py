"""Format rows of the older lathe guide (profile lathe-2018, type A unless a row needs B): chapter 2 "Format:"
lines and the alternatives written under them, chapter 3's M codes. Each is written as the guide writes it
and checked for what its description promises. Rows with a Y/V word run on a lathe with a Y axis (the
interpreter driven directly, as `hil path` does). Row ids as in docs/formats.md (`L<section>-<k>`).
"""

from __future__ import annotations

import dataclasses

import pytest

from lang_helpers import PathResult, run_path

LATHE = "lathe-2018"


def _ok(r: PathResult) -> PathResult:
    assert r.code == 0, r.alarm
    return r


def _run(capsys, tmp_path, prog: str, *args: str) -> PathResult:
    return _ok(run_path(capsys, tmp_path, prog, *args, profile=LATHE))


def _events(prog: str, axes: str = "XZ", **params: float):
    """Every event of the interpreter on lathe-2018 with these axes, and the interpreter."""
    from nc.interp import Interpreter
    from nc.profiles import make_profile
    from nc.program import parse_program

    ip = Interpreter(make_profile(LATHE, axes=tuple(axes), params=dict(params) or None))
    return list(ip.run(parse_program(prog))), ip


def _moves(prog: str, axes: str = "XYZ") -> list:
    from nc.moves import Move

    return [e for e in _events(prog, axes)[0] if isinstance(e, Move)]


def _r(v: float) -> float:
    return round(v, 6) + 0.0


def _pt(d: dict, axes: str) -> tuple[float, ...]:
    return tuple(_r(d[a]) for a in axes)


# ---- L§2.1 motion

def test_arcs_in_the_three_planes_with_r_or_centre_words():
    """L2.1-3 `G17 G02 (G03) X/U_ Y/V_ R_ F_ or`, L2.1-4 `G17 G02 (G03) X/U_ Y/V_ I_ J_ F_`, L2.1-5
    `G18 G02 (G03) Z/W_ X/U_ R_ F_ or`, L2.1-6 `G18 G02 (G03) Z/W_ X/U_ K_ I_ F_`, L2.1-7
    `G19 G02 (G03) Y/V_ Z/W_ R_ F_ or`, L2.1-8 `G19 G02 (G03) Y/V_ Z/W_ J_ K_ F_` (L§2.1 G02/G03): each
    plane, CW and CCW, absolute and U/V/W, radius or centre; X a diameter, I a radius value."""
    prog = ("G00 X0 Y0 Z0\n"
            "G17 G02 X20. Y10. R10. F100\nG17 G03 U-20. V-10. R10.\nG17 G02 X20. Y10. I10. J0\nG17 G03 U-20. V-10. I0 J-10.\n"
            "G18 G02 Z-10. X20. R10.\nG18 G03 W10. U-20. R10.\nG18 G02 Z-10. X20. K0 I10.\nG18 G03 W10. U-20. K10. I0\n"
            "G19 G02 Y10. Z-10. R10.\nG19 G03 V-10. W10. R10.\nG19 G02 Y10. Z-10. J0 K-10.\nG19 G03 V-10. W10. J-10. K0\n"
            "M30\n")
    arcs = _moves(prog)[1:]
    assert [m.kind for m in arcs] == ["arc"] * 12 and [m.dir for m in arcs] == ["cw", "ccw"] * 6
    assert [_pt(m.end, "XYZ") for m in arcs] == [(10.0, 10.0, 0.0), (0.0, 0.0, 0.0)] * 2 + [
        (10.0, 0.0, -10.0), (0.0, 0.0, 0.0)] * 2 + [(0.0, 10.0, -10.0), (0.0, 0.0, 0.0)] * 2
    assert [_pt(m.center, "XYZ") for m in arcs[::2]] == [(10.0, 0.0, 0.0)] * 2 + [(10.0, 0.0, 0.0)] * 2 + [
        (0.0, 0.0, -10.0)] * 2
    assert arcs[0].feed == 100.0 and arcs[-1].feed == 100.0


@pytest.mark.parametrize("plane,prog,arc_plane,centre", [
    # machine X is a radius (X20. = 10): each arc is a quarter circle of radius 10 there and back
    ("G17", "G17 G01 X20. Y0 F100\nG02 X0 Y10. R10.\nG03 X20. Y0 I10. J0", ("X", "Y"), (10.0, 10.0, 0.0)),
    ("G18", "G18 G01 Z0 X20. F100\nG02 Z-10. X0 R10.\nG03 Z0 X20. K10. I0", ("Z", "X"), (10.0, 0.0, -10.0)),
    ("G19", "G19 G01 Y10. Z0 F100\nG02 Y0 Z-10. R10.\nG03 Y10. Z0 J0 K10.", ("Y", "Z"), (10.0, 0.0, 0.0)),
])
def test_plane_designation_g17_g18_g19(plane, prog, arc_plane, centre):
    """L2.1-22 `X - Y plane: G17 {G01 - G03} X_ Y_{I_ J_ or R_}F_`, L2.1-23
    `Z - X plane: G18 {G01 - G03} Z_ X_{K_ I_ or R_}F_`, L2.1-24 `Y - Z plane: G19 {G01 - G03} Y_ Z_{J_ K_ or R_}F_`
    (L§2.1 G17/G18/G19): the plane decides where G02/G03 turn and which centre words (or R) they take;
    G01 is the same straight line in every plane."""
    m = _moves(f"G00 X20. Y0 Z0\n{prog}\nM30\n")
    assert [x.kind for x in m[1:]] == ["line", "arc", "arc"] and [x.dir for x in m[2:]] == ["cw", "ccw"]
    assert {x.plane for x in m[2:]} == {arc_plane}
    assert _pt(m[2].center, "XYZ") == centre and _pt(m[3].end, "XYZ") == _pt(m[1].end, "XYZ")


def test_g04_x_seconds_or_p_milliseconds(capsys, tmp_path):
    """L2.1-9 `G04 X_ or`, L2.1-10 `G04 P_` (L§2.1 G04: X in s with decimals, P in 0.001 s)."""
    r = _run(capsys, tmp_path, "G00 X10.\nG04 X1.5\nG04 P2500\nM30\n")
    assert [(m["kind"], m["duration"]) for m in r.moves[1:]] == [("dwell", 1.5), ("dwell", 2.5)]


def test_g09_exact_stop_on_one_block():
    """L2.1-11 `G09 G01 X_ Y_` (L§2.1 G09): that block ends in an exact stop, the next does not."""
    m = _moves("G00 X0 Y0\nG09 G01 X10. Y5. F100\nG01 X20.\nM30\n")
    assert [(_pt(x.end, "XY"), x.exact_stop) for x in m[1:]] == [((5.0, 5.0), True), ((10.0, 5.0), False)]


# ---- L§2.1 G10 / G11 data setting

def test_g10_l2_l10_l11_l20_l21_data_setting():
    """L2.1-12 `G10 L2 P_ X_ Y_ Z_`, L2.1-13 `G10 L10 P_ X/U_ Y/V_ Z/W_ R_ Q_`, L2.1-14
    `G10 L11 P_ X/U_ Y/V_ Z/W_ R_ Q_`, L2.1-15 `G10 L20 P_ X_ Y_ Z_`, L2.1-16 `G10 L21 P_ X_ Y_ Z_`
    (L§2.1 G10 items 1-5): work offset P0-P6, tool length / wear (U V W add), nose radius R and tip Q,
    extended work offset P1-P64, software limits P1-P4."""
    ev, ip = _events("G10 L2 P1 X10. Y2. Z-5.\nG10 L10 P3 X1. Y0.5 Z2. R0.4 Q3\nG10 L10 P3 U1. W-1.\n"
                     "G10 L11 P3 X0.1 Y0 Z0.2 R0.02 Q3\nG10 L20 P64 X4. Y1. Z-2.\nG10 L21 P1 X100. Y50. Z20.\n"
                     "G10 L21 P2 X-1. Y-50. Z-300.\nM30\n", "XYZ")
    t, fr = ip.tools, ip.frames
    assert fr.work_offsets[0] == {"X": 5.0, "Y": 2.0, "Z": -5.0}  # X a diameter: 10 -> 5 radius
    assert (t.lengths[("X", 3)], t.lengths[("Y", 3)], t.lengths[("Z", 3)]) == (2.0, 0.5, 1.0)
    assert (t.wears[("X", 3)], t.wears[("Z", 3)], t.radius[3], t.radius_wear[3], t.tip[3]) == (0.1, 0.2, 0.4, 0.02, 3)
    assert fr.work_offsets[5 + 64] == {"X": 2.0, "Y": 1.0, "Z": -2.0}
    p = ip.profile.params
    assert (p["soft limit 1 X"], p["soft limit 1 Z"], p["soft limit 2 Z"]) == (100.0, 20.0, -300.0)


def test_g10_l30_l1100_l3100_l4100_and_g11():
    """L2.1-17 `G10 L30 P_`, L2.1-18 `G10 L1100 R_ S_`, L2.1-19 `G10 L3100 P_`, L2.1-20 `G10 L4100 P_`,
    L2.1-21 `G11;` (L§2.1 G10 items 6-8): spindle positioning offset P in 0.01 degree (G11 L30 back to
    Pr405); R the maximum and S the current spindle speed (one S to the spindle); M2080-M2111 set / cleared
    without stopping the motion."""
    from nc.moves import Aux

    ev, ip = _events("G10 L30 P1050\n#100=0\nG10 L1100 R3000 S1200\nG10 L3100 P2081\n#101=#1865\n"
                     "G10 L4100 P2081\n#102=#1865\nM30\n", P405=20.0)
    assert ip.profile.params["spindle positioning offset"] == 10.5
    assert [(e.kind, e.value) for e in ev if isinstance(e, Aux) and e.kind == "S"] == [("S", 1200.0)]
    assert ip.state.spindle_max == 3000.0
    assert (ip.vars.get(101), ip.vars.get(102)) == (1.0, 0.0)
    _ev, ip = _events("G10 L30 P1050\nG11 L30\nM30\n", P405=20.0)
    assert ip.profile.params["spindle positioning offset"] == 20.0


def test_g21_or_g20_units(capsys, tmp_path):
    """L2.1-25 `G21 or G20` (L§2.1 G21/G20): G20 inch, G21 mm, for linear axes (set at the program's start:
    a change after motion is an alarm, docs/decisions/language.md)."""
    inch = _run(capsys, tmp_path, "G20\nG00 X1. Z-0.5\nM30\n")
    mm = _run(capsys, tmp_path, "G21\nG00 X1. Z-0.5\nM30\n")
    assert (inch.ends("X", "Z"), mm.ends("X", "Z")) == ([(25.4, -12.7)], [(1.0, -0.5)])


@pytest.mark.parametrize("g28,g29", [("G28 X50. Y5. Z20.", "G29 X30. Y0 Z5."),
                                     ("G28 U10. V5. W10.", "G29 U-20. V-5. W-15.")])
def test_g28_g29_through_the_intermediate_point(g28, g29):
    """L2.1-26 `G28 X_ Y_ Z_ or`, L2.1-27 `G28 U_ V_ W_`, L2.1-28 `G29 X_ Y_ Z_ or`, L2.1-29 `G29 U_ V_ W_`
    (L§2.1 G28/G29): G28 through the intermediate point to the machine origin; G29 back through the same
    point to the target (U V W from the intermediate point)."""
    m = _moves(f"G00 X40. Y0 Z10.\n{g28}\n{g29}\nM30\n")
    assert [_pt(x.work, "XYZ") for x in m[1:]] == [(50.0, 5.0, 20.0), (0.0, 0.0, 0.0), (50.0, 5.0, 20.0),
                                                   (30.0, 0.0, 5.0)]


@pytest.mark.parametrize("p", [2, 3, 4])
def test_g30_p2_p3_p4(p):
    """L2.1-30 `G30 P2 X_ Y_ Z_ or`, L2.1-31 `G30 P3 X_ Y_ Z_ or`, L2.1-32 `G30 P4 X_ Y_ Z_` (L§2.1 G30):
    through the intermediate point to the 2nd/3rd/4th reference point."""
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.program import parse_program

    ref = {f"N2.06{p - 1} X": 100.0, f"N2.06{p - 1} Y": 7.0, f"N2.06{p - 1} Z": 200.0}
    ip = Interpreter(make_profile(LATHE, axes=("X", "Y", "Z"), params=ref))
    m = [e for e in ip.run(parse_program(f"G00 X40. Y0 Z10.\nG30 P{p} X50. Y5. Z20.\nM30\n")) if isinstance(e, Move)]
    assert [_pt(x.end, "XYZ") for x in m[1:]] == [(25.0, 5.0, 20.0), (100.0, 7.0, 200.0)]


def test_g31_skip():
    """L2.1-33 `G31 X_Y_Z_F_P_` (L§2.1 G31): a feed move at F toward the point, ended by the skip signal
    (offline: at the end point); its position latched."""
    m = _moves("G00 X0 Y0 Z0\nG31 X10.Y2.Z-5.F100P0\nM30\n")
    assert m[-1].kind == "line" and m[-1].feed == 100.0 and _pt(m[-1].work, "XYZ") == (10.0, 2.0, -5.0)


@pytest.mark.parametrize("block", ["G32 X30. Z-20. F1.5 Q90000", "G32 U0 W-25. F1.5 Q90000"])
def test_g32_thread(capsys, tmp_path, block):
    """L2.1-34 `G32 X/U_ Z/W_ F_ Q_` (L§2.1 G32): one thread move at lead F from spindle angle Q (0.001°)."""
    r = _run(capsys, tmp_path, f"G00 X30. Z5.\nM03 S500\n{block}\nM30\n")
    th = r.moves[-1]
    assert (th["kind"], th["lead"], th["start_angle"], r.ends("X", "Z")[-1]) == ("thread", 1.5, 90.0, (30.0, -20.0))


@pytest.mark.parametrize("block", ["G34 X40. Z-20. F2. K0.1", "G34 U0 W-25. F2. K-0.05"])
def test_g34_variable_lead(capsys, tmp_path, block):
    """L2.1-35 `G34 X/U_ Z/W_ F_ K±` (L§2.1 G34): lead F changing by ±K per turn."""
    r = _run(capsys, tmp_path, f"G00 X40. Z5.\nM03 S500\n{block}\nM30\n")
    th = r.moves[-1]
    assert (th["kind"], th["lead"]) == ("thread", 2.0) and th["lead_change"] in (0.1, -0.05)
    assert r.ends("X", "Z")[-1] == (40.0, -20.0)


def test_g40_g41_g42_tool_nose_compensation(capsys, tmp_path):
    """L2.1-36 `G40`, L2.1-37 `G00 G41 P_ or`, L2.1-38 `G00 G42 P_` (L§2.1 G40-G42; "P_: coordinates of
    the target point", so P_ stands for the X/Z words): the nose centre runs left / right of the path by
    the nose radius of the T offset; G40 ends on the programmed point."""
    prog = ("G10 L10 P1 X0 Z0 R0.8 Q3\nT0101\nG00 X20. Z5.\nG00 {g} X20. Z2.\nG01 Z-20. F0.2\nG40 G00 X40. Z5.\nM30\n")
    right = _run(capsys, tmp_path, prog.format(g="G42"))
    left = _run(capsys, tmp_path, prog.format(g="G41"))
    rx = [(round(m["end"]["X"], 4), round(m["end"]["Z"], 4)) for m in right.moves if m.get("comp") == "G42"]
    lx = [(round(m["end"]["X"], 4), round(m["end"]["Z"], 4)) for m in left.moves if m.get("comp") == "G41"]
    assert all(m.get("comp_radius") == 0.8 for m in right.moves + left.moves if m.get("comp"))
    # tip 3 on an outside cut: G42 keeps the imaginary tip on the path (X radius 10), the cut ending R early
    # in Z; G41 puts the nose on the other side of the path, 2R lower in X
    assert rx == [(10.0, 1.2), (10.0, -20.8)] and lx == [(8.4, 1.2), (8.4, -20.8)]
    assert right.moves[-1]["work"] == {"X": 40.0, "Z": 5.0} and not right.moves[-1].get("comp")


def test_g52_g53_g54_to_g59_coordinates():
    """L2.1-39 `G52 X_ Y_ Z_`, L2.1-40 `G53 X_ Y_ Z_`, L2.1-41 `G54 X_ Y_ Z_ or`, L2.1-42 `G55 …`, L2.1-43 `G56 …`, L2.1-44 `G57 …`, L2.1-45 `G58 …`,
    L2.1-46 `G59 X_ Y_ Z_`
    (L§2.1): G52 shifts the local origin, G53 moves in machine coordinates for one block, G54-G59 select
    the work system and move in it in the same block."""
    offs = "".join(f"G10 L2 P{k} X{2 * k}. Y{k}. Z-{k}.\n" for k in range(1, 7))
    codes = "".join(f"G{53 + k} X1. Y1. Z1.\n" for k in range(1, 7))
    m = _moves(offs + codes + "G54\nG52 X2. Y0 Z-3.\nG00 X1. Y1. Z1.\nG53 X8. Y3. Z-9.\nM30\n")
    assert [_pt(x.end, "XYZ") for x in m[:6]] == [(k + 0.5, k + 1.0, 1.0 - k) for k in range(1, 7)]
    assert _pt(m[6].end, "XYZ") == (2.5, 2.0, -3.0)  # G54 (1, 1, -1) + local (1, 0, -3) + point (0.5, 1, 1)
    assert _pt(m[7].end, "XYZ") == (4.0, 3.0, -9.0) and m[7].exact_stop  # G53 X8. (diameter) = 4 radius


def test_g61_exact_stop_mode_and_g64_cutting_mode():
    """L2.1-47 `G61`, L2.1-48 `G64` (L§2.1): under G61 every move ends in an exact stop until G64."""
    m = _moves("G00 X0 Z0\nG61\nG01 X10. F100\nX20.\nG64\nX30.\nM30\n", "XZ")
    assert [x.exact_stop for x in m[1:]] == [True, True, False]


SUB = "O9010\n#100=#100+#9\n#101=#101+1\n#9=#9+100.\nM99\n"


def test_g65_g66_g67_macro_calls(capsys, tmp_path):
    """L2.1-49 `G65 P_ L_ I_`, L2.1-50 `G66 P_ L_ I_ or`, L2.1-51 `G67` (L§2.1): G65 calls P L times with
    argument I (#9 in this guide's argument table), fresh on each repetition, G66 after every moving block until G67."""
    r = _run(capsys, tmp_path, "#100=0\n#101=0\nG65 P9010 L2 I1.5\nG66 P9010 L1 I1.\nG00 X10.\nZ-1.\nG67\nX20.\nM30\n"
             + SUB, "--vars", "100-101")
    assert (r.vars["100"], r.vars["101"]) == (5.0, 4.0) and r.ends("X")[-1] == (20.0,)


# ---- L§2.1 turning cycles

CONTOUR = "N100 G00 X20.\nG01 Z-20. F0.1\nX40.\nN200 Z-40.\n"


def test_g71_g70_rough_and_finish(capsys, tmp_path):
    """L2.1-52 `G71 U u R e ;`, L2.1-53 `G71 P p Q q U u W w F f S s T t ;`, L2.1-58 `G70 P_ Q_;` (L§2.1):
    depth u (radius) per pass, retract e; allowances u (diameter) and w; feed f; then G70 along P-Q."""
    r = _run(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\nG71 U2. R0.5\nG71 P100 Q200 U0.4 W0.1 F0.25 S600 T0101\n"
             + CONTOUR + "G70 P100 Q200\nM30\n", "--vars", "2023,2024")
    rough = [m for m in r.moves if (m.get("tags") or [""])[:2] == ["G71", "rough"]]
    assert [round(m["work"]["X"], 4) for m in rough][:2] == [56.0, 52.0] and rough[-1]["work"]["X"] == 20.4
    assert {m["feed"] for m in rough} == {0.25} and r.vars == {"2023": 101.0, "2024": 600.0}
    fin = [m for m in r.moves if (m.get("tags") or [""])[0] == "G70" and m["kind"] != "rapid"]
    assert [(m["work"]["X"], m["work"]["Z"]) for m in fin] == [(20.0, -20.0), (40.0, -20.0), (40.0, -40.0)]


def test_g72_facing(capsys, tmp_path):
    """L2.1-54 `G72 Wd Re;`, L2.1-55 `G72 P_Q Uu Ww F_S T_;` (L§2.1): depth d along Z, retract e."""
    r = _run(capsys, tmp_path, "G00 X82. Z2.\nM03 S500\nG72 W2. R0.5\nG72 P100 Q200 U0.4 W0.2 F0.25 S600 T0101\n"
             "N100 G00 Z-6.\nG01 X40. F0.1\nN200 Z0\nM30\n")
    rough = [m for m in r.moves if (m.get("tags") or [""])[:2] == ["G72", "rough"]]
    assert [(m["work"]["X"], m["work"]["Z"]) for m in rough] == [(40.4, 0.0), (40.4, -2.0), (40.4, -4.0), (40.4, -5.8)]


def test_g73_pattern_repeat(capsys, tmp_path):
    """L2.1-56 `G73 U_i W_k R_d;`, L2.1-57 `G73 P_ Q_ U_u W_w F_ S_ T_;` (L§2.1): d passes, the first offset
    by i (X, radius) and k (Z)."""
    r = _run(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\nG73 U4. W2. R3\nG73 P100 Q200 U0.4 W0.1 F0.25 S600 T0101\n"
             "N100 G00 X20. Z2.\nG01 Z-20. F0.1\nN200 X50.\nM30\n")
    firsts = [m for m in r.moves if (m.get("tags") or [""])[:2] == ["G73", "pass"] and m["kind"] == "rapid"]
    assert [(round(m["work"]["X"], 4), round(m["work"]["Z"], 4)) for m in firsts] == [(28.4, 4.1), (24.4, 3.1),
                                                                                       (20.4, 2.1)]


def test_g74_g75_pecking(capsys, tmp_path):
    """L2.1-59 `G74 Re;`, L2.1-60 `G74 X/U_ Z/W_ PΔi QΔk RΔd F_;`, L2.1-61 `G75 R e ;`, L2.1-62
    `G75 X/U_ Z/W_ P Δ i Q Δ K R Δ d F_;` (L§2.1): G74 pecks Δk along Z and shifts Δi in X; G75 pecks Δi
    along X and shifts Δk in Z; each peck backs off e."""
    r = _run(capsys, tmp_path, "G00 X0 Z5.\nG74 R1.\nG74 U20. W-15. P5000 Q3000 R0 F0.1\nG00 X60. Z-10.\nG75 R1.\n"
             "G75 X40. Z-16. P3000 Q3000 R0 F0.1\nM30\n")
    p74 = [m for m in r.moves if (m.get("tags") or [""])[:2] == ["G74", "peck"]]
    p75 = [m for m in r.moves if (m.get("tags") or [""])[:2] == ["G75", "peck"]]
    assert [m["work"]["Z"] for m in p74[:5]] == [2.0, -1.0, -4.0, -7.0, -10.0]
    assert sorted({m["work"]["X"] for m in p74}) == [0.0, 10.0, 20.0]
    assert [m["work"]["X"] for m in p75[:4]] == [54.0, 48.0, 42.0, 40.0]
    assert sorted({m["work"]["Z"] for m in p75}) == [-16.0, -13.0, -10.0]


def test_g76_thread_cycle(capsys, tmp_path):
    """L2.1-63 `G76 Pmra Q Δ dmin R d;`, L2.1-64 `G76 X/U Z/W R i P k Q Δ d F;` (L§2.1): m finish passes,
    least depth Δdmin, allowance d; taper i, height k, first depth Δd, lead F."""
    r = _run(capsys, tmp_path, "G00 X40. Z5.\nM03 S500\nG76 P021060 Q50 R0.05\nG76 X28. Z-20. R0 P975 Q400 F1.5\nM30\n")
    th = [m for m in r.moves if m["kind"] == "thread" and "chamfer" not in m["tags"]]
    assert round(th[0]["work"]["X"], 4) == 29.15 and [m["work"]["X"] for m in th[-2:]] == [28.0, 28.0]
    assert {m["lead"] for m in th} == {1.5}


@pytest.mark.parametrize("block,path", [
    ("G90 X50. Z-30. R-5. F0.2", [(40.0, 5.0), (50.0, -30.0), (60.0, -30.0), (60.0, 5.0)]),
    ("G90 U-10. W-35. R-5. F0.2", [(40.0, 5.0), (50.0, -30.0), (60.0, -30.0), (60.0, 5.0)]),
    ("G94 X20. Z-3. R-2. F0.2", [(60.0, -5.0), (20.0, -3.0), (20.0, 5.0), (60.0, 5.0)]),
    ("G94 U-40. W-8. R-2. F0.2", [(60.0, -5.0), (20.0, -3.0), (20.0, 5.0), (60.0, 5.0)]),
])
def test_g90_g94_single_cycles(capsys, tmp_path, block, path):
    """L2.1-65 `G90 X/U_ Z/W_ R_ F_;`, L2.1-66 `G94 X/U_ Z/W_ R_ F_;` (L§2.1, type A): the four moves of
    the turning / facing cycle with taper R."""
    r = _run(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\n" + block + "\nM30\n")
    assert [(round(m["work"]["X"], 4), round(m["work"]["Z"], 4)) for m in r.moves[1:]] == path


# ---- L§2.1 hole cycles

C_AXES = "XZC"


def _holes(prog: str) -> list:
    return _moves(prog, C_AXES)


def test_g80_cancels():
    """L2.1-67 `G80;` (L§2.1): an axis word after G80 is a plain move."""
    m = _holes("G00 X30. Z5. C0\nG83 X0 C0 Z-4. R-2. F0.1\nG80;\nG00 X40. Z10.\nM30\n")
    assert not m[-1].tags and _pt(m[-1].work, "XZ") == (40.0, 10.0)


@pytest.mark.parametrize("code,block,axis,bottom", [
    ("G83", "G83 X0 C45. Z-10. R-2. Q3000 P200 F0.1 K1 L1", "Z", -10.0),  # L2.1-68
    ("G84", "G84 X20. C45. Z-10. R-2. Q0 P200 F1.5 K1 L0", "Z", -10.0),  # L2.1-69
    ("G85", "G85 X20. C45. Z-8. R-2. P200 F0.1 K1", "Z", -8.0),  # L2.1-70
    ("G87", "G87 Z-10. C45. X20. R-2. Q3000 P200 F0.1 K1 L1", "X", 20.0),  # L2.1-71
    ("G88", "G88 Z-10. C45. X20. R-2. Q0 P200 F1.5 K1 L0", "X", 20.0),  # L2.1-72
    ("G89", "G89 Z-10. C45. X20. R-2. P200 F0.1 K1", "X", 20.0),  # L2.1-73 (the guide writes it G85)
])
def test_face_and_side_hole_cycles(code, block, axis, bottom):
    """L2.1-68 `G83 X(U)_C_Z(W)_R_Q_P_F_K_L_M_;`, L2.1-69 `G84 X(U)_ C_ Z(W)_ R_ Q_ P_ F_ K_ L_ M_;`, L2.1-70
    `G85 X(U)_ C_ Z(W)_ R_ P_ F_ K_ M_;`, L2.1-71 `G87 Z(W)_ C_ X(U)_ R_ Q_ P_ F_ K_L_M_;`, L2.1-72
    `G88 Z(W)_ C_ X(U)_ R_ Q_ P_ F_ K_L_M_;`, L2.1-73 `G85 Z(W)_ C_ X(U)_ R_ P_ F_ K_ M_;` (the side boring
    cycle G89, L§2.1): positioned at C45 and the other axis, to the bottom along Z (face) or X (side),
    dwell P ms there; the M_ word is in test_hole_cycle_m_word_clamps_and_unclamps_c."""
    m = _holes(f"G00 X60. Z5. C0\nM03 S500\n{block}\nG80\nM30\n")
    cyc = [x for x in m if x.tags and x.tags[0] == code]
    assert {x.work["C"] for x in cyc} == {45.0}
    assert any(_r(x.work[axis]) == bottom for x in cyc if x.kind in ("line", "dwell"))
    assert [x.duration for x in cyc if x.kind == "dwell"] == [0.2]


@pytest.mark.parametrize("block,code", [
    ("G83 X0 C90. Z-10. R-2. Q3000 P200 F0.1 K1 L1 M80", "G83"),  # L2.1-68
    ("G84 X20. C45. Z-10. R-2. Q0 P200 F1.5 K1 L0 M80", "G84"),  # L2.1-69
    ("G85 X20. C45. Z-8. R-2. P200 F0.1 K1 M80", "G85"),  # L2.1-70
    ("G87 Z-10. C45. X20. R-2. Q3000 P200 F0.1 K1 L1 M80", "G87"),  # L2.1-71
    ("G89 Z-10. C45. X20. R-2. P200 F0.1 K1 M80", "G89"),  # L2.1-73
])
def test_hole_cycle_m_word_clamps_and_unclamps_c(block, code):
    """The `M_` of L2.1-68 … L2.1-73 (L§2.1 G83-G89: "when the tool moves to the start point, the system
    executes the M-code (e.g., M80: C-axis clamping). Then, when the tool completes drilling and retracts
    to point R and before pausing at the top of the hole, the system executes M + 1 code"): M80 after the
    positioning move and before the drill axis moves, M81 with the tool back at R, and no M80 at the
    block's end as an ordinary M code."""
    from nc.moves import Aux, Move

    ev, _ip = _events(f"G00 X60. Z5. C0\nM03 S500\n{block}\nG80\nM30\n", C_AXES)
    seq = [e for e in ev if (isinstance(e, Aux) and e.kind == "M" and e.value in (80, 81))
           or (isinstance(e, Move) and e.tags[:1] == (code,))]
    kinds = [e.value if isinstance(e, Aux) else e.tags[1] for e in seq]
    assert kinds.count(80) == 1 and kinds.count(81) == 1
    assert kinds[0] == "position" and kinds[1] == 80 and kinds[-1] in ("return", 81)
    axis = "Z" if code in ("G83", "G84", "G85") else "X"
    before_81 = [e for e in seq[:kinds.index(81)] if isinstance(e, Move)][-1]
    r_level = 3.0 if axis == "Z" else 56.0
    assert _r(before_81.work[axis]) == r_level  # back at R when M81 goes out


# ---- L§2.1 modes and settings

def test_g90_g91_absolute_incremental_on_type_b(capsys, tmp_path):
    """L2.1-74 `G90 X_ Y_ Z_`, L2.1-75 `G91 X_ Y_ Z_` (L§2.1, note 1-2: type B; the guide's example)."""
    r = _run(capsys, tmp_path, "G90 G00 X30. Z30.\nG91 X20. Z20.\nG90 U20. W20.\nG91 U20. W20.\nM30\n",
             "--param", "P306=1")
    assert r.ends("X", "Z") == [(30.0, 30.0), (50.0, 50.0), (70.0, 70.0), (90.0, 90.0)]


def test_g50_coordinate_setting_and_maximum_spindle_speed():
    """L2.1-76 `G50 X_ Y_ Z_ (coordinate system setting)`, L2.1-77 `G50 S_ (maximum spindle speed)`
    (L§2.1 G50 and its example): G50 X Z makes the current point that coordinate; G50 S clamps the spindle."""
    from nc.moves import Aux, Move

    ev, ip = _events("M3 S1500\nG0 G54 X0. Z0.\nG0 X10.\nG50 S1000\nG50 X0. Z0.\nG1 W-20. F0.25\nU10.\nM30\n")
    mv = [e for e in ev if isinstance(e, Move)]
    assert [_pt(x.end, "XZ") for x in mv[-2:]] == [(5.0, -20.0), (10.0, -20.0)]  # machine X radius
    assert [_pt(x.work, "XZ") for x in mv[-2:]] == [(0.0, -20.0), (10.0, -20.0)]
    assert any(isinstance(e, Aux) and e.kind == "S" and e.value == 1000.0 and e.args.get("max") for e in ev)


def test_g98_g99_feed_per_minute_and_per_revolution():
    """L2.1-78 `G98 G01 X_ Y_ Z_ F_`, L2.1-79 `G99 G01 X_ Y_ Z_ F_` (L§2.1)."""
    m = _moves("G98 G01 X10. Y1. Z-1. F100\nG99 G01 X12. Y2. Z-2. F0.35\nM30\n")
    assert [(x.feed, x.per_rev) for x in m] == [(100.0, False), (0.35, True)]


def test_g96_g97_surface_speed_and_rpm():
    """L2.1-80 `G96 S_ (m/min)`, L2.1-81 `G97 S_ (rev/min)` (L§2.1)."""
    from nc.moves import Aux

    ev, ip = _events("M03 S500\nG96 S120\nG01 X40. Z-1. F0.1\nG97 S800\nM30\n")
    s = [(e.value, e.args.get("css")) for e in ev if isinstance(e, Aux) and e.kind == "S"]
    assert (120.0, 1.0) in s and s[-1] == (800.0, None) and not ip.state.css


@pytest.mark.parametrize("first,second,corner", [
    ("G01 X20. Z-10. ,C2.", "G01 X40. Z-10.", "chamfer"),  # L2.1-82, L2.1-83
    ("G01 X20. Z-10. ,R2.", "G01 X40. Z-10.", "round"),  # L2.1-84, L2.1-85
    ("G02 U0 W-10. R20. ,C1.", "G01 X40. W0", "chamfer"),  # L2.1-82 with G02
    ("G03 X20. W-10. R20. ,R1.", "G01 U20.", "round"),  # L2.1-84 with G03
])
def test_chamfer_and_corner_rounding(capsys, tmp_path, first, second, corner):
    """L2.1-82 `G01/G02/G03 X/U_ Z/W_ ,C_`, L2.1-83 `G01/G02/G03 X/U_ Z/W_`, L2.1-84
    `G01/G02/G03 X/U_ Z/W_ ,R_`, L2.1-85 `G01/G02/G03 X/U_ Z/W_` (L§2.1): a chamfer / round of the given
    size between the ,C/,R block and the next one; the end point of the next block stays."""
    r = _run(capsys, tmp_path, f"G00 X20. Z0\nG01 F0.2\n{first}\n{second}\nM30\n")
    tag = ",C" if corner == "chamfer" else ",R"
    ins = [m for m in r.moves if tag in (m.get("tags") or [])]
    assert len(ins) == 1 and ins[0]["kind"] == ("line" if corner == "chamfer" else "arc")
    assert r.ends("X", "Z")[-1] == (40.0, -10.0)


def test_g01_angle_a(capsys, tmp_path):
    """L2.1-86 `G01 X_ (Z_) ,A_` (L§2.1): a line at angle A (from +Z) that ends at the given X (or Z)."""
    r = _run(capsys, tmp_path, "G00 X20. Z0\nG01 X40. ,A135. F0.2\nG01 Z-30. ,A180.\nM30\n")
    assert [tuple(round(v, 6) for v in e) for e in r.ends("X", "Z")[1:]] == [(40.0, -10.0), (40.0, -30.0)]


# ---- L§3.1 M codes on the bench (program flow through the MLC)

def _machine():
    from hil.bench import default_lathe
    from hil.scripting import Machine
    from mlc.machine import Mlc

    bench = dataclasses.replace(default_lathe(), profile=LATHE)
    m = Machine(bench, Mlc(None, axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config()))
    m.power_up()
    return m


def test_m00_m01_m02_m30_on_the_bench():
    """L3.1-1 `M00`, L3.1-2 `M01`, L3.1-3 `M02`, L3.1-4 `M30` (L§3.1): M00 stops until cycle start; M01
    only with the optional stop switch (M2x009); M02 / M30 end the program, later blocks never run."""
    m = _machine()
    m.panel.resume_after = 0.3
    t_m00 = m.run_program("M00\nG00 X40.\nM30\n", timeout=10)
    assert t_m00 >= 0.3 and abs(m.command("X") - 20.0) < 1e-6
    t_off = m.run_program("M01\nM30\n", timeout=10)
    m.mlc.mem.set_bit(21009, True)
    t_on = m.run_program("M01\nM30\n", timeout=10)
    assert t_off < 0.1 and t_on >= 0.3
    m.run_program("G00 X30.\nM02\nG00 X10.\nM30\n", timeout=10)
    assert abs(m.command("X") - 15.0) < 1e-6
    m.run_program("G00 X50.\nM30\nG00 X10.\n", timeout=10)
    assert abs(m.command("X") - 25.0) < 1e-6


def test_m98_p_l_and_m99(capsys, tmp_path):
    """L3.1-5 `M98 P_ L_`, L3.1-6 `M99` (L§3.1): the subprogram P runs L times; M99 returns to the block
    after the call."""
    r = _run(capsys, tmp_path, "G00 X0 Z0\nM98 P2000 L3\nG00 X99.\nM30\nO2000\nG01 W-1. F0.1\nM99\n")
    assert r.ends("Z") == [(0.0,), (-1.0,), (-2.0,), (-3.0,), (-3.0,)] and r.ends("X")[-1] == (99.0,)
