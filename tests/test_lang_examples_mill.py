"""NC5 milling worked examples E-N40..E-N54 (seed-catalog §7.2) and §7.3 prose assertions, through `hil path`.

Programs are the manual's listings (NC5 §3.12–§3.13); side annotations such as `(1)` are comments already.
Where a listing needs data the manual keeps in the OFS table (D20, D12, H01), one `G10` line in front
sets it, as an operator would.  Flags of the catalog (decimal-point rule A4) run in both modes.
"""

from __future__ import annotations

import math

import pytest

from lang_helpers import PathResult, run_path

MILL = "nc5-mill"
WHOLE_MM = ("--param", "N8.018 Bit10=1")  # decimal-point rule off: an integer is a whole mm (A4)


def tagged(r: PathResult, *tags: str) -> list[dict]:
    return [m for m in r.moves if all(t in m.get("tags", []) for t in tags)]


def xy(m: dict, key: str = "end") -> tuple[float, float]:
    return (round(m[key]["X"], 4), round(m[key]["Y"], 4))


def holes(r: PathResult, code: str, step: str = "cut") -> list[tuple[float, float]]:
    return [xy(m) for m in tagged(r, code, step)]


def levels(moves: list[dict]) -> list[float]:
    return [round(m["end"]["Z"], 4) for m in moves]


def hole_program(cycle_block: str, x2: str = "X-15.", x3: str = "X-30.") -> str:
    """The four-hole pattern of N§3.13.1–§3.13.3 examples 1–4 and the boring examples."""
    return (f"M03 S1000\nG17 G90 G00 G54 X0. Y0.\nG00 Z100.\n{cycle_block} (1)\n{x2} (2)\n{x3} (3)\n"
            "X-30. Y15. (4)\nG80\nG91 G28 X0. Y0. Z0.\nM05\n")


PATTERN = [(0.0, 0.0), (-15.0, 0.0), (-30.0, 0.0), (-30.0, 15.0)]


# ---------------------------------------------------------------- N§3.12 compensation and scaling

E_N40 = """G10 L12 P20 R5.
N00 G90 G00 X120.0 Y-20.0	(Rapid positioning to point A)
N01 G01 G42 X100.0 Y0 D20 F80	(A point to C point)
N02 Y52.0	(C point to D point)
N03 G03 X92.0 Y60.0 R8.0	(D point to E point)
N04 G01 X0	(E point to F point)
N05 Y0	(F point to G point)
N06 X100.0	(G point to C point)
"""


def test_e_n40_g42_right_compensation_outside_rectangle(capsys, tmp_path):
    r = run_path(capsys, tmp_path, E_N40, profile=MILL)
    assert r.code == 0, r.alarm
    comp = tagged(r, "comp")
    # start-up A → C ends one radius (D20 = 5) right of the first side; the CCW rectangle is cut from outside
    assert xy(comp[0], "start") == (120.0, -20.0) and xy(comp[0]) == (105.0, 0.0)
    assert [xy(m) for m in comp] == [(105.0, 0.0), (105.0, 52.0), (92.0, 65.0), (0.0, 65.0), (-5.0, 60.0),
                                     (-5.0, 0.0), (0.0, -5.0), (100.0, -5.0)]
    arc = comp[2]  # N03 R8 corner: same centre, radius 8 + 5
    assert arc["kind"] == "arc" and arc["dir"] == "ccw" and xy(arc, "center") == (92.0, 52.0)
    assert math.dist(xy(arc, "start"), (92.0, 52.0)) == pytest.approx(13.0)
    # the two square outer corners F and G get an arc of the tool radius around the programmed corner
    assert [xy(m, "center") for m in comp if "corner" in m["tags"]] == [(0.0, 60.0), (0.0, 0.0)]
    # the programmed (work) points are the contour itself
    assert [xy(m, "work") for m in comp if "corner" not in m["tags"]] == [
        (100.0, 0.0), (100.0, 52.0), (92.0, 60.0), (0.0, 60.0), (0.0, 0.0), (100.0, 0.0)]


