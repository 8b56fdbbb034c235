"""Format rows of the NC5 G command guide's chapter 3 (milling and common codes), each written as the manual
writes it (every optional word) and checked for the effect the row's description promises: end points,
cycle expansion, offsets, # variables, modal groups. Row ids as in docs/formats.md (`N<section>-<k>`).
"""

from __future__ import annotations

import pytest

from lang_helpers import PathResult, run_path


def _tags(r: PathResult) -> list[tuple[str, ...]]:
    return [tuple(m.get("tags") or ()) for m in r.moves]


def _z_of(r: PathResult, *tag: str) -> list[float]:
    """Z end points of the moves whose tags start with `tag`."""
    return [round(m["work"]["Z"], 6) for m in r.moves if tuple(m.get("tags") or ())[:len(tag)] == tag]


def _ok(r: PathResult) -> PathResult:
    assert r.code == 0, r.alarm
    return r


def test_g01_cp_f_and_the_corner_words_c_r_a(capsys, tmp_path):
    """N3.3.2-1 `G01 CP F_`, N3.3.2-2 `G01 CP F_ , C_`, N3.3.2-3 `[G01] R_`, N3.3.2-4 `[G01] A_` (N§3.3.2):
    a chamfer of C between two lines, a fillet arc of radius R, and A the angle of the line (the missing
    coordinate computed from it)."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG01 X10. F100\nG01 X20. F200 , C2.\nY10.\nG01 X30. ,R3.\n"
                     "Y20.\nG01 X40. ,A45.\nM30\n"))
    ends = [tuple(round(v, 6) for v in e) for e in r.ends("X", "Y")]
    assert ends[1] == (10.0, 0.0) and r.moves[1]["feed"] == 100.0
    assert ends[2:4] == [(18.0, 0.0), (20.0, 2.0)] and r.moves[3]["tags"] == [",C"]  # 2 mm back on both lines
    assert r.moves[3]["feed"] == 200.0
    arc = r.moves[6]
    assert arc["kind"] == "arc" and ends[5] == (27.0, 10.0) and ends[6] == (30.0, 13.0)  # fillet R3 at (30,10)
    assert (round(arc["center"]["X"], 6), round(arc["center"]["Y"], 6)) == (27.0, 13.0)
    assert ends[-1] == (40.0, 30.0)  # from (30,20) at 45 degrees to X40


@pytest.mark.parametrize("code,direction", [("G02", "cw"), ("G03", "ccw")])
def test_g09_with_g02_g03_stops_exactly_at_the_arc_end(capsys, tmp_path, code, direction):
    """N3.4.1-2 `G02`, N3.4.1-3 `G03` (the `G09 G01/G02/G03 CP` table, N§3.4.1): the arc block ends in an
    exact stop; the next block does not."""
    r = _ok(run_path(capsys, tmp_path, f"G90 G00 X0 Y0\nG09 {code} X10. Y0 R5. F100\nG01 X20.\nM30\n"))
    arc, nxt = r.moves[1], r.moves[2]
    assert arc["kind"] == "arc" and arc["dir"] == direction and arc.get("exact_stop") is True
    assert "exact_stop" not in nxt and r.ends("X", "Y")[1] == (10.0, 0.0)


def test_g94_g95_feed_per_minute_and_per_revolution(capsys, tmp_path):
    """N3.4.4-1 `G94 F_`, N3.4.4-2 `G95` (N§3.4.4): F in mm/min under G94, mm/rev under G95; group 5 in
    #20305."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X0\nM03 S1000\nG94 G01 X10. F200\nG95 G01 X20. F0.2\n#100=#20305\n"
                     "G94 F300\nX30.\nM30\n", "--vars", "100,20305"))
    assert [(m["feed"], m.get("per_rev", False)) for m in r.moves[1:]] == [(200.0, False), (0.2, True),
                                                                          (300.0, False)]
    assert (r.vars["100"], r.vars["20305"]) == (95.0, 94.0)


