"""Format rows of the NC5 G command guide's lathe chapters (N§3.14 hole cycles, N§3.15 turning cycles,
N§3.16 threading), written as the manual writes them on a type-A lathe (X diameter, U/W/H incremental) and
checked for the cycle the row's description promises: pass depths, allowances, pecks, dwell, end points.
Row ids as in docs/formats.md (`N<section>-<k>`).
"""

from __future__ import annotations

import pytest

from lang_helpers import PathResult, run_path
from tests.conftest import ROOT

C_BENCH = str(ROOT / "benches" / "lathe-c-axis.toml")  # X, Z and a C axis (type A)


def _ok(r: PathResult) -> PathResult:
    assert r.code == 0, r.alarm
    return r


def _of(r: PathResult, *tag: str) -> list[dict]:
    return [m for m in r.moves if tuple(m.get("tags") or ())[:len(tag)] == tag]


def _xz(moves: list[dict]) -> list[tuple[float, float]]:
    return [(round(m["work"]["X"], 4), round(m["work"]["Z"], 4)) for m in moves]


def _lathe(capsys, tmp_path, prog: str, *args: str) -> PathResult:
    return _ok(run_path(capsys, tmp_path, prog, *args, profile="nc5-lathe-a"))


# ---- N§3.14 hole cycles with the C axis

def test_g83_face_drilling_x_c_z_r_q_p_f_k_l(capsys, tmp_path):
    """N3.14.1-1 `G83 X_ C_ Z_ R_ Q_ P_ F_ K_ L_` (N§3.14.1): positioned at X and C, drilled along Z to the
    bottom Z from R (relative to the initial point) in pecks of Q (µm), L1 = deep peck back to R, dwell P ms
    at the bottom, then back to the initial point (type A)."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5. C0\nM03 S500\nG83 X0 C45. Z-10. R-2. Q3000 P200 F0.1 K1 L1\nG80\nM30\n",
               "--bench", C_BENCH)
    pos = _of(r, "G83", "position")[0]
    assert (pos["work"]["X"], pos["work"]["C"]) == (0.0, 45.0)
    assert [m["work"]["Z"] for m in _of(r, "G83", "peck")] == [0.0, -3.0, -6.0, -9.0, -10.0]
    assert {m["work"]["Z"] for m in _of(r, "G83", "retract")} == {3.0}  # R = 5 - 2
    assert [m["duration"] for m in _of(r, "G83", "dwell")] == [0.2] and r.moves[-1]["work"]["Z"] == 5.0


def test_g87_side_drilling_u_h_w(capsys, tmp_path):
    """N3.14.1-2 `G87 U_ H_ W_` (N§3.14.1: G87 drills along X; X/U is the hole bottom, Z/W and C/H position;
    on type A, U H W are increments): drilled from the initial X toward the bottom U below it."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z5. C0\nM03 S500\nG87 U-40. H90. W-15. R-2. Q3000 P200 F0.1 K1 L1\nG80\n"
               "M30\n", "--bench", C_BENCH)
    pos = _of(r, "G87", "position")[0]["work"]
    assert (pos["X"], pos["Z"], pos["C"]) == (60.0, -10.0, 90.0)
    pecks = [m["work"]["X"] for m in _of(r, "G87", "peck")]
    assert pecks[-1] == 20.0 and pecks[0] == 50.0  # R: 2 mm (radius) in, then 3 mm pecks (6 on the diameter)
    assert _of(r, "G87", "return")[-1]["work"]["X"] == 60.0


def test_g84_face_tapping(capsys, tmp_path):
    """N3.14.2-1 `G84 X_ C_ Z_ R_ Q_ P_ F_ K_ L_` (N§3.14.2): in at F (the lead, mm/rev) to Z, dwell P,
    spindle reversed, out at the same lead to R."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5. C0\nM03 S500\nG84 X20. C30. Z-10. R-2. Q0 P200 F1.5 K1 L0\nG80\nM30\n",
               "--bench", C_BENCH)
    tap, out = _of(r, "G84", "tap")[0], _of(r, "G84", "tap_out")[0]
    assert (tap["work"]["X"], tap["work"]["C"], tap["work"]["Z"]) == (20.0, 30.0, -10.0)
    assert (tap["feed"], tap["per_rev"], out["feed"], out["work"]["Z"]) == (1.5, True, 1.5, 3.0)
    assert [m["duration"] for m in _of(r, "G84", "dwell")] == [0.2]


def test_g88_side_tapping_u_h_w(capsys, tmp_path):
    """N3.14.2-2 `G88 U_ H_ W_` (N§3.14.2: G88 taps along X; U the hole bottom increment, H and W position)."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5. C0\nM03 S500\nG88 U-20. H90. W-5. R-2. P200 F1.5\nG80\nM30\n",
               "--bench", C_BENCH)
    assert _xz(_of(r, "G88", "tap")) == [(10.0, 0.0)] and _of(r, "G88", "tap")[0]["work"]["C"] == 90.0
    assert _xz(_of(r, "G88", "tap_out")) == [(26.0, 0.0)]


