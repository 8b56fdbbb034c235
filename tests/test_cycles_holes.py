"""Hole cycles through `hil path --json`: milling G73 G74 G76 G81–G89 and lathe G83–G85 G87–G89,
G98/G99 return levels, peck Q, dwell P, K repeats, tapping with spindle reversal."""

from __future__ import annotations

import json

from cycles_helpers import run

HEAD = "G17 G21 G90 G94\nG00 X0. Y0. Z100.\nM03 S1000\n"


def zs(moves):
    return [round(m["end"]["Z"], 6) for m in moves]


def test_g81_g99_g98_return_levels(capsys, tmp_path):
    r = run(capsys, tmp_path, HEAD + "G99 G81 X10. Y10. Z-20. R5. F100.\nX20.\nG98 X30.\nG80\nM30\n", profile="nc5-mill")
    assert r.code == 0, r.alarm
    holes = [r.tagged("G81", "cut")[i]["end"] for i in range(3)]
    assert [(h["X"], h["Y"], h["Z"]) for h in holes] == [(10.0, 10.0, -20.0), (20.0, 10.0, -20.0), (30.0, 10.0, -20.0)]
    # G99: back to R (5); G98: back to the initial level (100), where the cycle was first commanded
    assert zs(r.tagged("G81", "return")) == [5.0, 5.0, 100.0]
    assert r.tagged("G81", "cut")[0]["kind"] == "line" and r.tagged("G81", "cut")[0]["feed"] == 100.0
    assert all(m["kind"] == "rapid" for m in r.tagged("G81", "approach") + r.tagged("G81", "position"))


def test_g83_deep_peck_and_g73_chip_break(capsys, tmp_path):
    prog = HEAD + "G98 G83 X30. Y10. Z-20. R5. Q8. F100.\nG73 X40. Z-10. Q4.\nG80\nM30\n"
    r = run(capsys, tmp_path, prog, "--param", "N1.151=1.0", profile="nc5-mill")
    assert r.code == 0, r.alarm
    pecks = r.tagged("G83", "peck")
    assert zs(pecks) == [-3.0, -11.0, -19.0, -20.0]
    assert all(a - b <= 8.0 + 1e-9 for a, b in zip([5.0] + zs(pecks), zs(pecks)))
    # full retract to R after every peck but the last, rapid back to 1 mm above the last bottom
    assert zs(r.tagged("G83", "retract")) == [5.0, 5.0, 5.0]
    assert zs(r.tagged("G83", "reapproach")) == [-2.0, -10.0, -18.0]
    g73 = r.tagged("G73", "peck")
    assert zs(g73) == [1.0, -3.0, -7.0, -10.0]
    assert zs(r.tagged("G73", "retract")) == [2.0, -2.0, -6.0]  # back d = N1.151 only
    assert zs(r.tagged("G73", "return")) == [100.0]


def test_g84_g74_tapping_reverses_spindle(capsys, tmp_path):
    prog = HEAD + "G99 G84 X50. Y0. Z-15. R5. F150. P500\nG80\nM04\nG99 G74 X60. Y0. Z-15. R5. F150.\nG80\nM30\n"
    f = tmp_path / "tap.nc"
    f.write_text(prog)
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    taps = r.tagged("G84", "tap")
    outs = r.tagged("G84", "tap_out")
    assert zs(taps) == [-15.0] and zs(outs) == [5.0]
    assert all(m["kind"] == "line" and m["feed"] == 150.0 for m in taps + outs)
    assert r.tagged("G84", "dwell")[0]["duration"] == 0.5
    # the M events: G84 reverses to M04 at the bottom and restores M03; G74 the opposite
    from nc.interp import Interpreter
    from nc.moves import Aux
    from nc.profiles import make_profile
    from hil.session import load_program

    evs = list(Interpreter(make_profile("nc5-mill")).run(load_program(str(f))))
    seq = [(e.line, int(e.value)) for e in evs if isinstance(e, Aux) and e.kind == "M"]
    assert [v for ln, v in seq if ln == 4] == [4, 3]
    assert [v for ln, v in seq if ln == 7] == [3, 4]