@pytest.mark.parametrize("p,param", [(2, "N2.061"), (3, "N2.062"), (4, "N2.063")])
def test_g30_p2_p3_p4_return_through_the_intermediate_point(capsys, tmp_path, p, param):
    """N3.5.3-1 `G30 P2 CP`, N3.5.3-2 `[G30] P3`, N3.5.3-3 `[G30] P4` (N§3.5.3): rapid to the intermediate
    point CP, then to the 2nd/3rd/4th reference position (N2.061-N2.063), the axes of CP only; G29 comes
    back through the same intermediate point."""
    r = _ok(run_path(capsys, tmp_path, f"G90 G00 X10. Y10. Z0\nG30 P{p} X20. Y30.\nG29 X5. Y5.\nM30\n",
                     "--param", f"{param} X=-100", "--param", f"{param} Y=-{p}0"))
    assert r.machine("X", "Y")[1:3] == [(20.0, 30.0), (-100.0, -p * 10.0)]
    assert r.moves[2]["tags"] == [f"G30P{p}", "reference"] and r.moves[2]["exact_stop"] is True
    assert r.machine("X", "Y")[3:] == [(20.0, 30.0), (5.0, 5.0)] and r.machine("Z")[2] == (0.0,)


def test_g05_p_selects_a_parameter_group_and_checks_its_range(capsys, tmp_path):
    """N3.8.2-1 `G05`, N3.8.2-2 `[G05] P_` (N§3.8.2, "P_ parameter group ID, range P1-P20"): the block is
    accepted with P1-P20 (group 0 shows G05 in #20300) and a P outside the range is an argument error. `hil path`
    runs no planner: the group a G05 selects takes effect in the channel (`hil run`, tests/test_g05_groups.py;
    decision language L25-1), and its preview stop carries it."""
    r = _ok(run_path(capsys, tmp_path, "G05 P20\n#100=#20300\nG05 P1\nG90 G00 X1.\nM30\n", "--vars", "100",
                     "--preview-log"))
    assert r.vars["100"] == 5.0 and r.ends("X") == [(1.0,)]
    assert [(e["line"], e["reason"], e["group"]) for e in r.other if e["kind"] == "sync"] == [(1, "G05", 20),
                                                                                             (3, "G05", 1)]
    bad = run_path(capsys, tmp_path, "G05 P21\nM30\n")
    assert bad.code == 1 and bad.alarm["code"] == "0x0243"


WCS = {1: 22002, 2: 22003, 3: 22004, 4: 22005, 5: 22006, 6: 22007}  # X of G54..G59 (App. B)


def test_g10_l02_registers_a_work_offset(capsys, tmp_path):
    """N3.8.3.1-1 `G10 L02 P_ CP` (N§3.8.3.1): P0 the offset (external) coordinate, P1-P6 G54-G59; the
    new origin is used at once, and under G91 the value is added."""
    r = _ok(run_path(capsys, tmp_path, "G10 L02 P2 X100. Y50.\nG91 G10 L02 P2 X5.\nG90 G10 L02 P0 Y1.\nG55 G00 X0 Y0\n"
                     "M30\n", "--vars", "22003,22081,22000,22078"))
    assert r.vars == {"22003": 105.0, "22081": 50.0, "22000": 0.0, "22078": 1.0}
    assert r.machine("X", "Y") == [(105.0, 51.0)]


def test_g10_l10_l11_register_tool_length_and_wear(capsys, tmp_path):
    """N3.8.3.2-1 `G10 L10 P_ R_`, N3.8.3.2-2 `[G10] L11 CP` (N§3.8.3.2 and its example): on a mill R is
    the Z length (G91: added); L11 the wear; G43 H applies length + wear."""
    r = _ok(run_path(capsys, tmp_path, "G90 G10 L10 P1 R-300.\nG91 G10 L10 P1 R-100.\nG90 G10 L11 P1 Z0.5\n"
                     "G00 G43 H1 Z10.\nM30\n", "--vars", "28000,44000"))
    assert (r.vars["28000"], r.vars["44000"]) == (-400.0, 0.5)  # Z is the third axis: #26000 + 2*1000
    assert r.machine("Z") == [(10.0 - 400.0 + 0.5,)]


def test_g10_l12_l13_register_tool_radius_and_wear(capsys, tmp_path):
    """N3.8.3.3-1 `G10 L12 P_ R_`, N3.8.3.3-2 `[G10] L13` (N§3.8.3.3): radius and radius wear of tool P,
    used by G41/G42 D."""
    r = _ok(run_path(capsys, tmp_path, "G10 L12 P3 R4.\nG10 L13 P3 R1.\nG90 G00 X0 Y-20.\nG41 D3 G01 Y0 F100\n"
                     "Y20.\nG40 G00 X-30.\nM30\n", "--vars", "58002,59002"))
    assert (r.vars["58002"], r.vars["59002"]) == (4.0, 1.0)
    assert r.machine("X", "Y")[2] == (-5.0, 20.0)  # left of +Y by radius + wear


