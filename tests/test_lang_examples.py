"""Worked examples of the lathe manual (E-L01..E-L33) and §7.3 prose assertions, through `hil path`."""

from __future__ import annotations

import pytest

from lang_helpers import run_path

LA = "nc5-lathe-a"


def test_e_l01_rapid(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "X100. Z100.\nG00 X50.0 Z60.0\n", profile=LA)
    assert r.ends("X", "Z") == [(100, 100), (50, 60)] and r.moves[1]["kind"] == "rapid"
    r = run_path(capsys, tmp_path, "X100. Z100.\nG00 U25.0 W-40.0\n", profile=LA)
    assert r.ends("X", "Z")[-1] == (125.0, 60.0)  # as printed (doc error U25. for U-50.)


def test_e_l02_g01_feed_per_minute(capsys, tmp_path):
    prog = "G98;\nG54 X0.0 Z0.0;\nG00 X20.0;\nG01 Z-18.0 F500;\nX30.0;\nX40.0 Z-26.0;\nZ-41.0;\n"
    r = run_path(capsys, tmp_path, prog, profile=LA)
    assert r.ends("X", "Z")[1:] == [(20, 0), (20, -18), (30, -18), (40, -26), (40, -41)]
    assert [m["feed"] for m in r.moves[2:]] == [500.0] * 4
    assert [m["end"]["X"] for m in r.moves[2:4]] == [10.0, 15.0]


def test_e_l05_o0003_profile(capsys, tmp_path):
    prog = """O0003
G54 X0 Z0 S800 M3
G0 X41. Z0. Z2.
G0 X20. Z0.5
G01 Z-5. F0.12
G02 Z-15. R8. (1)
G03 Z-35. R13. (2)
G02 Z-45. R7.5 (3)
G03 X28. Z-65. R11. (4)
G01 X30. Z-73.
X40.2
M5
M30
"""
    r = run_path(capsys, tmp_path, prog, profile=LA)
    assert r.code == 0, r.alarm
    ends = r.ends("X", "Z")[2:]
    assert ends == [(20, 0.5), (20, -5), (20, -15), (20, -35), (20, -45), (28, -65), (30, -73), (40.2, -73)]
    for m, rad in zip(r.moves[4:8], (8.0, 13.0, 7.5, 11.0)):
        c = m["center"]
        for p in (m["start"], m["end"]):
            assert ((p["X"] - c["X"]) ** 2 + (p["Z"] - c["Z"]) ** 2) ** 0.5 == pytest.approx(rad, abs=1e-6)
    assert r.moves[3]["feed"] == 0.12  # feed per revolution by default on a type A lathe (A3)


