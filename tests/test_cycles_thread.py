"""Threading through `hil path --json`: G76 depth law, flank infeed, chamfer, phase; G92; G32; G34."""

from __future__ import annotations

import math

import pytest

from cycles_helpers import run, zx
from nc.alarms import NcAlarm
from nc.cycles.threading import g34_check, g76_depths

G76 = """G21 G99
G00 X28. Z5.
G76 P021060 Q100 R0.05
G76 X21.4 Z-22. P1300 Q400 F2.{extra}
M30
"""


def thread_passes(r, code="G76"):
    """Main thread move of each pass (the one before the chamfer) in program order."""
    return [m for m in r.tagged(code) if m["kind"] == "thread" and "chamfer" not in m["tags"]]


def test_g76_depth_law_count_and_depths(capsys, tmp_path):
    r = run(capsys, tmp_path, G76.format(extra=""))
    assert r.code == 0, r.alarm
    passes = thread_passes(r)
    root = 10.7  # X21.4 diameter, an OD thread
    depths = [1.3 - (m["start"]["X"] - root) for m in passes]
    # Δd √n with Δd = 0.4, each step ≥ Δdmin 0.1, the last rough pass at k − d = 1.25, 2 finish passes at k
    expected = []
    d, n = 0.0, 1
    while d < 1.25 - 1e-12:
        nxt = 0.4 * math.sqrt(n)
        d = min(max(nxt, d + 0.1), 1.25)
        expected.append(d)
        n += 1
    expected += [1.3, 1.3]
    assert depths == pytest.approx(expected, abs=1e-6)  # JSON carries 0.1 µm
    assert expected[:4] == pytest.approx([0.4, 0.4 * math.sqrt(2), 0.4 * math.sqrt(3), 0.8])
    assert len(r.tagged("G76", "finish")) >= 2 and len([m for m in passes if "finish" in m["tags"]]) == 2
    # every pass: same lead, same spindle start angle, ends at the thread end Z before its chamfer
    assert {m["lead"] for m in passes} == {2.0}
    assert {m["start_angle"] for m in passes} == {0.0}
    for m in passes:
        assert m["end"]["X"] == m["start"]["X"]  # straight thread
    # end position = start point
    assert zx(r.tagged("G76")[-1]["end"]) == (5.0, 14.0)


def test_g76_flank_infeed_and_chamfer(capsys, tmp_path):
    r = run(capsys, tmp_path, G76.format(extra=""))
    passes = thread_passes(r)
    half = math.tan(math.radians(30.0))
    for m in passes:
        left = m["start"]["X"] - 10.7  # height above the root
        # right-flank infeed: the start is shifted back along the 30° flank (decisions A41)
        assert math.isclose(m["start"]["Z"] - 5.0, left * half, abs_tol=1e-6)
    # chamfer r = 10 → 1.0 lead = 2 mm pulled out at 45°
    ch = [m for m in r.tagged("G76", "chamfer")]
    assert ch and all(math.isclose(m["start"]["Z"] - m["end"]["Z"], 2.0, abs_tol=1e-9) for m in ch)
    assert all(math.isclose(m["end"]["X"] - m["start"]["X"], 2.0, abs_tol=1e-9) for m in ch)
    assert all(m["end"]["Z"] == -22.0 for m in ch)


def test_g76_radial_and_alternating_infeed(capsys, tmp_path):
    r = run(capsys, tmp_path, G76.format(extra=" L1"))
    assert {m["start"]["Z"] for m in thread_passes(r)} == {5.0}
    r = run(capsys, tmp_path, G76.format(extra=" L3"))
    rough = [m for m in thread_passes(r) if "rough" in m["tags"]]
    sides = [m["start"]["Z"] > 5.0 for m in rough]
    assert sides[0] and not sides[1] and sides[2]


def test_g76_bad_height_alarms(capsys, tmp_path):
    r = run(capsys, tmp_path, G76.format(extra="").replace("P1300 Q400", "P0 Q400"))
    assert r.code == 1 and r.alarm["code"] == "0x0246" and r.alarm["line"] == 4


def test_g76_depth_law_unit():
    ps = g76_depths(1.0, 0.3, 0.05, 0.0, 1)
    assert [p.depth for p in ps if not p.finish][:3] == pytest.approx([0.3, 0.3 * math.sqrt(2), 0.3 * math.sqrt(3)])
    steps = [b.depth - a.depth for a, b in zip(ps, ps[1:]) if not b.finish]
    assert all(s >= 0.05 - 1e-12 or b == 1.0 for s, b in zip(steps, [p.depth for p in ps[1:]]))


def test_g92_taper_chamfer_modal_and_phase(capsys, tmp_path):
    prog = """G21 G99
G00 X30. Z5.
G92 X23. Z-20. F1.5 Q90000
X22.5
X22.2 R-1.
G80
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    main = [m for m in r.tagged("G92", "thread") if "chamfer" not in m["tags"]]
    assert [round(m["start"]["X"], 9) for m in main] == [11.5, 11.25, 10.1]
    assert main[0]["start_angle"] == 90.0 and main[0]["lead"] == 1.5
    # modal repeat keeps Z-20: the chamfer (1.0 lead = 1.5 mm, 45°, parameters N1.178/N1.177) ends there
    ch = r.tagged("G92", "chamfer")
    assert all(m["end"]["Z"] == -20.0 and math.isclose(m["start"]["Z"], -18.5) for m in ch)
    # taper R-1: the thread line runs from X(end)+R at the start Z to X(end) at the end Z
    z0, x0 = zx(main[2]["start"])
    z1, x1 = zx(main[2]["end"])
    slope = (11.1 - 10.1) / (-20.0 - 5.0)
    assert math.isclose((x1 - x0) / (z1 - z0), slope, rel_tol=1e-9)
    # each cycle: rapid X out, rapid Z back to the start point
    assert all(zx(m["end"]) == (5.0, 15.0) for m in r.tagged("G92", "return"))


def test_g92_no_chamfer_by_parameter(capsys, tmp_path):
    prog = "G00 X30. Z5.\nG92 X23. Z-20. F1.5\nM30\n"
    r = run(capsys, tmp_path, prog, "--param", "N1.178=0")
    th = r.tagged("G92", "thread")
    assert len(th) == 1 and th[0]["end"]["Z"] == -20.0 and th[0]["end"]["X"] == 11.5


def test_g32_start_angle_and_g34_lead_law(capsys, tmp_path):
    prog = """G21 G99
G00 X20. Z2.
G32 Z-20. F1.5 Q180000
G34 Z-40. F2. K0.1
M30
"""
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    g32, g34 = r.tagged("G32")[0], r.tagged("G34")[0]
    assert g32["kind"] == "thread" and g32["lead"] == 1.5 and g32["start_angle"] == 180.0
    assert zx(g32["end"]) == (-20.0, 10.0)
    assert g34["lead"] == 2.0 and g34["lead_change"] == 0.1
    # manual's law (A43): distance after t turns = F·t + ½·K·t² → first turn advances F + K/2
    t = g34_check(20.0, 2.0, 0.1)
    assert math.isclose(2.0 * t + 0.05 * t * t, 20.0)
    assert math.isclose(2.0 * 1 + 0.05 * 1, 2.05)


def test_g34_lead_reaching_zero_alarms(capsys, tmp_path):
    prog = "G00 X20. Z2.\nG34 Z-40. F1. K-0.1\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 1 and r.alarm["code"] == "0x0223" and r.alarm["line"] == 2
    with pytest.raises(NcAlarm):
        g34_check(10.0, 1.0, -0.1)