def test_g10_l14_registers_the_tool_length_tolerance(capsys, tmp_path):
    """N3.8.3.4-1 `G10 L14 P_ R_ CP` (N§3.8.3.4): R the Z length tolerance; with both R and CP, CP is
    ignored."""
    r = _ok(run_path(capsys, tmp_path, "G10 L14 P2 R0.05 Z9.\nG10 L14 P3 X0.02\nM30\n", "--vars", "63001,61002"))
    assert (r.vars["63001"], r.vars["61002"]) == (0.05, 0.02)


def test_g10_l15_registers_the_tool_life():
    """N3.8.3.5-1 `G10 L15 P_ D_ R_`, N3.8.3.5-2 `[G10] CP` (N§3.8.3.5): the actual life of tool P; D1 adds
    to it, without D the value is set; CP gives it when there is no R."""
    from nc.interp import Interpreter
    from nc.profiles import make_profile
    from nc.program import parse_program

    ip = Interpreter(make_profile("nc5-mill"))
    list(ip.run(parse_program("G10 L15 P4 R10.\nG10 L15 P4 D1 R2.5\nG10 L15 P5 Z7.\nM30\n")))
    assert (ip.tools.life[("life", 4)], ip.tools.life[("life", 5)]) == (12.5, 7.0)


def test_g10_l20_registers_an_extended_work_offset(capsys, tmp_path):
    """N3.8.3.6-1 `G10 L20 P_ CP` (N§3.8.3.6): P1-P64 = G54 P1-P64; N3.6.5-1's G54 P_ then uses it."""
    r = _ok(run_path(capsys, tmp_path, "G10 L20 P64 X-10. Y20.\nG54 P64 G90 G00 X0 Y0\nM30\n",
                     "--vars", "22077"))
    assert r.vars["22077"] == -10.0 and r.machine("X", "Y") == [(-10.0, 20.0)]


def test_g10_l21_registers_a_software_limit():
    """N3.8.3.7-1 `G10 L21 P_ CP` (N§3.8.3.7): P1 the 1st positive soft limit, P2 the negative; the channel's
    limit check (nc.softlimits, run by `hil run`) then refuses a move beyond it before it starts (0x0A01)."""
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.program import parse_program
    from nc.softlimits import SoftLimits

    ip = Interpreter(make_profile("nc5-mill"))
    moves = [e for e in ip.run(parse_program("G10 L21 P1 X50.\nG10 L21 P2 X-5.\nG90 G00 X40.\nX60.\nX-6.\nM30\n"))
             if isinstance(e, Move)]
    assert (ip.profile.params["soft limit 1 X"], ip.profile.params["soft limit 2 X"]) == (50.0, -5.0)
    limits = SoftLimits(params=ip.profile.params)
    found = [limits.check(m) for m in moves]
    assert found[0] is None and [(a.code, a.axis) for a in found[1:]] == [(0x0A01, "X"), (0x0A01, "X")]