E_N41 = """G10 L12 P12 R4.
N00 G90 G00 X-20.0 Y-20.0
(Rapid positioning to point A)
N01 G01 G41 X0 Y0 D12 F80
(A point to B point, enable left compensation)
N02 Y35.	(B point to C point)
N03 X20.	(C point to D point)
N04 G03 X25.0 Y60.0 R65.0	(D point to E point)
N05 G02 X60.0 Y100.0 R25.	(E point to F point)
N06 G01 X90.0 Y35.0	(F point to G point)
N07 G01 Y0	(G point to H point)
N08 X45. Y10.	(H point to I point)
N09 X0 Y0	(I point to B point)
N10 X -20. Y -20.	(B point to A point)
N11 G40
(Tool disengaged, cancel compensation)
"""


def test_e_n41_as_printed_n05_is_an_arc_radius_error(capsys, tmp_path):
    # E(25,60) → F(60,100) is a 53.15 mm chord: R25 cannot reach it (decisions A30: alarm beyond N1.040)
    r = run_path(capsys, tmp_path, E_N41, profile=MILL)
    assert r.code == 1 and r.alarm["code"] == "0x0259"
    assert r.alarm["block"].startswith("N05 G02")
    assert xy(r.moves[1]) == (-4.0, 0.0)  # what ran before: B offset 4 to the left (outside)


def test_e_n41_g41_and_g40_cancel(capsys, tmp_path):
    # N05 with a radius that reaches F (R30 > half chord 26.58; decisions E-N41), the rest as printed
    r = run_path(capsys, tmp_path, E_N41.replace("R25.", "R30."), profile=MILL)
    assert r.code == 0, r.alarm
    comp = tagged(r, "comp")
    # G41 on this clockwise walk keeps the tool outside: X = −4 along B → C
    assert (xy(comp[0]), xy(comp[1], "start"), xy(comp[1])) == ((-4.0, 0.0), (-4.0, 0.0), (-4.0, 35.0))
    corners = [m for m in comp if "corner" in m["tags"]]
    assert [xy(m, "center") for m in corners] == [(0.0, 35.0), (60.0, 100.0), (90.0, 35.0), (90.0, 0.0)]
    assert all(math.dist(xy(m), xy(m, "center")) == pytest.approx(4.0, abs=1e-4) for m in corners)
    arcs = [m for m in comp if m["kind"] == "arc" and "corner" not in m["tags"]]
    # N04 G03 R65 (tool inside the CCW arc: 61), N05 G02 R30 (tool outside the CW arc: 34)
    assert [(a["dir"], round(math.dist(xy(a), xy(a, "center")), 3)) for a in arcs] == [("ccw", 61.0), ("cw", 34.0)]
    assert xy(arcs[0], "center") == (-40.0, 60.0)
    # inner corner D (line → concave arc) is trimmed: the Y39 line stops where it meets the R61 arc
    assert xy(comp[3]) == (17.2713, 39.0)
    # N10 `X -20. Y -20.` (spaces inside the words) leaves B for A; N11 G40 has no motion, so the
    # last element ends normal to itself (decisions A53: note 6 is not followed)
    last = r.moves[-1]
    assert xy(last, "work") == (-20.0, -20.0) and last["line"] == 14
    assert xy(last) == (round(-20 + 2 * 2 ** 0.5, 4), round(-20 - 2 * 2 ** 0.5, 4))


def test_e_n42_g43_and_g44_give_the_same_z(capsys, tmp_path):
    a = run_path(capsys, tmp_path, "G10 L10 P1 R-400.\nG43 Z5.0 H01\nM30\n", profile=MILL)
    b = run_path(capsys, tmp_path, "G10 L10 P1 R400.\nG44 Z5.0 H01\nM30\n", profile=MILL)
    assert a.code == b.code == 0
    # Z program origin 400 below the machine origin: both reach machine Z −395 for programmed Z5
    assert a.machine("Z") == b.machine("Z") == [(-395.0,)]
    assert a.ends("Z") == b.ends("Z") == [(5.0,)]