def test_g76_fine_boring_shift_and_g87_back_boring(capsys, tmp_path):
    prog = HEAD + "G98 G76 X70. Y0. Z-30. R5. Q2. P1000 F80.\nG87 X80. Z-30. R-40. Q2. F80.\nG80\nM30\n"
    r = run(capsys, tmp_path, prog, "--param", "N1.150=1", profile="nc5-mill")
    assert r.code == 0, r.alarm
    sh = r.tagged("G76", "shift")
    # N1.150 bits 0-1 = 1: shift toward −X by Q at the bottom, back after the retract
    assert (sh[0]["end"]["X"], sh[0]["end"]["Z"]) == (68.0, -30.0)
    assert (sh[1]["end"]["X"], sh[1]["end"]["Z"]) == (70.0, 100.0)
    assert r.tagged("G76", "dwell")[0]["duration"] == 1.0
    g87 = r.tagged("G87")
    cut = r.tagged("G87", "cut")[0]
    assert (cut["start"]["Z"], cut["end"]["Z"]) == (-40.0, -30.0)  # bores upward from R to Z
    assert g87[-1]["end"]["Z"] == 100.0  # always back to the initial level


def test_g85_g86_g89_g88(capsys, tmp_path):
    prog = HEAD + ("G99 G85 X10. Y0. Z-10. R2. F50.\nG86 X20.\nG89 X30. P300\nG88 X40. P200\nG80\nM30\n")
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    assert r.code == 0, r.alarm
    assert r.tagged("G85", "cut_out")[0]["kind"] == "line" and r.tagged("G85", "cut_out")[0]["end"]["Z"] == 2.0
    assert r.tagged("G86", "return")[0]["kind"] == "rapid"
    assert r.tagged("G89", "dwell")[0]["duration"] == 0.3 and r.tagged("G89", "cut_out")
    assert r.tagged("G88", "dwell")[0]["duration"] == 0.2


def test_k_repeat_incremental(capsys, tmp_path):
    prog = HEAD + "G91 G99 G81 X10. Z-10. R-95. K3 F100.\nG80 G90\nM30\n"
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    cuts = r.tagged("G81", "cut")
    assert [(m["end"]["X"], m["end"]["Z"]) for m in cuts] == [(10.0, -5.0), (20.0, -5.0), (30.0, -5.0)]
    assert zs(r.tagged("G81", "approach")) == [5.0]


def test_lathe_face_and_side_drilling(capsys, tmp_path):
    prog = """G21 G98
G00 X0. Z10.
G83 X0. Z-20. R5. Q6. F100. L1
G80
G00 X50. Z-10.
G87 X10. R4. Q5. P200 F80. L2
G80
G00 Z10.
G85 X0. Z-8. R5. F60.
G80
M30
"""
    r = run(capsys, tmp_path, prog, "--param", "N1.151=0.5")
    assert r.code == 0, r.alarm
    # face drilling along Z, R 5 mm from the initial point toward the hole, deep peck L1
    assert zs(r.tagged("G83", "approach")) == [5.0]
    assert zs(r.tagged("G83", "peck")) == [-1.0, -7.0, -13.0, -19.0, -20.0]
    assert zs(r.tagged("G83", "retract")) == [5.0] * 4
    assert zs(r.tagged("G83", "return")) == [10.0]
    # side drilling along X (radius 25 → 5), chip-breaking L2, dwell 0.2 s at the bottom
    xs = [round(m["end"]["X"], 6) for m in r.tagged("G87", "peck")]
    assert xs[0] == 25.0 - 4.0 - 5.0 and xs[-1] == 5.0
    assert r.tagged("G87", "dwell")[0]["duration"] == 0.2
    assert [round(m["end"]["X"], 6) for m in r.tagged("G87", "return")] == [25.0]
    assert r.tagged("G85", "cut_out")[0]["end"]["Z"] == 5.0


def test_lathe_tapping_g84(capsys, tmp_path):
    prog = "G21 G98\nG00 X0. Z10.\nM03 S500\nG84 X0. Z-12. R5. F750.\nG80\nM30\n"
    r = run(capsys, tmp_path, prog)
    assert r.code == 0, r.alarm
    assert zs(r.tagged("G84", "tap")) == [-12.0] and zs(r.tagged("G84", "tap_out")) == [5.0]
    assert zs(r.tagged("G84", "return")) == [10.0]


def test_hole_cycle_json_has_tags(capsys, tmp_path):
    r = run(capsys, tmp_path, HEAD + "G81 X1. Y1. Z-1. R1. F10.\nG80\nM30\n", profile="nc5-mill")
    assert all(isinstance(m.get("tags", []), list) for m in r.moves)
    json.dumps(r.moves)