def test_g04_p_milliseconds_and_x_seconds(capsys, tmp_path):
    """N3.8.4-1 `G04 P_`, N3.8.4-2 `[G04] X_` (N§3.8.4): P in ms, X in s; the axes stand."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X3.\nG04 P250\nG04 X1.5\nM30\n"))
    assert [(m["kind"], m["duration"]) for m in r.moves[1:]] == [("dwell", 0.25), ("dwell", 1.5)]
    assert r.ends("X")[1:] == [(3.0,), (3.0,)]


def test_g900_p_q_sets_and_clears_an_mlc_relay():
    """N3.8.5-1 `G900 P_ Q_` (N§3.8.5): P the M relay, Q the value (0 clears, else sets); the block goes to
    the MLC without waiting for a finish; a P out of range or a missing P/Q ignores the block (notes 1-2).
    The format table says 30200~30339, App. B (M30200-M30399) 30399: decision C5 in mlc.md takes App. B."""
    from nc.interp import Interpreter
    from nc.moves import Aux
    from nc.profiles import make_profile
    from nc.program import parse_program

    prog = "G900 P30200 Q1\nG900 P30339 Q0\nG900 P30399 Q-1\nG900 P30400 Q1\nG900 P30201\nG900 Q1\nM30\n"
    ev = [e for e in Interpreter(make_profile("nc5-mill")).run(parse_program(prog))
          if isinstance(e, Aux) and e.kind == "G900"]
    assert [(e.value, e.args["Q"], e.wait) for e in ev] == [(30200, 1.0, False), (30339, 0.0, False),
                                                          (30399, 1.0, False)]


def test_g96_s_constant_surface_speed_and_g97_s_rpm(capsys, tmp_path):
    """N3.9.2-1 `G96 S_`, N3.9.2-2 `G97` (N§3.9.2): G96 S in m/min (group 17 = 96), G97 S in rpm; #20404
    the commanded speed."""
    r = _ok(run_path(capsys, tmp_path, "M03 S500\nG96 S120\n#100=#20317\nG97 S800\n#101=#20317\n#102=#20404\nM30\n",
                     "--vars", "100-102"))
    assert r.vars == {"100": 96.0, "101": 97.0, "102": 800.0}


SUB = "O9010\n#100=#100+#9\n#101=#101+1\n#9=#9+100.\nM99\n"


def test_g65_p_l_arguments(capsys, tmp_path):
    """N3.11.4.4-1 `G65 P_ L_ I_` (N§3.11.4.4): P the program, L the repeat count, argument I into #9 (the
    argument table), passed afresh to each repetition."""
    r = _ok(run_path(capsys, tmp_path, "#100=0\n#101=0\nG65 P9010 L3 I2.5\nM30\n" + SUB, "--vars", "100-101"))
    assert (r.vars["100"], r.vars["101"]) == (7.5, 3.0)


def test_g66_p_l_modal_call_and_g67_cancel(capsys, tmp_path):
    """N3.11.4.5-1 `G66 P_ L_ I_`, N3.11.4.5-2 `G67` (N§3.11.4.5): after each moving block the macro runs
    L times; after G67 no more."""
    r = _ok(run_path(capsys, tmp_path, "#100=0\n#101=0\nG66 P9010 L2 I1.\nG00 X1.\nX2.\nG67\nX3.\nM30\n" + SUB,
                     "--vars", "100-101"))
    assert (r.vars["100"], r.vars["101"]) == (4.0, 4.0) and r.ends("X")[-1] == (3.0,)


def test_m96_p_interrupt_macro_and_m97_cancel(capsys, tmp_path):
    """N3.11.4.6-1 `M96 P_`, N3.11.4.6-2 `M97` (N§3.11.4.6): with M96 the M2x019 signal stops the running
    block, runs program P, and M99 goes on to the block's end; after M97 the signal does nothing."""
    prog = "G90 G00 X0 Y0\nM96 P9100\nG01 X10. F100\nM97\nG01 X20.\nM30\nO9100\nG00 Y5.\nM99\n"
    r = _ok(run_path(capsys, tmp_path, prog, "--interrupt", "3@0.5"))
    assert _tags(r)[1:4] == [("M96 stop",), (), ("M96", "resume")]
    assert r.ends("X", "Y")[1:4] == [(5.0, 0.0), (5.0, 5.0), (10.0, 0.0)]
    r = _ok(run_path(capsys, tmp_path, prog, "--interrupt", "5@0.5"))
    assert r.ends("X", "Y")[-1] == (20.0, 0.0) and ("M96 stop",) not in _tags(r)


def test_m98_p_h_q_and_m99_p(capsys, tmp_path):
    """N3.11.4.7-1 `M98 P_ H_`, N3.11.4.7-2 `[M98] Q_`, N3.11.4.7-3 `M99 P_` (N§3.11.4.7): H starts the
    subprogram at its N label, Q at a line, H wins over Q; M99 P returns to label N of the caller."""
    prog = ("G90 G00 X0 Y0\nM98 P2000 H20\nM98 P2000 Q13\nM98 P2000 H30 Q12\nM98 P2100\nX99.\nN50 Y7.\nM30\n"
            "O2000\nN10 G00 X1.\nN20 G00 X2.\nX3.\nN30 X4.\nM99\nO2100\nG00 Y1.\nM99 P50\n")
    r = _ok(run_path(capsys, tmp_path, prog))
    assert [m["work"]["X"] for m in r.moves[1:8]] == [2.0, 3.0, 4.0, 4.0, 4.0, 4.0, 4.0]
    assert r.ends("X", "Y")[-2:] == [(4.0, 1.0), (4.0, 7.0)]  # X99. skipped: M99 P50 went to N50