def test_e_l07_g09_one_shot_exact_stop(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G0 X0.0 Z0.0\nG09 G01 Z-50. F0.2\nG09 X50.0\nZ-50.0\n", profile=LA)
    assert [m.get("exact_stop", False) for m in r.moves[1:]] == [True, True, False]
    r = run_path(capsys, tmp_path, "G61 G01 Z-5. F0.2\nZ-6.\nG64 Z-7.\n", profile=LA)
    assert [m.get("exact_stop", False) for m in r.moves] == [True, True, False]


def test_e_l08_g10_tool_data_both_forms(capsys, tmp_path):
    for form in ("G10 L10 P1 X-50. W20. R2. Q3", "G10 P10001 X-50. W20. R2. Q3"):
        r = run_path(capsys, tmp_path, f"G10 L10 P1 Z5.\n{form}\nM30\n", "--vars", "6001,6401,7201,7601",
                     profile="lathe-2018")
        assert r.vars == {"6001": -50.0, "6401": 25.0, "7201": 2.0, "7601": 3.0}


def test_e_l09_e_l10_e_l11_reference_returns(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G0 X5. Z5.\nG28 X10. Z10.\nG29 X5. Z15.\n", profile=LA)
    assert r.ends("X", "Z") == [(5, 5), (10, 10), (0, 0), (10, 10), (5, 15)]
    r = run_path(capsys, tmp_path, "G28 X1. Z1.\nG30 P2 X15.0 Z15.0\nG29 X20.0 Z25.0\n", profile=LA,
                 *())
    assert r.ends("X", "Z")[-2:] == [(15, 15), (20, 25)]  # G29 uses the latest intermediate point


def test_e_l12_g31_lathe(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G00 X5. Z5.\nG98 G01 G31 Z25.0 F50.\nG01 X40.0 Z50.0 F100.\n", profile=LA)
    assert r.ends("X", "Z") == [(5, 5), (5, 25), (40, 50)]


def test_e_l13_g32_passes(capsys, tmp_path):
    passes = "".join(f"X{d}\nG32 Z-30. F1.5\nG0 X40.\nZ15.\n" for d in ("17.45", "17.20", "17.00", "16.85", "16.80"))
    r = run_path(capsys, tmp_path, "T0202\nM3 S1000\nG0 X40.\nZ15.\n" + passes + "M30\n", profile=LA)
    threads = [m for m in r.moves if m["kind"] == "thread"]
    assert [m["start"]["X"] * 2 for m in threads] == pytest.approx([17.45, 17.2, 17.0, 16.85, 16.8])
    assert all(m["work"]["Z"] == -30.0 for m in threads)


def test_e_l17_e_l18_g52_lathe(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G54 X10. Z10.;\nG52 X20.0 Z40.0;\nG00 X20.0 Z20.0;\n", profile=LA)
    assert r.machine("X", "Z")[-1] == (20.0, 60.0)  # G54 (X40 diameter, Z60)
    prog = "G10 L2 P3 X100. Z0\nG54 G00 X5. Z10.;\nG52 X10. Z20.;\nG00 X20. Z20.;\nG56 G00 X10. Z40.;\n"
    r = run_path(capsys, tmp_path, prog, profile=LA)
    assert [m["work"]["X"] for m in r.moves] == [5.0, 20.0, 10.0]
    assert r.machine("X", "Z") == [(2.5, 10.0), (15.0, 40.0), (60.0, 60.0)]


def test_e_l19_g53_lathe(capsys, tmp_path):
    prog = "G53U150.W-150.\nG53X50.Z-50.\nG1G53X100.Z-100.F1000\nX50.\n"
    r = run_path(capsys, tmp_path, prog, profile=LA)
    assert [m["kind"] for m in r.moves] == ["rapid", "rapid", "line"]
    assert r.machine("X", "Z")[:2] == [(25.0, -50.0), (50.0, -100.0)]
    assert r.moves[2]["feed"] == 1000.0


def test_e_l20_extended_wcs(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G10 L20 P10 X0 Z-7.\nG54 P10 G00 X0 Z0\n", profile=LA)
    assert r.machine("Z") == [(-7.0,)]


def test_e_l21_g65_argument(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G65 P9 A5.0\n#101=1\nM30\nO0009\n#100=#1\nM99\n", "--vars", "100-101",
                 profile="lathe-2018")
    assert r.vars == {"100": 5.0, "101": 1.0}


@pytest.mark.parametrize("block", ["G90 X30. Z30.", "G91 X20. Z20.", "G90 U20. W20.", "G91 U20. W20."])
def test_e_l30_type_b_absolute_incremental(capsys, tmp_path, block):
    r = run_path(capsys, tmp_path, f"G90 G00 X10. Z10.\n{block}\n", profile="nc5-lathe-b")
    assert r.ends("X", "Z")[-1] == (30.0, 30.0)


def test_e_l31_type_b_mixed_needs_decimal_points(capsys, tmp_path):
    prog = ("G94;\nG00 G90 G54 X0 Z0;\nG01 X10. F500;\nX20. Z-10;\nG91 Z-10.0;\nX10.0;\nG90 Z-40.0;\n"
            "G00 X50. Z5. ;\n")
    r = run_path(capsys, tmp_path, prog, "--param", "N8.018 Bit10=1", profile="nc5-lathe-b")
    assert r.ends("X", "Z")[1:] == [(10, 0), (20, -10), (20, -20), (30, -20), (30, -40), (50, 5)]
    r = run_path(capsys, tmp_path, prog, profile="nc5-lathe-b")
    assert r.ends("X", "Z")[2] == (20.0, -0.01)  # default rule: Z-10 is 0.010 mm


def test_e_l32_g50_clamp_and_setting(capsys, tmp_path):
    prog = "M3 S1500;\nG0 G54 X0. Z0.;\nG0 X10.;\nG50 S1000;\nG50 X0. Z0.;\nG1 W-20. F0.25;\nU10.;\nG0 X30.;\nM5 ;\nM30 ;\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "21016", profile=LA)
    assert r.machine("X", "Z")[2:] == [(5.0, -20.0), (10.0, -20.0), (20.0, -20.0)]
    assert r.ends("X", "Z")[2:] == [(0, -20), (10, -20), (30, -20)]
    assert r.vars["21016"] == 40.0  # after M30 the display is G54 again (X40 diameter)


def test_e_l33_feed_per_rev(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "M3 S1000\nG99 G01 Z-20. F0.35\n", profile=LA)
    assert r.moves[0]["feed"] == 0.35


def test_733_7_g53_in_g91_keeps_modal_codes(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G91 G01 G53 X10. F100\nX5.\n")
    assert [m["kind"] for m in r.moves] == ["line"] and r.ends("X") == [(5.0,)]


def test_733_4_m98_without_p_calls_current_program_from_h(capsys, tmp_path):
    prog = "#100=0\nM98 H20\nM30\nN20 #100=#100+1\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100")
    assert r.vars["100"] == 1.0


def test_733_9_g31_under_g41_is_refused(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G41 D1 G01 X1. F100\nG31 X10.\n")
    assert r.code == 1 and r.alarm["line"] == 2