def test_g85_face_boring(capsys, tmp_path):
    """N3.14.3-1 `G85 X_ C_ Z_ R_ P_ F_ K_` (N§3.14.3): feed in to Z, dwell P, feed out to R."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5. C0\nM03 S500\nG85 X20. C0 Z-8. R-2. P100 F0.1 K1\nG80\nM30\n",
               "--bench", C_BENCH)
    assert [m["tags"][1] for m in _of(r, "G85")] == ["position", "approach", "cut", "dwell", "cut_out", "return"]
    assert _xz(_of(r, "G85", "cut")) == [(20.0, -8.0)] and _of(r, "G85", "cut_out")[0]["feed"] == 0.1


def test_g89_side_boring_u_h_w(capsys, tmp_path):
    """N3.14.3-2 `G89 U_ H_ W_` (N§3.14.3: along X, U the bottom increment, H W position)."""
    r = _lathe(capsys, tmp_path, "G00 X20. Z0 C0\nM03 S500\nG89 U-10. H45. W-3. R-2. P100 F0.1\nG80\nM30\n",
               "--bench", C_BENCH)
    assert _xz(_of(r, "G89", "cut")) == [(10.0, -3.0)] and _of(r, "G89", "cut")[0]["work"]["C"] == 45.0
    assert [m["duration"] for m in _of(r, "G89", "dwell")] == [0.1] and _xz(_of(r, "G89", "cut_out")) == [(16.0, -3.0)]


def test_g80_cancels_the_lathe_hole_cycle(capsys, tmp_path):
    """N3.14.4-1 `G80` (N§3.14.4): after G80 an axis word moves plainly; group 9 reads 80."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5. C0\nG83 X0 Z-4. R-2. F0.1\nG80\n#100=#20309\nG00 X40. Z10.\nM30\n",
               "--vars", "100", "--bench", C_BENCH)
    assert r.vars["100"] == 80.0 and not r.moves[-1].get("tags") and _xz(r.moves[-1:]) == [(40.0, 10.0)]


# ---- N§3.15 turning cycles

CONTOUR = "N10 G00 X20.\nG01 Z-20. F0.1\nX40.\nN20 Z-40.\n"


def test_g71_stock_removal_and_g70_finish(capsys, tmp_path):
    """N3.15.2-1 `G71 U_ R_ H_`, N3.15.2-2 `G71 P_ Q_ U_ W_ F_ S_ T_`, N3.15.1-1 `G70 P_ Q_` (N§3.15.1-2):
    rough passes U deep (radius) at F, each escaping R, leaving U (diameter) / W, with the tool T and spindle
    speed S of the second block; G70 then runs blocks P-Q at their own feed."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\nG71 U2. R0.5 H0\nG71 P10 Q20 U0.4 W0.1 F0.25 S600 T0101\n"
               + CONTOUR + "G70 P10 Q20\nM30\n", "--vars", "20403,20404")
    rough = _of(r, "G71", "rough")
    assert [round(m["work"]["X"], 4) for m in rough] == [56.0, 52.0, 48.0, 44.0, 40.0, 36.0, 32.0, 28.0, 24.0, 20.4]
    assert rough[0]["work"]["Z"] == -39.9 and rough[-1]["work"]["Z"] == -19.9 and rough[0]["feed"] == 0.25
    retract = _of(r, "G71", "retract")[0]["work"]
    assert (retract["X"], retract["Z"]) == (57.0, -39.4)  # R0.5 escape, 45 degrees
    assert _xz(_of(r, "G70", "finish")) == [(20.0, 5.0), (20.0, -20.0), (40.0, -20.0), (40.0, -40.0)]
    assert _of(r, "G70", "finish")[1]["feed"] == 0.1 and r.vars == {"20403": 101.0, "20404": 600.0}


def test_g72_facing_stock_removal(capsys, tmp_path):
    """N3.15.3-1 `G72 W_ R_ H_`, N3.15.3-2 `G72 P_ Q_ U_ W_ F_ S_ T_` (N§3.15.3): passes W deep along Z,
    cut radially to the contour plus U, leaving W on the faces."""
    r = _lathe(capsys, tmp_path, "G00 X82. Z2.\nM03 S500\nG72 W2. R0.5 H0\nG72 P10 Q20 U0.4 W0.2 F0.25 S600 T0101\n"
               "N10 G00 Z-6.\nG01 X40. F0.1\nN20 Z0\nM30\n")
    assert _xz(_of(r, "G72", "rough")) == [(40.4, 0.0), (40.4, -2.0), (40.4, -4.0), (40.4, -5.8)]


def test_g73_profile_rough_turning(capsys, tmp_path):
    """N3.15.4-1 `G73 U_ W_ R_ H_`, N3.15.4-2 `G73 P_ Q_ U_ W_ F_ S_ T_` (N§3.15.4): R passes of the
    contour, the first offset by U (X, radius) and W (Z), the last on the contour plus the allowances."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\nG73 U4. W2. R3 H0\nG73 P10 Q20 U0.4 W0.1 F0.25 S600 T0101\n"
               "N10 G00 X20. Z2.\nG01 Z-20. F0.1\nN20 X50.\nM30\n")
    firsts = [m for m in _of(r, "G73", "pass") if m["kind"] == "rapid"]
    assert _xz(firsts) == [(28.4, 4.1), (24.4, 3.1), (20.4, 2.1)]  # X: 20+0.4+2*4*(2,1,0)/2, Z: 2+0.1+2*(2,1,0)/2
    assert {m["feed"] for m in _of(r, "G73", "pass") if m["kind"] == "line"} == {0.25}