def test_g41_g42_d_and_g40(capsys, tmp_path):
    """N3.12.1-1 `G40`, N3.12.1-2 `G41 D_`, N3.12.1-3 `G42` (N§3.12.1): the tool centre runs left / right of
    the programmed line by the radius of D; G40 ends on the programmed point."""
    r = _ok(run_path(capsys, tmp_path, "G10 L12 P1 R5.\nG90 G00 X0 Y0\nG41 D1 G01 X20. F100\nY20.\nG40 X0 Y30.\n"
                     "G42 D1 G01 X20.\nY50.\nG40 G00 X0 Y60.\nM30\n"))
    m = [tuple(round(v, 6) for v in e) for e in r.machine("X", "Y")]
    assert m[2] == (15.0, 20.0) and m[3] == (0.0, 30.0)  # left of +Y is -X
    assert m[5] == (25.0, 50.0) and m[6] == (0.0, 60.0)  # right of +Y is +X


def test_g43_g44_cp_h_z_and_g49(capsys, tmp_path):
    """N3.12.2-1 `G43 CP H_ Z_`, N3.12.2-2 `G44`, N3.12.2-3 `G49` (N§3.12.2): G43 adds length H, G44
    subtracts it, G49 cancels; the other axes of CP move in the same block."""
    r = _ok(run_path(capsys, tmp_path, "G10 L10 P1 R100.\nG10 L10 P2 R50.\nG90 G00 X0 Y0 Z0\nG43 X5. H1 Z10.\n"
                     "G44 H2 Z10.\n#100=#20308\nG49 Z10.\nM30\n", "--vars", "100,20308,20401"))
    assert r.machine("X", "Z")[1:] == [(5.0, 110.0), (5.0, -40.0), (5.0, 10.0)]
    assert r.vars == {"100": 44.0, "20308": 49.0, "20401": 2.0}


def test_g51_scaling_centre_axis_ratios_and_total_ratio(capsys, tmp_path):
    """N3.12.3-1 `G51 X_ Y_ Z_ I_ J_ K_ P_` (N§3.12.3): about the centre X Y Z, per-axis ratio I J K or the
    total ratio P (1 = 0.001, P100 = 0.1 times); G50 cancels."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X0 Y0 Z0\nG51 X10. Y10. Z0 I2000 J500 K1000\nG01 X20. Y20. Z-4. F100\n"
                     "G50\nG51 X0 Y0 Z0 P100\nG01 X50. Y30. Z-10.\nG50\nG00 X20. Y20.\nM30\n"))
    assert [tuple(round(v, 6) for v in e) for e in r.machine("X", "Y", "Z")[1:]] == [
        (30.0, 15.0, -4.0), (5.0, 3.0, -1.0), (20.0, 20.0, -1.0)]


def test_g24_mirror_and_g25_cancel(capsys, tmp_path):
    """N3.12.4-1 `G25 CP`, N3.12.4-2 `G24` (N§3.12.4 and its example: `G24X0` ... `G25X0`): G24 with an
    axis word mirrors that axis about its value, G25 with the axis cancels that axis only. The table's
    CP cell spans both rows (the example gives G24 an axis); G24 without one is an argument error."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG24 X10. Y0\nG01 X20. Y5. F100\nG25 X10.\nG01 X20. Y5.\n"
                     "G25 Y0\nG01 X20. Y5.\nM30\n"))
    assert r.machine("X", "Y")[1:] == [(0.0, -5.0), (20.0, -5.0), (20.0, 5.0)]
    bad = run_path(capsys, tmp_path, "G24\nM30\n")
    assert bad.code == 1 and bad.alarm["code"] == "0x0222"