def test_e_n43_scaling_ratio_p_in_thousandths(capsys, tmp_path):
    prog = "G90 G00 X0 Y0\nG51 X0 Y0 P100\nG01 X100. Y50. F100\nG50\nX100. Y50.\nM30\n"
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    assert r.machine("X", "Y")[1:] == [(10.0, 5.0), (100.0, 50.0)]  # P100 = 0.1 times; G50 restores 1:1
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG51 X0 Y0 P1\nG01 X1000. F100\nG50\n"
                                   "G51 X0 Y0 P999999\nG01 X0.001 Y0 F100\nM30\n", profile=MILL)
    assert r.code == 0, r.alarm
    assert [round(x, 6) for (x,) in r.machine("X")[1:]] == [1.0, 0.999999]  # min ratio 0.001, max 999.999
    for p in ("P0", "P1000000"):
        r = run_path(capsys, tmp_path, f"G51 X0 Y0 {p}\nM30\n", profile=MILL)
        assert r.code == 1 and r.alarm["code"] == "0x0223"  # outside 0.001–999.999


# ---------------------------------------------------------------- N§3.13 hole cycles


def test_e_n47_g81_decimal_point_flag(capsys, tmp_path):
    prog = hole_program("G99 G81 X0. Y0. Z-30. R10. K1 F100.", "X-15", "X-30")
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    # default rule (N8.018 Bit10 = 0): `X-15`, `X-30` are 0.015 / 0.030 mm
    assert holes(r, "G81") == [(0.0, 0.0), (-0.015, 0.0), (-0.03, 0.0), (-30.0, 15.0)]
    r = run_path(capsys, tmp_path, prog, *WHOLE_MM, profile=MILL)
    assert r.code == 0, r.alarm
    assert holes(r, "G81") == PATTERN  # the manual's intended pattern
    assert levels(tagged(r, "G81", "approach")) == [10.0]  # from the initial Z100 to R once
    assert levels(tagged(r, "G81", "cut")) == [-30.0] * 4 and {m["feed"] for m in tagged(r, "G81", "cut")} == {100.0}
    assert levels(tagged(r, "G81", "return")) == [10.0] * 4  # G99: back to R after each hole
    assert all(m["kind"] == "rapid" for m in tagged(r, "G81", "position") + tagged(r, "G81", "return"))
    assert r.moves[-1]["end"] == {"X": 0.0, "Y": 0.0, "Z": 0.0}  # G91 G28 X0. Y0. Z0.: straight to reference


def test_e_n48_g82_dwell_at_the_bottom(capsys, tmp_path):
    r = run_path(capsys, tmp_path, hole_program("G99 G82 X0. Y0. Z-30. R10. P100 F100."), profile=MILL)
    assert r.code == 0, r.alarm
    assert holes(r, "G82") == PATTERN  # no K: one hole a block
    dwells = tagged(r, "G82", "dwell")
    assert [m["duration"] for m in dwells] == [0.1] * 4  # P100 = 100 ms, not subject to the decimal rule
    assert [(xy(m), m["end"]["Z"]) for m in dwells] == [(p, -30.0) for p in PATTERN]
    assert levels(tagged(r, "G82", "return")) == [10.0] * 4


def test_e_n49_g83_q_without_decimal_point(capsys, tmp_path):
    prog = hole_program("G99 G83 X0. Y0. Z-30. R10. Q4 K1 F100.")
    r = run_path(capsys, tmp_path, prog, *WHOLE_MM, profile=MILL)
    assert r.code == 0, r.alarm
    pecks = tagged(r, "G83", "peck")
    assert levels(pecks[:10]) == [6.0, 2.0, -2.0, -6.0, -10.0, -14.0, -18.0, -22.0, -26.0, -30.0]  # Q4 = 4 mm
    assert sorted({xy(m) for m in pecks}) == sorted(PATTERN) and len(pecks) == 40
    assert levels(tagged(r, "G83", "retract")[:9]) == [10.0] * 9  # deep hole: out to R after every peck
    assert levels(tagged(r, "G83", "reapproach")[:3]) == [7.0, 3.0, -1.0]  # d = N1.151 (1 mm) above the bottom
    # default rule: Q4 is 4 µm, 10000 pecks a hole; the re-approach never starts above R (cutting air).
    # 120 000 moves: read them from the interpreter rather than through 120 000 JSON lines
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.program import parse_program

    moves = [e for e in Interpreter(make_profile(MILL)).run(parse_program(prog)) if isinstance(e, Move)]
    pecks = [m for m in moves if "peck" in m.tags]
    assert len(pecks) == 4 * 10000 and [round(m.end["Z"], 4) for m in pecks[:2]] == [9.996, 9.992]
    assert max(m.end["Z"] for m in moves if "G83" in m.tags and "approach" not in m.tags) == 10.0