@pytest.mark.parametrize("second", ["G74 X20. Z-10. P5000 Q3000 R0 F0.1", "G74 U20. W-15. P5000 Q3000 R0 F0.1"])
def test_g74_end_face_peck_drilling(capsys, tmp_path, second):
    """N3.15.5-1 `G74 R_`, N3.15.5-2 `G74 X_ Z_ P_ Q_ R_ F_`, N3.15.5-3 `[G74] U_ W_` (N§3.15.5): pecks of
    Q (µm) along Z to Z/W, each backing off R; then X shifts by P (µm, radius) until X/U."""
    r = _lathe(capsys, tmp_path, "G00 X0 Z5.\nM03 S500\nG74 R1.\n" + second + "\nM30\n")
    pecks = _of(r, "G74", "peck")
    assert [m["work"]["Z"] for m in pecks[:5]] == [2.0, -1.0, -4.0, -7.0, -10.0]
    assert sorted({m["work"]["X"] for m in pecks}) == [0.0, 10.0, 20.0]  # P5000: 5 mm radius = 10 on X
    assert [m["work"]["Z"] for m in _of(r, "G74", "retract")[:2]] == [3.0, 0.0]  # back off R1


@pytest.mark.parametrize("second", ["G75 X40. Z-16. P3000 Q3000 R0 F0.1", "G75 U-20. W-6. P3000 Q3000 R0 F0.1"])
def test_g75_outer_diameter_grooving(capsys, tmp_path, second):
    """N3.15.6-1 `G75 R_`, N3.15.6-2 `G75 X_ Z_ P_ Q_ R_ F_`, N3.15.6-3 `[G75] U_ W_` (N§3.15.6): pecks of
    P (µm, radius) along X to X/U, each backing off R; Z shifts by Q until Z/W."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z-10.\nM03 S500\nG75 R1.\n" + second + "\nM30\n")
    pecks = _of(r, "G75", "peck")
    assert [m["work"]["X"] for m in pecks[:4]] == [54.0, 48.0, 42.0, 40.0]
    assert sorted({m["work"]["Z"] for m in pecks}) == [-16.0, -13.0, -10.0]


@pytest.mark.parametrize("block", ["G90 X50. Z-30. R-5. F0.2", "G90 U-10. W-35. R-5. F0.2"])
def test_g90_outer_diameter_cutting_cycle(capsys, tmp_path, block):
    """N3.15.7-1 `G90 X_ Z_ R_ F_`, N3.15.7-2 `[G90] U_ W_` (N§3.15.7): rapid in to X + 2R (taper R, radius),
    cut to (X, Z), out along X, rapid back to the start."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\n" + block + "\nM30\n")
    assert _xz(_of(r, "G90")) == [(40.0, 5.0), (50.0, -30.0), (60.0, -30.0), (60.0, 5.0)]
    assert [m["kind"] for m in _of(r, "G90")] == ["rapid", "line", "line", "rapid"]