def test_g68_rotation_and_g69(capsys, tmp_path):
    """N3.12.5-1 `G68 X_ Y_ R_`, N3.12.5-2 `G69` (N§3.12.5): rotation about X Y by R degrees (positive
    CCW); G69 cancels."""
    r = _ok(run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG68 X10. Y0 R90.\nG01 X20. Y0 F100\nG68 X0 Y0 R-90.\n"
                     "G01 X10. Y0\nG69\nG01 X20. Y0\nM30\n"))
    assert [tuple(round(v, 6) for v in e) for e in r.machine("X", "Y")[1:]] == [(10.0, 10.0), (0.0, -10.0),
                                                                               (20.0, 0.0)]


HOLE = "G90 G00 X0 Y0 Z10.\n"


def test_g73_peck_drilling(capsys, tmp_path):
    """N3.13.1-1 `G73 X_ Y_ Z_ R_ Q_ F_ K_` (N§3.13.1): rapid to R, feed Q at a time with a short
    retract (chip break) between pecks, to Z; K holes (G91: at successive increments)."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G91 G98 G73 X10. Y10. Z-7. R-8. Q2. F100 K2\nG80\nM30\n"))
    assert [round(x, 6) for (x,) in r.ends("X") if x] and r.ends("X", "Y")[-1] == (20.0, 20.0)
    assert _z_of(r, "G73", "peck")[:4] == [0.0, -2.0, -4.0, -5.0] and len(_z_of(r, "G73", "peck")) == 8
    assert _z_of(r, "G73", "retract")[0] > 0.0 > _z_of(r, "G73", "retract")[1]  # a short retract, not to R
    assert r.moves[-1]["feed"] is None and _z_of(r, "G73", "return") == [10.0, 10.0]


def test_g81_drilling(capsys, tmp_path):
    """N3.13.1-2 `G81 X_ Y_ Z_ R_ F_ K_` (N§3.13.1): rapid to R, feed to Z, rapid out; K repeats."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G99 G81 X10. Y10. Z-5. R2. F100 K2\nG80\nM30\n"))
    assert [t[1] for t in _tags(r)[1:]] == ["position", "approach", "cut", "return", "cut", "return"]
    assert _z_of(r, "G81", "cut") == [-5.0, -5.0] and _z_of(r, "G81", "return") == [2.0, 2.0]  # G99: to R


def test_g82_drilling_with_dwell(capsys, tmp_path):
    """N3.13.1-3 `G82 X_ Y_ Z_ R_ P_ F_ K_` (N§3.13.1): as G81 with a dwell of P ms at the bottom."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G82 X10. Y10. Z-5. R2. P500 F100 K1\nG80\nM30\n"))
    dw = [m for m in r.moves if m["kind"] == "dwell"]
    assert len(dw) == 1 and dw[0]["duration"] == 0.5 and dw[0]["work"]["Z"] == -5.0
    assert _z_of(r, "G82", "return") == [10.0]  # G98: back to the initial level


def test_g83_deep_hole_peck_drilling(capsys, tmp_path):
    """N3.13.1-4 `G83 X_ Y_ Z_ R_ Q_ F_ K_` (N§3.13.1): every peck retracts to R, comes back rapid to just
    above the last depth, feeds Q further."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G83 X20. Y10. Z-5. R2. Q2. F100 K1\nG80\nM30\n"))
    assert _z_of(r, "G83", "peck") == [0.0, -2.0, -4.0, -5.0]
    assert set(_z_of(r, "G83", "retract")) == {2.0} and _z_of(r, "G83", "return") == [10.0]


@pytest.mark.parametrize("code,rows", [("G74", "N3.13.2-1"), ("G84", "N3.13.2-2")])
def test_g74_g84_tapping(capsys, tmp_path, code, rows):
    """N3.13.2-1 `G74 X_ Y_ Z_ R_ Q_ S_ F_ K_`, N3.13.2-2 `G84` (N§3.13.2): feed to Z at F (the lead,
    mm/rev) with the spindle at S, reverse out to R; G74 left-hand (spindle reverse), G84 right-hand."""
    r = _ok(run_path(capsys, tmp_path, HOLE + f"M03 S500\nG99 {code} X10. Y10. Z-5. R2. Q0 S300 F1. K1\nG80\nM30\n"))
    assert _z_of(r, code, "tap") == [-5.0] and _z_of(r, code, "tap_out") == [2.0], rows
    assert [m["feed"] for m in r.moves if "tap" in (m.get("tags") or [])] == [1.0]