def test_e_n50_g74_left_hand_tapping(capsys, tmp_path):
    prog = ("G17 G90 G00 G54 X0. Y0.\nG00 Z100.\nM29 S1000\nG99 G74 X0. Y0. Z-30. R10. P1000 K1 F1000. (1)\n"
            "X-15. (2)\nX-30. (3)\nX-30. Y15. (4)\nM28 G91 G80 G28 X0. Y0. Z0.\n")
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    taps, outs = tagged(r, "G74", "tap"), tagged(r, "G74", "tap_out")
    assert [xy(m) for m in taps] == PATTERN and levels(taps) == [-30.0] * 4 and levels(outs) == [10.0] * 4
    # F1000 at S1000 (G94): lead 1.0 mm/rev, in and out at the same feed
    assert {m["feed"] for m in taps + outs} == {1000.0} and not any(m.get("per_rev") for m in taps)
    assert [m["duration"] for m in tagged(r, "G74", "dwell")] == [1.0] * 4  # P1000 although not in the format line
    assert r.moves[-1]["end"] == {"X": 0.0, "Y": 0.0, "Z": 0.0}  # M28 (no meaning here) G91 G80 G28
    # spindle: reverse (M04) into the hole, forward (M03) out of it (N§3.13.2 steps 2–3)
    from nc.interp import Interpreter
    from nc.moves import Aux
    from nc.profiles import make_profile
    from nc.program import parse_program

    evs = list(Interpreter(make_profile(MILL)).run(parse_program(prog)))
    first = [int(e.value) for e in evs if isinstance(e, Aux) and e.kind == "M" and e.line == 4]
    assert first[:2] == [4, 3]


def test_e_n51_e_n52_g76_fine_boring_g99_g98(capsys, tmp_path):
    for ret, level in (("G99", 10.0), ("G98", 100.0)):
        r = run_path(capsys, tmp_path, hole_program(f"{ret} G76 X0. Y0. Z-30. R10. P1000 Q5. F100."), profile=MILL)
        assert r.code == 0, r.alarm
        assert holes(r, "G76") == PATTERN and levels(tagged(r, "G76", "cut")) == [-30.0] * 4
        assert [m["duration"] for m in tagged(r, "G76", "dwell")] == [1.0] * 4
        shifts = tagged(r, "G76", "shift")
        # orient, shift Q5 (N1.150 bits 0–1 = 0: +X) at the bottom, retract, shift back at the return level
        assert [(xy(m), m["end"]["Z"]) for m in shifts[:2]] == [((5.0, 0.0), -30.0), ((0.0, 0.0), level)]
        assert levels(tagged(r, "G76", "return")) == [level] * 4
        assert [xy(m) for m in tagged(r, "G76", "return")] == [(x + 5.0, y) for x, y in PATTERN]


def test_e_n53_g85_feeds_out_to_r(capsys, tmp_path):
    r = run_path(capsys, tmp_path, hole_program("G99 G85 X0. Y0. Z-30. R10. F100."), profile=MILL)
    assert r.code == 0, r.alarm
    assert holes(r, "G85") == PATTERN
    outs = tagged(r, "G85", "cut_out")
    assert levels(outs) == [10.0] * 4 and all(m["kind"] == "line" and m["feed"] == 100.0 for m in outs)
    assert not tagged(r, "G85", "return")  # G99: the feed out already ends at R