@pytest.mark.parametrize("block", ["G94 X20. Z-3. R-2. F0.2", "G94 U-40. W-8. R-2. F0.2"])
def test_g94_end_face_cutting_cycle(capsys, tmp_path, block):
    """N3.15.8-1 `G94 X_ Z_ R_ F_`, N3.15.8-2 `[G94] U_ W_` (N§3.15.8): rapid in Z to Z + R (taper), face
    to (X, Z), out along Z, rapid back."""
    r = _lathe(capsys, tmp_path, "G00 X60. Z5.\nM03 S500\n" + block + "\nM30\n")
    assert _xz(_of(r, "G94")) == [(60.0, -5.0), (20.0, -3.0), (20.0, 5.0), (60.0, 5.0)]


# ---- N§3.16 threading

def test_g32_threading_with_start_angle(capsys, tmp_path):
    """N3.16.1-1 `G32 X_ Z_ F_ Q_` (N§3.16.1): one thread move at lead F from the spindle angle Q
    (0.001 degree)."""
    r = _lathe(capsys, tmp_path, "G00 X30. Z5.\nM03 S500\nG32 X30. Z-20. F1.5 Q90000\nM30\n")
    th = r.moves[-1]
    assert (th["kind"], th["lead"], th["start_angle"]) == ("thread", 1.5, 90.0)
    assert _xz([th]) == [(30.0, -20.0)]


@pytest.mark.parametrize("block", ["G92 X29. Z-20. R-1. F1.5 Q0", "G92 U-11. W-25. R-1. F1.5 Q0"])
def test_g92_threading_cycle(capsys, tmp_path, block):
    """N3.16.2-1 `G92 X_ Z_ R_ F_ Q_`, N3.16.2-2 `[G92] U_ W_` (N§3.16.2): rapid in to X + 2R, thread to
    (X, Z) at lead F (with the pull-out chamfer), rapid out and back."""
    r = _lathe(capsys, tmp_path, "G00 X40. Z5.\nM03 S500\n" + block + "\nM30\n")
    g = _of(r, "G92")
    assert _xz(g[:1]) == [(27.0, 5.0)] and _xz(g[-3:-2]) == [(32.0, -20.0)] and _xz(g[-1:]) == [(40.0, 5.0)]
    assert {m["lead"] for m in g if m["kind"] == "thread"} == {1.5}


@pytest.mark.parametrize("second", ["G76 X28. Z-20. P975 Q400 R0 L0 F1.5", "G76 U-12. W-25. P975 Q400 R0 L0 F1.5"])
def test_g76_multiple_thread_cutting_cycle(capsys, tmp_path, second):
    """N3.16.3-1 `G76 P_ Q_ R_`, N3.16.3-2 `G76 X_ Z_ P_ Q_ R_ L_ F_`, N3.16.3-3 `[G76] U_ W_` (N§3.16.3 and
    its example): P mmrraa (m finish passes, chamfer r, angle a), Q the least depth (µm), R the finish
    allowance; then height P, first depth Q (µm), taper R, infeed L, lead F (decision A41)."""
    r = _lathe(capsys, tmp_path, "G00 X40. Z5.\nM03 S500\nG76 P021060 Q50 R0.05\n" + second + "\nM30\n")
    rough = [m for m in _of(r, "G76", "rough") if "chamfer" not in m["tags"]]
    finish = [m for m in _of(r, "G76", "finish") if "chamfer" not in m["tags"]]
    assert round(rough[0]["work"]["X"], 4) == round(28.0 + 2 * 0.975 - 2 * 0.4, 4)  # first depth 0.4
    assert [round(m["work"]["X"], 4) for m in finish] == [28.0, 28.0]  # m = 2 finish passes at the root
    assert round(rough[-1]["work"]["X"], 4) == 28.1  # the last rough pass leaves R0.05 (radius)
    assert {m["lead"] for m in rough + finish} == {1.5}


@pytest.mark.parametrize("block", ["G34 X40. Z-20. F2. Q0 K0.1", "G34 U0 W-25. F2. Q0 K0.1"])
def test_g34_variable_lead_threading(capsys, tmp_path, block):
    """N3.16.4-1 `G34 X_ Z_ F_ Q_`, N3.16.4-2 `[G34] U_ W_` (N§3.16.4): lead F growing by K per turn
    (decision A43)."""
    r = _lathe(capsys, tmp_path, "G00 X40. Z5.\nM03 S500\n" + block + "\nM30\n")
    th = r.moves[-1]
    assert (th["kind"], th["lead"], th["lead_change"]) == ("thread", 2.0, 0.1) and _xz([th]) == [(40.0, -20.0)]