def test_g76_fine_boring_with_shift(capsys, tmp_path):
    """N3.13.3-1 `G76 X_ Y_ Z_ R_ Q_ F_ K_` (N§3.13.3): feed to Z, oriented stop, shift Q off the wall,
    rapid out, shift back."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G76 X40. Y10. Z-5. R2. Q1. F100 K1\nG80\nM30\n"))
    kinds = [t[1] for t in _tags(r)[1:]]
    assert kinds == ["position", "approach", "cut", "shift", "return", "shift"]
    assert r.ends("X", "Z")[4:] == [(41.0, -5.0), (41.0, 10.0), (40.0, 10.0)]


@pytest.mark.parametrize("block,steps", [
    ("G85 X50. Y10. Z-5. R2. F100 K1", ["cut", "cut_out"]),  # N3.13.3-2: feed in, feed out
    ("G86 X50. Y10. Z-5. R2. F100 K1", ["cut", "return"]),  # N3.13.3-3: feed in, spindle stop, rapid out
    ("G89 X50. Y10. Z-5. R2. P300 F100 K1", ["cut", "dwell", "cut_out"]),  # N3.13.3-6: with dwell P
])
def test_g85_g86_g89_boring(capsys, tmp_path, block, steps):
    """N3.13.3-2 `G85 X_ Y_ Z_ R_ F_ K_`, N3.13.3-3 `G86 X_ Y_ Z_ R_ F_ K_`, N3.13.3-6
    `G89 X_ Y_ Z_ R_ P_ F_ K_` (N§3.13.3)."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G99 " + block + "\nG80\nM30\n"))
    assert [t[1] for t in _tags(r)[3:3 + len(steps)]] == steps
    assert r.ends("X", "Y", "Z")[3] == (50.0, 10.0, -5.0) and r.ends("Z")[-1] == (2.0,)


def test_g87_back_boring(capsys, tmp_path):
    """N3.13.3-4 `G87 X_ Y_ Z_ R_ Q_ P_ F_ K_` (N§3.13.3): shifted by Q, rapid down to R (below the part),
    shift back, bore upward to Z with dwell P, shift, out."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G87 X70. Y10. Z-5. R-20. Q1. P300 F100 K1\nG80\nM30\n"))
    kinds = [t[1] for t in _tags(r)[1:]]
    assert kinds[:6] == ["position", "shift", "approach", "shift", "cut", "dwell"]
    assert r.ends("X", "Z")[3] == (71.0, -20.0) and r.ends("X", "Z")[5] == (70.0, -5.0)


def test_g88_boring_with_dwell_and_manual_return(capsys, tmp_path):
    """N3.13.3-5 `G88 X_ Y_ Z_ P_ F_ K_` (N§3.13.3): feed to Z, dwell P, then out (the manual retract is
    a rapid here); R is the modal R of the cycle group (none in the row)."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G81 X0 Y0 Z-1. R2. F100\nG88 X80. Y10. Z-5. P300 F100 K1\nG80\n"
                     "M30\n"))
    g88 = [m for m in r.moves if (m.get("tags") or [""])[0] == "G88"]
    assert [m["tags"][1] for m in g88] == ["position", "approach", "cut", "dwell", "return"]
    assert g88[1]["work"]["Z"] == 2.0 and g88[3]["duration"] == 0.3


def test_g80_cancels_and_g98_g99_choose_the_return_level(capsys, tmp_path):
    """N3.13.4-1 `G80`, N3.13.5-1 `G98`, N3.13.5-2 `G99` (N§3.13.4-3.13.5): G98 returns to the initial
    level, G99 to R; after G80 an axis word is a plain move (group 9 = 80 in #20309)."""
    r = _ok(run_path(capsys, tmp_path, HOLE + "G98 G81 X10. Z-5. R2. F100\nG99 X20.\nG80\n#100=#20309\nX30. Y5.\nM30\n",
                     "--vars", "100"))
    assert _z_of(r, "G81", "return") == [10.0, 2.0]
    assert r.vars["100"] == 80.0 and r.moves[-1]["kind"] == "rapid" and not r.moves[-1].get("tags")
    assert r.ends("X", "Y", "Z")[-1] == (30.0, 5.0, 2.0)