def test_e_n54_g80_cancels_g73(capsys, tmp_path):
    prog = ("G17 G90 G00 G54 X0. Y0. Z100.\nG99 G73 X0. Y0. Z-20. R10. Q4. K1 F100.\nX10.Y0.\nX20.Y0.\nG80\n"
            "G17 G90 G00 G54 X0. Y0.\n")
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    pecks = tagged(r, "G73", "peck")
    assert sorted({xy(m) for m in pecks}) == [(0.0, 0.0), (10.0, 0.0), (20.0, 0.0)]  # not three times X0.Y0.
    assert levels(pecks[:8]) == [6.0, 2.0, -2.0, -6.0, -10.0, -14.0, -18.0, -20.0]
    assert levels(tagged(r, "G73", "retract")[:2]) == [7.0, 3.0]  # chip break: back d = 1 mm only
    last = r.moves[-1]  # after G80 the last block is a plain rapid at the R level
    assert last["kind"] == "rapid" and not last.get("tags") and last["end"] == {"X": 0.0, "Y": 0.0, "Z": 10.0}


# ---------------------------------------------------------------- §7.3 prose assertions

HEAD = "G17 G90 G00 X0. Y0. Z50.\nM03 S500\n"


def test_733_10_k_below_one_positions_k_truncated_and_one_shot(capsys, tmp_path):
    prog = HEAD + "G99 G81 X10. Y0. Z-5. R2. K0 F100.\nX20. K2.7\nX30.\nG80\nM30\n"
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    assert xy(r.moves[1]) == (10.0, 0.0) and r.moves[1]["end"]["Z"] == 50.0  # K0: position only
    # K2.7 → 2 holes at X20 (absolute: same place); K is one-shot, Z R F stay modal
    assert holes(r, "G81") == [(20.0, 0.0), (20.0, 0.0), (30.0, 0.0)]
    assert levels(tagged(r, "G81", "cut")) == [-5.0] * 3


def test_733_11_tapping_block_without_f_alarms(capsys, tmp_path):
    r = run_path(capsys, tmp_path, HEAD + "G84 X10. Y0. Z-5. R2.\nM30\n", profile=MILL)
    assert r.code == 1 and (r.alarm["code"], r.alarm["line"]) == ("0x1001", 3)
    # a modal F of an earlier G01 does not count: F is a required word of the tapping block
    r = run_path(capsys, tmp_path, HEAD + "G01 X1. F100\nG84 X10. Y0. Z-5. R2.\nM30\n", profile=MILL)
    assert r.code == 1 and (r.alarm["code"], r.alarm["line"]) == ("0x1001", 4)
    r = run_path(capsys, tmp_path, HEAD + "G84 X10. Y0. Z-5. R2. F500.\nX20.\nM30\n", profile=MILL)
    assert r.code == 0 and holes(r, "G84", "tap") == [(10.0, 0.0), (20.0, 0.0)]  # repeats keep the block's F


def test_733_15_if_nesting_limit(capsys, tmp_path):
    def nest(n: int) -> str:
        return "#1=1\n" + "IF[#1==1]THEN\n" * n + f"#100={n}\n" + "ENDIF\n" * n + "M30\n"

    assert run_path(capsys, tmp_path, nest(5), "--vars", "100", profile=MILL).vars == {"100": 5.0}
    r = run_path(capsys, tmp_path, nest(6), profile=MILL)
    assert r.code == 1 and r.alarm["code"] == "0x023E" and r.alarm["line"] == 7


