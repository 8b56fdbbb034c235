"""Modal state, coordinate systems, data setting and the decimal-point rule (E-N12..E-N27, E-L02..E-L20)."""

from __future__ import annotations

import pytest

from lang_helpers import run_path

BENCH_G55 = "--param", "N2.060 X=0"


def test_e_n22_e_n23_e_n24_absolute_incremental(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G01 G90 X10.0 Y10.0 F500.0\nX30.0 Y30.0\n")
    assert r.ends("X", "Y") == [(10.0, 10.0), (30.0, 30.0)]
    r = run_path(capsys, tmp_path, "G01 G91 X10.0 Y10.0 F500.0\nX20.0 Y20.0\n")
    assert r.machine("X", "Y")[-1] == (30.0, 30.0)
    r = run_path(capsys, tmp_path, "G01 G90 X0 Y0 F1000\nX40.0\nG91 Y20.0\nX-5.0 Y5.0\nG90 X5.0\nX0 Y20.0\nY0\nM30\n")
    assert r.ends("X", "Y") == [(0, 0), (40, 0), (40, 20), (35, 25), (5, 25), (0, 20), (0, 0)]


def test_e_n17_g52_local_system(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G54 X0 Y0\nG52 X40.0 Y40.0\nG00 X20.0 Y20.0\n")
    assert r.machine("X", "Y")[-1] == (60.0, 60.0)


def test_e_n18_a35_g52_persists_across_wcs(capsys, tmp_path):
    prog = "G10 L2 P3 X10. Y-10.\nG90G54G00X10.Y10.\nG52X30.Y20.\nG00X20.Y20.\nG56G00X50.Y10.\n"
    r = run_path(capsys, tmp_path, prog)
    assert r.machine("X", "Y") == [(10.0, 10.0), (50.0, 40.0), (90.0, 20.0)]


def test_e_n19_g53(capsys, tmp_path):
    prog = ("G91 G53 X150. Y-150.\nX-30. Y-30.\nG90 G53 X50. Y-50. Z0.\nG1 G53 X100. Y-100. F1000\n"
            "X50. Y50.\n")
    r = run_path(capsys, tmp_path, prog)
    assert [m["kind"] for m in r.moves] == ["rapid", "rapid", "rapid", "line"]
    assert r.machine("X", "Y") == [(-30.0, -30.0), (50.0, -50.0), (100.0, -100.0), (50.0, 50.0)]
    assert r.moves[3]["feed"] == 1000.0
    assert any(o["kind"] == "sync" for o in run_path(capsys, tmp_path, prog, "--preview-log").other)


def test_e_n20_g55_rectangle(capsys, tmp_path):
    prog = "G10 L2 P2 X150. Y100.\nG00 G90 G55 X0 Y0\nG00 X100.0\nY50.0\nX0.\nX0.\n"
    r = run_path(capsys, tmp_path, prog)
    assert r.machine("X", "Y")[:4] == [(150, 100), (250, 100), (250, 150), (150, 150)]


def test_e_n21_g92_rectangle_cleared_by_m30(capsys, tmp_path):
    prog = ("G10 L2 P1 X150. Y100.\nG00 G90 G54 X0.0 Y0.0\nG00 G92 X0.0 Y0.0\nG01 X100.0 Y0.0 F1000.0\n"
            "X100.0 Y50.0\nX0.0 Y50.0\nX0.0 Y0.0\nM30\n")
    r = run_path(capsys, tmp_path, prog, "--vars", "21016")
    assert r.machine("X", "Y") == [(150, 100), (250, 100), (250, 150), (150, 150), (150, 100)]
    assert r.vars["21016"] == 0.0  # after M30 the G92 shift is gone and G54 X0 is machine 150


def test_e_n12_e_n13_g28_g29(capsys, tmp_path):
    inc = run_path(capsys, tmp_path, "G90 G00 X30. Y40.\nG28G91X70.0Y40.0\nM06\nG29X20.0Y-40.0\n")
    ab = run_path(capsys, tmp_path, "G90 G00 X30. Y40.\nG28G90X100.0Y80.0\nM06\nG29X120.0Y40.0\n")
    for r in (inc, ab):
        assert r.machine("X", "Y") == [(30, 40), (100, 80), (0, 0), (100, 80), (120, 40)]
    r = run_path(capsys, tmp_path, "G90 G00 X50. Y65. Z80.\nG90 G28 Z50.\n")
    assert r.machine("X", "Y", "Z")[1:] == [(50, 65, 50), (50, 65, 0)]


def test_g28_ends_length_compensation_at_the_intermediate_point(capsys, tmp_path):
    """N§3.5.1: the reference move runs without G43, so its work Z is the machine Z minus the work origin
    only; the offset is cancelled also when the named axes already stand at the reference point."""
    r = run_path(capsys, tmp_path, "G10 L10 P1 R12.7\nG00 X10. Y0. Z0.\nG43 H1 Z5.\nG28 X20.\nM30\n")
    ref = r.moves[-1]
    assert "reference" in ref["tags"] and ref["end"]["Z"] == 17.7 and ref["work"]["Z"] == 17.7
    r = run_path(capsys, tmp_path, "G10 L10 P1 R12.7\nG00 X0. Y0. Z0.\nG43 H1 Z5.\nG91 G28 X0.\n"
                 "G90 G00 Z5.\nM30\n", "--vars", "20308")
    assert r.machine("Z")[-1] == (5.0,) and r.vars["20308"] == 49.0


def test_g29_without_g28_is_0x0253(capsys, tmp_path):
    assert run_path(capsys, tmp_path, "G29 X10.\n").alarm["code"] == "0x0253"


def test_e_n14_g30_reference_points(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G30 P2 X100. Y80.\nG91 G30 P2 X0. Y0.\nG30 P3 Z0\n",
                 "--param", "N2.061 X=300", "--param", "N2.061 Y=200", "--param", "N2.062 Z=-5")
    assert r.machine("X", "Y") == [(100, 80), (300, 200), (300, 200)]
    assert r.machine("Z")[-1] == (-5.0,)
    assert run_path(capsys, tmp_path, "G30 P5 X0\n").alarm["code"] == "0x0243"


def test_g53_with_g28_is_0x0265(capsys, tmp_path):
    assert run_path(capsys, tmp_path, "G53 G28 X0\n").alarm["code"] == "0x0265"


def test_e_n15_g31_emits_tagged_move_and_sync(capsys, tmp_path):
    # the G31 F is for that block only (N§3.5.4); the next G01 uses the default feed N1.042
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG01 G31 X80.0 F500.0\nY40.0\n", "--preview-log",
                 "--param", "N1.042=800")
    assert r.moves[2]["feed"] == 800.0
    assert r.ends("X", "Y") == [(0, 0), (80, 0), (80, 40)]
    assert r.moves[1]["feed"] == 500.0
    assert any(o["kind"] == "sync" and o["line"] == 2 for o in r.other)


def test_e_l06_e_n26_dwell(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G04 X1.5\nG04 P1500\nG04 X1\nG04 X1.\n")
    assert [m["duration"] for m in r.moves] == [1.5, 1.5, 0.001, 1.0]
    r = run_path(capsys, tmp_path, "G04 X1\n", "--param", "N1.11 Bit4=1")
    assert r.moves[0]["duration"] == 1.0
    assert run_path(capsys, tmp_path, "G04 P1.2\n").alarm["code"] == "0x0258"


def test_e_n25_g10_l10_tool_length(capsys, tmp_path):
    prog = "G10 L10 P1 R-300.0\nG10 L10 P2 R-100.0\nG90 G10 L10 P1 R-300.0\nG91 G10 L10 P1 R-100.0\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "28000,28001")  # Z = axis 3 -> #26000+2000
    assert r.vars == {"28000": -400.0, "28001": -100.0}


def test_g10_l2_l20_offsets_and_g54_p(capsys, tmp_path):
    prog = "G10 L20 P7 X5. Y6.\nG90 G54 P7 G00 X1. Y1.\nG10 L2 P0 X100.\nG55 X0 Y0\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "20331,22000,22020")
    assert r.machine("X", "Y") == [(6.0, 7.0), (100.0, 0.0)]
    assert r.vars["22000"] == 100.0 and r.vars["22020"] == 5.0
    assert run_path(capsys, tmp_path, "G54 P65\n").alarm["code"] == "0x0237"
    assert run_path(capsys, tmp_path, "G54 P1.5\n").alarm["code"] == "0x0236"


def test_e_l08_lathe_g10_tool_data_and_offset(capsys, tmp_path):
    prog = "G10 L10 P1 X10. Z-5. R0.4 Q3\nG10 L11 P1 X0.2\nT0101\nG00 X0 Z0\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "26000,26001,58000", profile="nc5-lathe-a")
    assert r.vars["26000"] == 10.0 and r.vars["58000"] == 0.4
    assert r.machine("X", "Z")[-1] == (pytest.approx(5.1), pytest.approx(-5.0))
    legacy = run_path(capsys, tmp_path, "G10 P10003 X1. Z2.\nG10 P3 Z0.5\nM30\n", "--vars", "6003,6403,7003",
                      profile="lathe-2018")
    assert legacy.vars == {"6003": 1.0, "6403": 2.0, "7003": 0.5}


def test_e_n27_g900(capsys, tmp_path):
    from hil.cli import main
    f = tmp_path / "g.nc"
    f.write_text("G900 P30200 Q1\nG900 P30320 Q0\nG900 P1 Q1\nG900 P30201\nG900 P30202 Q7\n")
    from nc.interp import Interpreter
    from nc.moves import Aux
    from nc.profiles import make_profile
    from nc.program import parse_program
    ev = [e for e in Interpreter(make_profile("nc5-mill")).run(parse_program(f.read_text())) if isinstance(e, Aux)]
    assert [(e.value, e.args["Q"]) for e in ev] == [(30200, 1.0), (30320, 0.0), (30202, 1.0)]
    assert main(["path", str(f), "--profile", "nc5-mill"]) == 0


def test_decimal_point_rule_a4(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X1000 Y2.5 Z-15\n")
    assert r.ends("X", "Y", "Z") == [(1.0, 2.5, -0.015)]
    r = run_path(capsys, tmp_path, "G90 G00 X1000 Y2.5 Z-15\n", "--param", "N8.018 Bit10=1")
    assert r.ends("X", "Y", "Z") == [(1000.0, 2.5, -15.0)]


def test_lathe_diameter_and_u_w_incremental_a5(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G00 X40. Z10.\nU-10. W-5.\nG01 X20. W-10. F0.2\n", profile="nc5-lathe-a")
    assert r.ends("X", "Z") == [(40, 10), (30, 5), (20, -5)]
    assert r.machine("X")[0] == (20.0,)  # machine X is a radius
    r = run_path(capsys, tmp_path, "G90 G00 X40. Z10.\nG91 X-10. Z-5.\nG90 U-10. W-5.\n", profile="nc5-lathe-b")
    assert r.ends("X", "Z") == [(40, 10), (30, 5), (20, 0)]
    assert run_path(capsys, tmp_path, "G91 X1.\n", profile="nc5-lathe-a").alarm["code"] == "0x021D"


def test_e_l32_g50_coordinate_setting_type_a(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G00 X100. Z50.\nG50 X200. Z100. S1000\nG00 X100. Z0\n", profile="nc5-lathe-a")
    assert r.ends("X", "Z")[-1] == (100.0, 0.0)
    assert r.machine("X", "Z")[-1] == (0.0, -50.0)


def test_units_g20_g70_and_lock(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G20 G90 G01 X1. F10.\n")
    assert r.moves[0]["end"]["X"] == pytest.approx(25.4) and r.moves[0]["feed"] == pytest.approx(254.0)
    r = run_path(capsys, tmp_path, "G70 G90 G00 X1. Z1.\n", profile="nc5-lathe-c")
    assert r.machine("Z")[0] == (pytest.approx(25.4),)
    assert run_path(capsys, tmp_path, "G21 G00 X1.\nG20\n").alarm["code"] == "0x0207"


def test_a9_same_group_conflict_and_repeated_words(capsys, tmp_path):
    assert run_path(capsys, tmp_path, "G01 G00 X1.\n").alarm["code"] == "0x0202"
    r = run_path(capsys, tmp_path, "G0 X41. Z0. Z2.\n", profile="nc5-lathe-a")
    assert r.ends("X", "Z") == [(41.0, 2.0)]
    assert run_path(capsys, tmp_path, "G00 X1. U1.\n", profile="nc5-lathe-a").alarm["code"] == "0x0202"


def test_m_code_limit_and_block_skip(capsys, tmp_path):
    assert run_path(capsys, tmp_path, "M08 M09 M10 M11 M12\n").alarm["code"] == "0x0248"
    prog = "G90 G00 X1.\n/X2.\nX3.\n"
    assert run_path(capsys, tmp_path, prog).ends("X") == [(1.0,), (2.0,), (3.0,)]
    assert run_path(capsys, tmp_path, prog, "--block-skip").ends("X") == [(1.0,), (3.0,)]


def test_e_n01_axis_name_with_digit(capsys, tmp_path):
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.program import parse_program
    prof = make_profile("nc5-mill", ("X", "Y", "Z", "XA1"))
    moves = [e for e in Interpreter(prof).run(parse_program("G90 G00 XA1=100. X5.\n")) if isinstance(e, Move)]
    assert moves[0].work["XA1"] == 100.0 and moves[0].work["X"] == 5.0


def test_system_positions_and_modal_readback(capsys, tmp_path):
    prog = "G10 L2 P1 X10.\nG90 G54 G01 X5. Y6. F100\n#100=#21000\n#101=#21016\n#102=#20301\n#103=#20303\n#104=#20400\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100-104")
    assert r.vars == {"100": 15.0, "101": 5.0, "102": 1.0, "103": 90.0, "104": 100.0}
    legacy = run_path(capsys, tmp_path, "G01 X20. Z5. F0.2\n#100=#2100\n#101=#2116\n#102=#2001\n#103=#2102\nM30\n",
                      "--vars", "100-103", profile="lathe-2018")
    assert legacy.vars == {"100": 10.0, "101": 20.0, "102": 1.0, "103": 5.0}


def test_e_l02_e_l03_arcs(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG03 X100.0 Y80.0 R-50.0 F80\n")
    assert r.alarm["code"] == "0x0259"  # chord 128 > 2R: radius error
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG02 X100. Y0 R50. F80\nG02 X0 Y0 R-50. F80\n")
    assert r.moves[1]["center"]["X"] == pytest.approx(50.0) and r.moves[1]["center"]["Y"] == pytest.approx(0.0)
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG02 I-50.0 F100\n")  # E-N08 full circle
    assert r.moves[1]["kind"] == "arc" and r.moves[1]["center"]["X"] == -50.0 and r.moves[1]["end"]["X"] == 0.0
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG02 X10. Y10. F100\n")  # no R/IJK: a line
    assert r.moves[1]["kind"] == "line"


def test_chamfer_and_fillet_a32(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G17 G00 X0 Y0\nG01 X20. F100 ,C5.\nY20. ,R5.\nX0\n")
    assert r.ends("X", "Y")[1:] == [(15, 0), (20, 5), (20, 15), (15, 20), (0, 20)]
    arc = r.moves[4]
    assert arc["kind"] == "arc" and arc["dir"] == "ccw" and arc["center"]["X"] == 15 and arc["center"]["Y"] == 15
    assert run_path(capsys, tmp_path, "G01 X20. F100 ,C5.\nM30\n").alarm["code"] == "0x0207"
    # ,A linear angle: X from Z and the angle (lathe, angle from +Z)
    r = run_path(capsys, tmp_path, "G00 X0 Z0\nG01 Z-10. ,A135. F0.2\n", profile="nc5-lathe-a")
    assert r.ends("X", "Z")[-1] == (pytest.approx(20.0), -10.0)


def test_g53_reaches_machine_point_past_g54_g92_and_g43(capsys, tmp_path):
    """N§3.6.3: G53 X_ Z_ is a machine position whatever G54, G92 and G43 H say; G43 ends there for good
    (note 4, N§3.9 note 2), so the G53 move's work point and every later Z are without the 12.7 mm;
    G54 and the G92 shift stay. Hand-computed: work origin X = 100 + 10 (G92), Y = 50 + 10, Z = -200."""
    prog = ("G10 L2 P1 X100. Y50. Z-200.\nG10 L10 P1 R12.7\nG90 G54 G00 X10. Y10. Z10.\nG92 X0 Y0\n"
            "G43 H1 Z5.\nG53 X20. Z-50.\nG00 Y5.\nX0 Z0\n")
    r = run_path(capsys, tmp_path, prog, "--vars", "20308,20312")
    assert r.machine("X", "Y", "Z") == [(110, 60, -190), (110, 60, -182.3), (20, 60, -50), (20, 65, -50),
                                        (110, 65, -200)]
    g53 = r.moves[2]
    assert g53["kind"] == "rapid" and g53["exact_stop"] and (g53["work"]["X"], g53["work"]["Z"]) == (-90.0, 150.0)
    assert r.vars == {"20308": 49.0, "20312": 54.0}  # G49 afterwards, work system unchanged


def test_g53_ends_lathe_tool_offset_and_keeps_g54(capsys, tmp_path):
    """Lathe: the tool offset is the length compensation G53 cancels (decision: language.md, G53).
    G54 X20. (diameter) = radius 10; T0101 geometry X10. (diameter) = 5, Z-5."""
    prog = "G10 L2 P1 X20. Z-100.\nG10 L10 P1 X10. Z-5.\nG54 T0101\nG00 X20. Z10.\nG53 X80. Z-50.\nG00 X20.\n"
    r = run_path(capsys, tmp_path, prog, profile="nc5-lathe-a")
    assert r.machine("X", "Z") == [(25, -95), (40, -50), (20, -50)]
    assert r.ends("X", "Z") == [(20, 10), (60, 50), (20, 50)]


def test_g53_suspends_radius_compensation_for_its_move(capsys, tmp_path):
    """N§3.6.3 note 4: radius compensation is cancelled in the G53 move (it reaches machine X60 Y40
    exactly) and restored by the next motion block (start-up to Y35 = Y40 - R5 under G41)."""
    prog = "G10 L12 P1 R5.\nG90 G00 X0 Y0\nG41 D1 G01 X20. F500\nY20.\nG53 X60. Y40.\nG01 X0. Y40.\nG40 X-20.\n"
    r = run_path(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g53 = next(m for m in r.moves if "G53" in m.get("tags", ()))
    assert (g53["start"]["X"], g53["start"]["Y"]) == (15.0, 20.0) and "cancel" in g53["tags"]
    assert (g53["end"]["X"], g53["end"]["Y"]) == (60.0, 40.0)
    after = r.moves[r.moves.index(g53) + 1]
    assert "comp" in after["tags"] and (after["end"]["X"], after["end"]["Y"]) == (0.0, 35.0)


def test_g53_in_g91_keeps_g43_and_g53_alone_ends_it(capsys, tmp_path):
    """An ignored G91 G53 cancels nothing; a G90 G53 without axis words stands still but still ends G43
    (decision: language.md, G53)."""
    r = run_path(capsys, tmp_path, "G10 L10 P1 R12.7\nG43 H1 Z5.\nG91 G53 Z0.\nG90 G00 Z6.\n", "--vars", "20308")
    assert r.machine("Z") == [(17.7,), (18.7,)] and r.vars == {"20308": 43.0}
    r = run_path(capsys, tmp_path, "G10 L10 P1 R12.7\nG43 H1 Z5.\nG53\nG00 Z7.\n", "--vars", "20308")
    assert r.machine("Z") == [(17.7,), (7.0,)] and r.vars == {"20308": 49.0}


def test_g28_suspends_radius_compensation_and_the_next_motion_block_restores_it(capsys, tmp_path):
    """N§3.5.1 and the G41/G42 note 4 (both manuals): under G41 a G28 goes to its intermediate point
    and the reference point without compensation, and the next motion block starts it again (G01 to
    X0 Y40 heads +Y from the reference point X0 Y0, so G41 puts it at X-5); it is not a G40."""
    prog = "G10 L12 P1 R5.\nG90 G00 X0 Y0\nG41 D1 G01 X20. F500\nY20.\nG28 X60. Y40.\nG01 X0. Y40.\nG40 X-20.\n"
    r = run_path(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    ref = next(m for m in r.moves if "reference" in m.get("tags", ()))
    mid = next(m for m in r.moves if "intermediate" in m.get("tags", ()))
    assert (mid["end"]["X"], mid["end"]["Y"]) == (60.0, 40.0)  # the intermediate point itself, uncompensated
    assert (ref["end"]["X"], ref["end"]["Y"]) == (0.0, 0.0)  # N2.060 reference point (0 on this profile)
    after = r.moves[r.moves.index(ref) + 1]
    assert "comp" in after["tags"] and (after["end"]["X"], after["end"]["Y"]) == (-5.0, 40.0)
