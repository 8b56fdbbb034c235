"""More seed-catalog §7 worked examples through `hil path --json` (ids in the test names)."""

from __future__ import annotations

from lang_helpers import run_path


def test_e_n02_g00_absolute_and_incremental_reach_same_point(capsys, tmp_path):
    # Both blocks reach (92,35); the incremental one starts from A = (30,60).
    r = run_path(capsys, tmp_path, "G90 G00 X92. Y35.\nM30\n")
    assert r.ends("X", "Y") == [(92.0, 35.0)]
    r = run_path(capsys, tmp_path, "G90 G00 X30. Y60.\nG91 G00 X62. Y-25.\nM30\n")
    assert r.ends("X", "Y")[-1] == (92.0, 35.0)


def test_e_n03_g01_lathe_profile(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G98 G54 X0.0 Z0.0\nG00 X20.0\nG01 Z-18. F500\nX30.\nX40. Z-26.\nZ-41.\nM30\n",
                 profile="nc5-lathe-a")
    assert r.code == 0, r.alarm
    assert r.ends("X", "Z")[-5:] == [(20.0, 0.0), (20.0, -18.0), (30.0, -18.0), (40.0, -26.0), (40.0, -41.0)]
    assert [m["kind"] for m in r.moves[-4:]] == ["line"] * 4 and r.moves[-1]["feed"] == 500.0


def test_e_n16_g31_without_skip_reaches_end(capsys, tmp_path):
    # G31's F holds for that block only (N§3.5.4, decisions): the printed follow-up without F alarms 0x1001,
    # so the follow-up gets its own F here.
    bare = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG01 G90 G31 X50.0 F150.0\nX80.0 Y40.0\nM30\n")
    assert bare.code == 1 and bare.alarm["code"] == "0x1001" and bare.alarm["line"] == 3
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG01 G90 G31 X50.0 F150.0\nX80.0 Y40.0 F150.\nM30\n")
    assert r.code == 0, r.alarm
    assert r.ends("X", "Y")[-2:] == [(50.0, 0.0), (80.0, 40.0)]
    assert "G31" in r.moves[-2]["tags"]
