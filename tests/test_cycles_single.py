"""G90 / G94 single cycles with taper R and modal repeats, G74 / G75 peck grooving."""

from __future__ import annotations

from cycles_helpers import run, zx


def test_g90_taper_and_modal_repeat(capsys, tmp_path):
    prog = "G21 G99\nG00 X40. Z2.\nG90 X30. Z-20. R-2. F0.2\nX28.\nG80\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g = r.tagged("G90")
    # (1) rapid to X end + R, (2) cut to the end point, (3) cut out in X, (4) rapid back (A48)
    assert [m["kind"] for m in g[:4]] == ["rapid", "line", "line", "rapid"]
    assert zx(g[0]["end"]) == (2.0, 13.0)
    assert zx(g[1]["end"]) == (-20.0, 15.0)
    assert zx(g[2]["end"]) == (-20.0, 20.0)
    assert zx(g[3]["end"]) == (2.0, 20.0)
    # the repeat with X only keeps Z-20 and R-2
    assert zx(g[4]["end"]) == (2.0, 12.0) and zx(g[5]["end"]) == (-20.0, 14.0)
    assert g[1]["feed"] == 0.2


def test_g94_face_taper(capsys, tmp_path):
    prog = "G21 G99\nG00 X40. Z2.\nG94 X10. Z-3. R-1. F0.2\nZ-4.\nG80\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g = r.tagged("G94")
    assert [m["kind"] for m in g[:4]] == ["rapid", "line", "line", "rapid"]
    assert zx(g[0]["end"]) == (-4.0, 20.0)
    assert zx(g[1]["end"]) == (-3.0, 5.0)
    assert zx(g[2]["end"]) == (2.0, 5.0)
    assert zx(g[3]["end"]) == (2.0, 20.0)
    assert zx(g[5]["end"]) == (-4.0, 5.0)  # repeat: X10. kept, new Z, taper R-1 kept


def test_g74_face_grooving_pecks_and_shifts(capsys, tmp_path):
    prog = "G21 G99\nG00 X30. Z5.\nG74 R0.5\nG74 X20. Z-10. P3000 Q2500 R0. F0.1\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    pecks = r.tagged("G74", "peck")
    cols = sorted({round(m["end"]["X"], 6) for m in pecks}, reverse=True)
    assert cols == [15.0, 12.0, 10.0]  # X shift P 3 mm (radius), the last one clamped at X20.
    for x in cols:
        col = [m for m in pecks if round(m["end"]["X"], 6) == x]
        depths = [m["end"]["Z"] for m in col]
        assert depths[-1] == -10.0
        assert all(a - b <= 2.5 + 1e-9 for a, b in zip([5.0] + depths, depths))
    rets = r.tagged("G74", "retract")
    assert all(abs(m["end"]["Z"] - m["start"]["Z"] - 0.5) < 1e-9 for m in rets)
    assert zx(r.tagged("G74")[-1]["end"]) == (5.0, 15.0)


def test_g75_grooving_with_bottom_escape(capsys, tmp_path):
    prog = "G21 G99\nG00 X50. Z-20.\nG75 R0.5\nG75 X30. Z-26. P2000 Q3000 R0.2 F0.1\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    pecks = r.tagged("G75", "peck")
    cols = sorted({round(m["end"]["Z"], 6) for m in pecks}, reverse=True)
    assert cols == [-20.0, -23.0, -26.0]
    for z in cols:
        xs = [m["end"]["X"] for m in pecks if round(m["end"]["Z"], 6) == z]
        assert xs[-1] == 15.0 and all(a - b <= 2.0 + 1e-9 for a, b in zip([25.0] + xs, xs))
    esc = r.tagged("G75", "escape")
    assert len(esc) == 2 and all(abs(m["end"]["Z"] - m["start"]["Z"] - 0.2) < 1e-9 for m in esc)
    assert zx(r.tagged("G75")[-1]["end"]) == (-20.0, 25.0)
