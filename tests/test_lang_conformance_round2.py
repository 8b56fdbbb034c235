"""Manual conformance round 2 (issue 19): behaviours held against the NC5 G command guide (N§ = NC5 guide,
App. A = its alarm table). Each test failed on main before its fix."""

from __future__ import annotations

import pytest

from lang_helpers import run_path

MACRO = "O9000\n#100=#100+#1\n#101=#101+1\n#1=#1+10.\nM99\n"


def test_g65_l_repeats_the_whole_call_with_fresh_arguments_n3_11_4_4_example_1(capsys, tmp_path):
    """N§3.11.4.4 format 'G65 P_ L_ <argument>', Example 1 (3): L is the number of repetitions; each one is
    the call again, so the macro's change of its own #1 does not reach the next repetition."""
    r = run_path(capsys, tmp_path, "#100=0\n#101=0\nG65 P9000 L3 A1.\nM30\n" + MACRO, "--vars", "100-101")
    assert r.code == 0, r.alarm
    assert (r.vars["101"], r.vars["100"]) == (3.0, 3.0)  # three passes, each with A=1 (not 1+11+21)


def test_g66_l_runs_the_macro_l_times_per_moving_block_n3_11_4_5(capsys, tmp_path):
    """N§3.11.4.5 'G66 P_ L_ <argument>': the macro runs L times after each block that moves an axis,
    with the arguments of the G66 block every time."""
    r = run_path(capsys, tmp_path, "#100=0\n#101=0\nG66 P9000 L2 A1.\nG00 X10.\nX20.\nG67\nM30\n" + MACRO,
                 "--vars", "100-101")
    assert r.code == 0, r.alarm
    assert (r.vars["101"], r.vars["100"]) == (4.0, 4.0)  # 2 blocks x L2, each pass with A=1


def test_m98_p_l_repeats_the_subprogram_app_a_0x0251(capsys, tmp_path):
    """App. A 0x0251: 'Only P_, H(Q)_, L_ can be used' with M98, so L is legal; it is the repeat count
    (decision A21 revisited)."""
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nM98 P2000 L3\nM30\nO2000\nG91 G01 X1. F100\nG90\nM99\n")
    assert r.code == 0, r.alarm
    assert [e[0] for e in r.ends("X")][-3:] == [1.0, 2.0, 3.0]


def test_m98_l0_does_not_call(capsys, tmp_path):
    """A repeat count of 0 runs the subprogram no time (as G65 L0)."""
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nM98 P2000 L0\nM30\nO2000\nG91 G01 X1. F100\nG90\nM99\n")
    assert r.code == 0, r.alarm
    assert r.ends("X")[-1] == (0.0,)


