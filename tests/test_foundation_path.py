"""Issue 2: `hil path --json` gives the moves of a lathe type A program exactly as specified."""

from __future__ import annotations

import math

from tests.conftest import ROOT

KEYS = {"kind", "line", "block", "start", "end", "work", "center", "dir", "feed", "duration"}


def test_moves_have_the_documented_keys_and_machine_radius_x(hil, program):
    p = program("G98\nG00 X50. Z60.\nG01 Z-18. F500\nX30.\nX40. Z-26.\n")
    r = hil("path", p, "--json")
    assert r.code == 0, r.err
    moves = r.json_lines()
    assert all(set(m) == KEYS for m in moves)
    assert [m["kind"] for m in moves] == ["rapid", "line", "line", "line"]
    # X is a diameter in the program, a radius in machine coordinates
    assert moves[0]["end"] == {"X": 25.0, "Z": 60.0}
    assert moves[0]["work"] == {"X": 50.0, "Z": 60.0}
    assert moves[3]["end"] == {"X": 20.0, "Z": -26.0}
    assert moves[3]["start"] == {"X": 15.0, "Z": -18.0}
    assert [m["feed"] for m in moves[1:]] == [500.0, 500.0, 500.0]
    assert moves[2]["line"] == 4 and moves[2]["block"] == "X30."


def test_incremental_u_w_and_final_position(hil, program):
    p = program("G98 G00 X100. Z100.\nG00 U-50. W-40.\nG01 W-10. F200\n")
    moves = hil("path", p, "--json").json_lines()
    assert moves[1]["work"] == {"X": 50.0, "Z": 60.0}
    assert moves[2]["end"] == {"X": 25.0, "Z": 50.0}


def test_arc_points_lie_on_the_radius(hil, program):
    # R form and I/K form of arcs in G18; both CW and CCW
    p = program("G98 G00 X20. Z0.\nG02 X40. Z-10. R10. F300\nG03 X60. Z-20. K-10.\nG02 X40. Z-30. R-10.\n")
    moves = hil("path", p, "--json").json_lines()
    for arc in moves[1:]:
        assert arc["kind"] == "arc"
        c, s, e = arc["center"], arc["start"], arc["end"]
        r0 = math.hypot(s["X"] - c["X"], s["Z"] - c["Z"])
        r1 = math.hypot(e["X"] - c["X"], e["Z"] - c["Z"])
        assert abs(r0 - r1) < 1e-9
    assert moves[1]["dir"] == "cw" and moves[2]["dir"] == "ccw"
    # G02 X40 Z-10 R10 from (X10, Z0) radius: CW seen from +Y in the right-handed (Z, X) plane
    assert moves[1]["center"] == {"X": 20.0, "Z": 0.0}
    # R- selects the 270-degree arc: from (X30, Z-20) to (X20, Z-30) the centre is (X20, Z-20),
    # not (X30, Z-30) which would give the 90-degree arc
    assert moves[3]["center"] == {"X": 20.0, "Z": -20.0}


def test_dwell_p_ms_and_x_seconds(hil, program):
    p = program("G04 P250\nG04 X1.5\nG04 X2\n")
    moves = hil("path", p, "--json").json_lines()
    assert [m["duration"] for m in moves] == [0.25, 1.5, 0.002]  # X2 without a point is 0.002 s (N1.11 bit4 = 0)


def test_decimal_point_rule_integer_means_micrometres(hil, program):
    p = program("G98 G00 X20000 Z-5000\n")
    m = hil("path", p, "--json").json_lines()[0]
    assert m["work"] == {"X": 20.0, "Z": -5.0}


def test_inch_input(hil, program):
    p = program("G20 G98\nG01 Z1. F10.\n")
    m = hil("path", p, "--json").json_lines()[0]
    assert m["end"]["Z"] == 25.4
    assert abs(m["feed"] - 254.0) < 1e-9


def test_example_program_runs_through_path(hil):
    r = hil("path", ROOT / "examples" / "lathe_demo.nc", "--json")
    assert r.code == 0
    moves = r.json_lines()
    assert moves[-1]["work"] == {"X": 100.0, "Z": 50.0}
    assert any(m["kind"] == "arc" for m in moves)


def test_vars_line_reports_vacant_variables(hil, program):
    p = program("G00 X10.\n")
    r = hil("path", p, "--json", "--vars", "100-102,500")
    last = r.json_lines()[-1]
    assert last["kind"] == "vars"
    assert set(last["values"]) == {"100", "101", "102", "500"}
    assert all(v is None for v in last["values"].values())


def test_feed_per_revolution_is_flagged(hil, program):
    moves = hil("path", program("G99 S500 M03\nG01 Z-5. F0.2\nG98\nG01 Z-10. F100\n"), "--json").json_lines()
    assert moves[0]["feed"] == 0.2 and moves[0]["per_rev"] is True
    assert moves[1]["feed"] == 100.0 and "per_rev" not in moves[1]


def test_without_a_bench_path_runs_on_the_default_benchs_profile_and_parameters(hil, program):
    """`hil path` without --bench does not load the bench module (start-up, issue 16): it takes the default
    bench's profile and parameters as constants, which must stay what `default_lathe()` holds."""
    from hil.bench import default_lathe
    from hil.commands.path import DEFAULT_PROFILE

    bench = default_lathe()
    assert (bench.profile, bench.params) == (DEFAULT_PROFILE, {})
    p = program("G00 X50. Z60.\n")
    assert hil("path", p, "--json").json_lines()[0]["end"] == {"X": 25.0, "Z": 60.0}  # a lathe: X a diameter
    r = hil("path", p, "--profile", "zz")
    assert r.code == 2 and "unknown profile 'zz'" in r.err
