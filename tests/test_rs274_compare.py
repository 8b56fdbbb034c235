"""Our paths against LinuxCNC's standalone interpreter `rs274` (Debian linuxcnc-uspace), for
programs that can be written in both dialects. Accepted differences: docs/decisions/cycles.md."""

from __future__ import annotations

import math

import pytest

from cycles_helpers import run
from rs274_helpers import dedupe, needs_rs274, rs274

pytestmark = needs_rs274


def test_cutter_compensation_matches_linuxcnc(capsys, tmp_path):
    body = """G00 X-20. Y-20. Z5.
G01 Z-2. F500
{g41} G01 X0. Y0.
Y40.
G02 X20. Y60. R20.
G01 X60.
Y0.
X0.
G40 G01 X-20. Y-20.
"""
    lc = rs274(tmp_path, "G17 G21 G90 G94\n" + body.format(g41="G41.1 D8.") + "M2\n")
    ours = run(capsys, tmp_path, "G17 G21 G90 G94\nG10 L12 P1 R4.\n" + body.format(g41="G41 D1") + "M30\n",
               profile="nc5-mill")
    assert ours.code == 0, ours.alarm
    mine = [m for m in ours.moves if "comp" in m.get("tags", []) and "cancel" not in m["tags"]][1:]
    # LinuxCNC: traverse, plunge, entry, then the body, then the exit
    theirs = lc[3:-1]
    assert len(mine) == len(theirs) == 7
    for m, (call, v) in zip(mine, theirs):
        if call == "ARC_FEED":
            assert m["kind"] == "arc"
            assert (m["end"]["X"], m["end"]["Y"]) == pytest.approx((v[0], v[1]), abs=1e-4)
            assert (m["center"]["X"], m["center"]["Y"]) == pytest.approx((v[2], v[3]), abs=1e-4)
            assert (m["dir"] == "cw") == (v[4] < 0)
        else:
            assert m["kind"] == "line"
            assert (m["end"]["X"], m["end"]["Y"], m["end"]["Z"]) == pytest.approx(tuple(v[:3]), abs=1e-4)
    # accepted difference: the start-up block. LinuxCNC enters tangent to the cutter circle around the
    # first point, we end the start-up normal to the next block (Fanuc type A, decisions A53)
    entry = [m for m in ours.moves if "comp" in m.get("tags", [])][0]
    assert (entry["end"]["X"], entry["end"]["Y"]) == (-4.0, 0.0)
    assert lc[2][1][0] == pytest.approx(-4.0) and lc[2][1][1] != pytest.approx(0.0)


def test_drilling_cycles_match_linuxcnc(capsys, tmp_path):
    body = """G00 X0. Y0. Z50.
G99 G81 X10. Y10. Z-20. R5. F100.
X20.
G80
G00 Z50.
G98 G83 X30. Y10. Z-20. R5. Q8. F100.
G80
G00 Z50.
G98 G82 X40. Y10. Z-5. R2. P500 F100.
G80
G00 Z50.
G99 G85 X50. Y10. Z-6. R3. F100.
G80
"""
    lc = rs274(tmp_path, "G17 G21 G90 G94\n" + body.replace("P500", "P0.5") + "M2\n")
    ours = run(capsys, tmp_path, "G17 G21 G90 G94\n" + body + "M30\n", "--param", "N1.151=0.254",
               profile="nc5-mill")
    assert ours.code == 0, ours.alarm
    mine = dedupe([("rapid" if m["kind"] == "rapid" else "feed", [m["end"]["X"], m["end"]["Y"], m["end"]["Z"]])
                   for m in ours.moves if m["kind"] != "dwell"])
    theirs = dedupe([("rapid" if c == "STRAIGHT_TRAVERSE" else "feed", v[:3]) for c, v in lc])
    assert len(mine) == len(theirs)
    for (k1, p1), (k2, p2) in zip(mine, theirs):
        assert k1 == k2
        assert p1 == pytest.approx(p2, abs=1e-4)


def test_g76_depth_law_matches_linuxcnc(capsys, tmp_path):
    """LinuxCNC G76 with degression R2 cuts J·√n like our G76 (Δdmin 0, allowance 0, radial infeed)."""
    lc = rs274(tmp_path, "G18 G21 G90 G7\nG0 X28 Z5\nM3 S500\nG76 P2 Z-22 I-3.3 J0.4 R2 K1.3 Q0 H1\nM2\n")
    # crest 28 − 3.3 = 24.7 Ø, depth 1.3 Ø = 0.65 radius: root X23.4; first depth 0.2 radius
    ours = run(capsys, tmp_path, "G21 G99\nG00 X28. Z5.\nG76 P010000 Q0 R0\nG76 X23.4 Z-22. P650 Q200 F2. L1\nM30\n")
    assert ours.code == 0, ours.alarm
    mine = [m["start"]["X"] for m in ours.moves if m["kind"] == "thread"]
    theirs = [v[0] for c, v in lc if c == "STRAIGHT_FEED"]
    assert len(mine) == len(theirs)
    assert mine == pytest.approx(theirs, abs=1e-4)
    assert all(math.isfinite(x) for x in mine)