@pytest.mark.parametrize("block", ["G54 X0 Y0", "G55", "G28 X0", "G30 X0", "G29 X10."])
def test_g68_active_refuses_wcs_and_reference_returns_app_a_0x025f(capsys, tmp_path, block):
    """App. A 0x025F and N§3.12.5: with G68 rotation on, G54–G59, G28/G29/G30 (and 3-D arcs) are
    refused until G69."""
    r = run_path(capsys, tmp_path, f"G90 G00 X0 Y0\nG28 X0\nG68 X0 Y0 R30.\n{block}\nG69\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x025F" and r.alarm["line"] == 4, r.alarm


def test_after_g69_the_same_blocks_run(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG68 X0 Y0 R30.\nG01 X10. F100\nG69\nG54 X0 Y0\nG28 X0\nM30\n")
    assert r.code == 0, r.alarm


def _circle_through(a, b, c):
    import numpy as np
    a, b, c = map(np.array, (a, b, c))
    u, v = b - a, c - a
    w = np.cross(u, v)
    centre = a + (np.cross(w, u) * v.dot(v) + np.cross(v, w) * u.dot(u)) / (2 * w.dot(w))
    return centre, float(np.linalg.norm(a - centre)), w / np.linalg.norm(w)


@pytest.mark.parametrize("code, body", [
    ("G2.4", "G90 G2.4 X10. Y10. Z5. F300\nG2.4 X20. Y0 Z10.\n"),
    ("G3.4", "G90 G3.4 X10. Y10. Z5. F300\nG3.4 X20. Y0 Z10.\n"),
    # N§3.3.4 note (1): under G91 the middle point is relative to the start, the end to the middle point
    ("G2.4", "G91 G2.4 X10. Y10. Z5. F300\nG2.4 X10. Y-10. Z5.\nG90\n"),
])
def test_three_point_arc_in_the_manuals_two_block_format_n3_3_4(capsys, tmp_path, code, body):
    """N§3.3.4 format table: 'G2.4 X1 Y1 Z1 (Middle-point position)' then 'G2.4 X2 Y2 Z2 (End-point position)':
    the 3-D arc from the current point through the middle point to the end point."""
    import numpy as np
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0 Z0\n" + body + "M30\n")
    assert r.code == 0, r.alarm
    arc = [m for m in r.moves if m["line"] == 3]
    assert arc and all(code in m["tags"] for m in arc)
    assert not [m for m in r.moves if m["line"] == 2]  # the middle-point block does not move by itself
    centre, radius, normal = _circle_through((0, 0, 0), (10, 10, 5), (20, 0, 10))
    pts = [np.array([m["end"][a] for a in "XYZ"]) for m in arc]
    assert tuple(pts[-1]) == (20.0, 0.0, 10.0)
    for p in pts:  # every vertex on the circle: on its sphere and in its plane
        assert np.linalg.norm(p - centre) == pytest.approx(radius, abs=2e-6)
        assert float((p - centre).dot(normal)) == pytest.approx(0.0, abs=2e-6)
    # the path passes through the middle point (within the chord tolerance, 0.5 µm)
    mid = np.array([10.0, 10.0, 5.0])
    seg = min(np.linalg.norm(np.cross(q - p, p - mid)) / np.linalg.norm(q - p) for p, q in zip(pts, pts[1:])
              if (mid - p).dot(q - p) >= 0 and (mid - q).dot(p - q) >= 0)
    assert seg < 0.5e-3


def test_three_point_middle_without_end_point_is_0x0260(capsys, tmp_path):
    """App. A 0x0260 'Insufficient information for circle command by three points method'."""
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0 Z0\nG2.4 X10. Y10. Z5. F300\nG01 X20.\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x0260" and r.alarm["line"] == 3, r.alarm


def test_three_point_arc_is_refused_under_g68_app_a_0x025f(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0 Z0\nG68 X0 Y0 R30.\nG2.4 X10. Y10. Z5. F300\nG2.4 X20. Y0 Z10.\nM30\n")
    assert r.code == 1 and r.alarm["code"] == "0x025F" and r.alarm["line"] == 3, r.alarm


def test_path_text_prints_one_convention_and_says_which(capsys, tmp_path):
    """Issue 19 item 6: the lathe listing printed diameter end points with radius centres in one line."""
    from hil.cli import main
    f = tmp_path / "l.nc"
    f.write_text("G00 X40. Z5.\nG01 Z-10. F100\nG02 X60. Z-20. R10.\nM30\n")
    capsys.readouterr()
    assert main(["path", str(f), "--profile", "nc5-lathe-a"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "# work coordinates as the program writes them, X as a diameter; arc centres in the same coordinates"
    assert lines[-1] == "    3 arc    X60 Z-20 cw centre X60 Z-10 F100/rev"  # centre at radius 30 = diameter 60


def test_path_format_page_states_the_resolution_the_json_prints(capsys, tmp_path):
    """Issue 19 item 5: docs/path-format.md promised 0.1 µm while --json printed 7 decimals."""
    from tests.conftest import ROOT
    r = run_path(capsys, tmp_path, "#1=1/3\nG90 G01 X#1 Y0 F100\nM30\n")
    assert r.ends("X") == [(0.3333333,)]
    text = (ROOT / "docs" / "path-format.md").read_text()
    assert "rounded to 7 decimals (1e-7 mm" in text and "Numbers are rounded to 0.1 µm" not in text


@pytest.mark.parametrize("setting, z_moves", [(None, [10.0, 0.0]), ("0", [10.0, 0.0]), ("1", [])])
def test_n1_010_length_comp_block_without_z_moves_or_not_n3_12_2_note_3(capsys, tmp_path, setting, z_moves):
    """N§3.12.2 note (3): [N1.010] = 0 moves the tool to the compensated position in a G43/G44/G49 block
    without Z; = 1 processes it internally only (no movement)."""
    args = ("--param", f"N1.010={setting}") if setting is not None else ()
    r = run_path(capsys, tmp_path, "G10 L10 P1 R10.\nG90 G00 X0 Y0 Z0\nG43 H1\nG01 X5. F100\nG49\nM30\n", *args)
    assert r.code == 0, r.alarm
    comp_blocks = [m for m in r.moves if m["line"] in (3, 5)]
    assert [m["end"]["Z"] for m in comp_blocks] == z_moves  # machine Z: +10 under G43 H1, back to 0 at G49
    assert all(m["work"]["Z"] == 0.0 for m in comp_blocks)  # the programmed Z is kept