def test_733_17_r_wins_over_ijk(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X0 Y0\nG02 X20. Y0 I5. J0 R10. F100\nM30\n", profile=MILL)
    assert r.code == 0 and xy(r.moves[1], "center") == (10.0, 0.0)  # I5 alone would put it at (5, 0)


def test_733_22_length_comp_cancelled_by_g53_g28_g30_and_m30(capsys, tmp_path):
    on = "G43 Z10. H01\n"
    prog = ("G10 L10 P1 R100.\nG90 G00 " + on + "G53 Z0.\nG00 Z10.\n" + on + "G28 Z20.\nG00 Z10.\n" + on +
            "G30 P2 Z20.\nG00 Z10.\n" + on + "M30\n")
    r = run_path(capsys, tmp_path, prog, "--vars", "20308", profile=MILL)
    assert r.code == 0, r.alarm
    plain = [m["end"]["Z"] for m in r.moves if m["block"] == "G00 Z10."]
    assert plain == [10.0, 10.0, 10.0]  # after G53, G28, G30 the next Z is uncompensated (not restored)
    assert [m["end"]["Z"] for m in r.moves if m["block"].endswith(on.strip())] == [110.0] * 4
    assert r.vars == {"20308": 49.0}  # M30: back to G49


def test_733_26_m96_prohibited_with_g41_g51_and_in_subprograms(capsys, tmp_path):
    from nc.alarms import NcAlarm
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.store import ProgramStore

    for active in ("G10 L12 P1 R2.\nG41 D1 G01 X10. F100\n", "G51 X0 Y0 P500\nG01 X10. F100\n"):
        store = ProgramStore()
        progs = store.add_text(f"M96 P50\n{active}X20.\nX30.\nM30\nO0050\n#100=7\nM99\n")
        it = Interpreter(make_profile(MILL), store=store)
        ev = it.run(progs[0], preview=False)
        while not isinstance(next(ev), Move):
            pass
        it.request_interrupt()
        with pytest.raises(NcAlarm) as exc:
            list(ev)
        assert exc.value.alarm.code == 0x0005
    r = run_path(capsys, tmp_path, "M98 P20\nM30\nO0020\nM96 P50\nM99\nO0050\nM99\n", profile=MILL)
    assert r.code == 1 and r.alarm["code"] == "0x0005"  # not in a subprogram


def test_733_28_g31_trigger_positions_machine_and_absolute(capsys, tmp_path):
    from nc.interp import Interpreter
    from nc.moves import Move
    from nc.profiles import make_profile
    from nc.program import parse_program

    it = Interpreter(make_profile(MILL))
    ev = it.run(parse_program("G10 L2 P1 X100.\nG54 G01 G31 X50. F100\n#100=#21048\n#101=#21064\nM30\n"),
                preview=False)
    while not isinstance(next(ev), Move):  # up to the G31 move (G10 and G31 stop preview: Sync events)
        pass
    it.record_skip({"X": 130.0, "Y": 0.0, "Z": 0.0})  # the probe fired at machine X130 = work X30
    list(ev)
    assert (it.variable(100), it.variable(101)) == (130.0, 30.0)
    it = Interpreter(make_profile("lathe-2018"))
    ev = it.run(parse_program("G01 G31 Z-50. F100\n#100=#2150\n#101=#2166\nM30\n"), preview=False)
    while not isinstance(next(ev), Move):
        pass
    it.record_skip({"X": 0.0, "Z": -20.0})
    list(ev)
    assert (it.variable(100), it.variable(101)) == (-20.0, -20.0)


def test_733_29_g10_l2_takes_effect_at_the_next_motion_block(capsys, tmp_path):
    prog = "G90 G54 G00 X10. Y0\nG10 L2 P1 X100.\n#100=#21000\nG00 X10.\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100", profile=MILL)
    assert r.vars == {"100": 10.0}  # the G10 block itself does not move the machine
    assert r.machine("X") == [(10.0,), (110.0,)]


def test_733_30_g10_l10_needs_g43_again(capsys, tmp_path):
    prog = "G10 L10 P1 R100.\nG43 G00 Z10. H01\nG10 L10 P1 R50.\nG00 Z20.\nG43 Z20. H01\nG00 Z30.\nM30\n"
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.machine("Z") == [(110.0,), (120.0,), (70.0,), (80.0,)]


# ---------------------------------------------------------------- G80, then the same cycle again


@pytest.mark.parametrize("cancel", ["G80", "G00"])
def test_same_hole_cycle_after_g80_starts_afresh(capsys, tmp_path, cancel):
    # no move between the cancel and the new G82: the tool still sits at the first cycle's R level
    prog = ("G17 G90 G00 X0. Y0. Z100.\nG99 G82 X0. Y0. Z-30. R10. P500 F100.\n" + cancel +
            "\nG98 G82 X20. Z-5. F100.\nG80\nM30\n")
    r = run_path(capsys, tmp_path, prog, profile=MILL)
    assert r.code == 0, r.alarm
    second = [m for m in tagged(r, "G82") if m["line"] == 4]
    # the initial level is where the new cycle was commanded (Z10), R defaults to it, P500 is gone
    assert [m["kind"] for m in second] == ["rapid", "line", "rapid"]
    assert levels(second) == [10.0, -5.0, 10.0] and "return" in second[-1]["tags"]


# ---------------------------------------------------------------- modal state variables, M96 into an arc


def test_modal_state_variables_after_g91_g18_g95(capsys, tmp_path):
    prog = ("G10 L10 P3 R1.\nG10 L12 P4 R2.\nT5 H3 D4\nG91 G18 G95 G01 Z-1. F0.2 S1200 M03\nG99 G43 Z0. H3\n"
            "#4001=#4001+1\nM30\n")
    groups = {20301: 1.0, 20302: 18.0, 20303: 91.0, 20305: 95.0, 20306: 21.0, 20307: 40.0, 20308: 43.0,
              20309: 80.0, 20310: 99.0, 20311: 50.0, 20312: 54.0, 20313: 64.0, 20314: 67.0, 20315: 69.0,
              20316: 15.0, 20317: 97.0, 20318: 25.0}
    status = {20400: 0.2, 20401: 3.0, 20402: 4.0, 20403: 5.0, 20404: 1200.0}
    ids = ",".join(str(n) for n in [*groups, *status, 4001, 20300])
    r = run_path(capsys, tmp_path, prog.replace("M30\n", ""), "--vars", ids, profile=MILL)
    assert r.code == 0, r.alarm
    assert {int(k): v for k, v in r.vars.items()} == {**groups, **status, 4001: 1.0, 20300: None}
    # #4001 is an extend variable on NC5 (vacant + 1 = 1), not Fanuc's modal G code
    r = run_path(capsys, tmp_path, "G99 G01 W-1. F0.2\n#100=#2001\n#101=#2005\n#102=#2020\nM30\n",
                 "--vars", "100-102", profile="lathe-2018")
    assert r.vars == {"100": 1.0, "101": 99.0, "102": 0.2}  # lathe-2018: #2000 + group, #2020 F


M96_ARC = "M96 P50\nG90 G00 X0 Y0\nG03 X0 Y20. R10. F100\nG01 X30.\nM30\nO0050\nG00 Z5.\nZ0.\nM99\n"


def test_m96_return_into_an_interrupted_arc_is_linear(capsys, tmp_path):
    r = run_path(capsys, tmp_path, M96_ARC, "--interrupt", "3@0.25", profile=MILL)
    assert r.code == 0, r.alarm
    cut, up, down, resume, nxt = r.moves[1:]
    # the arc ran a quarter of its length (45° of 180°) about its centre (0,10) when M2x019 fired
    assert cut["kind"] == "arc" and xy(cut, "center") == (0.0, 10.0) and "M96 stop" in cut["tags"]
    assert xy(cut) == (round(10 * math.sin(math.pi / 4), 4), round(10 - 10 * math.cos(math.pi / 4), 4))
    assert (up["line"], up["end"]["Z"], down["end"]["Z"]) == (7, 5.0, 0.0)  # O0050 from the stop point
    # M99: straight on to the arc's programmed end (N§3.11.4.6 note 2), at the arc's feed, then the next block
    assert resume["kind"] == "line" and resume["tags"] == ["M96", "resume"] and resume["line"] == 3
    assert (xy(resume, "start"), xy(resume), resume["feed"]) == (xy(cut), (0.0, 20.0), 100.0)
    assert (nxt["line"], xy(nxt, "start"), xy(nxt)) == (4, (0.0, 20.0), (30.0, 20.0))
    # interrupted rapid: the rest is a rapid; no M96 active: the trigger is ignored
    r = run_path(capsys, tmp_path, M96_ARC.replace("G00 X0 Y0", "G00 X40. Y0"), "--interrupt", "2", profile=MILL)
    assert [(m["kind"], xy(m)) for m in r.moves[:4]] == [("rapid", (20.0, 0.0)), ("rapid", (20.0, 0.0)),
                                                        ("rapid", (20.0, 0.0)), ("rapid", (40.0, 0.0))]
    r = run_path(capsys, tmp_path, M96_ARC.replace("M96 P50", "M97"), "--interrupt", "3", profile=MILL)
    assert [xy(m) for m in r.moves] == [(0.0, 0.0), (0.0, 20.0), (30.0, 20.0)]
    assert run_path(capsys, tmp_path, M96_ARC, "--interrupt", "3@2", profile=MILL).code == 2
