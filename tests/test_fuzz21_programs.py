"""Bugs found by running seeded random programs through `hil run` (session 20, fuzz21).

Each test is the minimised program of one finding; it runs the program on a shipped bench, lock-step, and
checks what a user would: the run agrees with `hil path`, the bench's checks pass, alarms name their block.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import hil as hil_api
from nc.alarms import NcAlarm

ROOT = Path(__file__).resolve().parent.parent
MILL = ROOT / "benches" / "mill-3axis.toml"
LATHE = ROOT / "benches" / "lathe-2axis.toml"


def _run(tmp_path: Path, text: str, bench: Path = MILL, **kw):
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    trace = tmp_path / "t.parquet"
    return hil_api.run(prog, bench=bench, check=True, trace=trace, **kw), hil_api.path(prog, bench=bench)


def test_g49_in_the_first_block_keeps_z_where_it_stands(tmp_path):
    """A safety line `G49` before the first move (no length offset was active) must not move Z: the run
    started from the bench's power-on Z 100 but took the programmed Z as 0 and dived to machine Z 0
    before the first rapid, a move `hil path` does not have (and the contour check failed on it)."""
    r, moves = _run(tmp_path, "G21 G17 G90 G40 G49 G80 G54\nG00 X0. Y0. Z30.\nM30\n")
    assert r.ok, (r.alarms, [c for c in r.checks if not c.ok])
    z = r.trace.load().column("Z_cmd").to_pylist()
    assert min(z) >= 30.0 - 1e-9  # from 100 down to 30, never below
    assert [m.end["Z"] for m in moves if hasattr(m, "end")] == [30.0]
    assert r.final_position["Z"] == 30.0


def test_block_end_variables_at_program_start_are_where_the_axes_stand(tmp_path):
    """Block-end coordinates (#21032+, the Z one #21034) read before any move (Appendix B: the last block's end point) are
    the power-on position in the run as in `hil path`."""
    r, _ = _run(tmp_path, "#100=#21034\nG00 Z[#100-10.]\nM30\n")
    assert r.ok, r.alarms
    assert r.final_position["Z"] == 90.0


def test_a_zero_length_block_at_a_blended_corner_is_not_contour_error(tmp_path):
    """`X0. Y0.` where the tool already is, between a Z plunge and an XY cut at another feed: the drives stay
    within 0.02 mm of the programmed corner, but the contour check judged the corner's blend (the plunge's
    line) only against the plunge and the zero-length move, not the cut after it, and failed at 0.056 mm."""
    text = "G00 X0. Y0. Z30.\nG01 Z1.379 F300.\nX0. Y0.\nX-35.514 Y-36.25 F120.\nM30\n"
    r, _ = _run(tmp_path, text)
    contour = next(c for c in r.checks if c.name == "contour error")
    assert contour.ok and contour.value < 0.03, contour
    # the same corner without the zero-length block is judged the same
    r2, _ = _run(tmp_path, text.replace("X0. Y0.\n", "", 1))
    assert next(c for c in r2.checks if c.name == "contour error").value == pytest.approx(contour.value, abs=2e-3)


def test_a_compensated_block_that_runs_backwards_names_its_line(tmp_path):
    """G70 finishing under G42 (nose 0.8) whose last element, a 1.086 mm face, is shorter than the inner
    corner's trim toward the return to the start point: the interference alarm 0x120B is right, but it came
    with no line and no block (`hil path --json` printed `"line": null`). It names the block that runs backwards."""
    text = ("G10 L10 P1 R0.8 Q3\nG21 G99\nT0101\nG96 S180 M03\nG00 X60. Z20.\nG00 X45. Z5.\n"
            "G71 U1. R0.9\nG71 P100 Q150 U0.03 W0.1 F0.3\nN100 G00 X13.438\nG01 Z0. F0.15\nZ-6.44\nX21.956\n"
            "X23.699 Z-7.867\nX32.419\nZ-12.328\nN150 X34.591\nG42 G00 X45. Z2.\nG70 P100 Q150\nG40 G00 X60. Z20.\n"
            "M30\n")
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    with pytest.raises(NcAlarm) as exc:
        hil_api.path(prog, bench=LATHE)
    a = exc.value.alarm
    assert (a.code, a.line, a.block) == (0x120B, 16, "N150 X34.591"), a
    r = hil_api.run(prog, bench=LATHE)
    assert not r.completed and [(x.code, x.line, x.block) for x in r.alarms] == [(0x120B, 16, "N150 X34.591")]


def test_a_negative_f_in_a_cycle_block_is_the_negative_f_alarm(tmp_path):
    """`G94 X14.416 Z-2.42 F0.2 F-1` (a repeated F, the last wins, A9): a negative F is 0x0223 "F must not be
    negative" in a G01 block, but in a cycle's block it was dropped and the cycle said 0x1001 "no F programmed"."""
    for bench, text in ((LATHE, "G00 X42. Z2.\nG94 X14.416 Z-2.42 F0.2 F-1\nM30\n"),
                        (MILL, "G99 G81 X10. Y10. Z-5. R2. F-300.\nG80\nM30\n")):
        prog = tmp_path / "p.nc"
        prog.write_text(text)
        with pytest.raises(NcAlarm) as exc:
            hil_api.path(prog, bench=bench)
        assert (exc.value.alarm.code, exc.value.alarm.line) == (0x0223, 2 if bench == LATHE else 1), exc.value


@pytest.mark.parametrize("p, k", [("P500", 0.5), ("P2000", 2.0)])
def test_an_r_arc_under_g51_scales_its_radius_with_its_end_points(tmp_path, p, k):
    """N§3.12.3: G51 scales the programmed path about its centre. An R-form arc's end points were scaled but its R
    was not: at P2000 a half circle `G03 X-10. Y0. R10.` from X10. became 0x0259 (R10 < half the scaled chord 20),
    at P500 a 10 mm arc over a 10 mm chord, centre off by 8.66 mm. The scaled arc is the programmed one, scaled."""
    text = f"G00 X0. Y0.\nG51 X0. Y0. {p}\nG01 X10. Y0. F600.\nG03 X-10. Y0. R10.\nG50\nG00 X0. Y0.\nM30\n"
    r, moves = _run(tmp_path, text)
    arc = next(m for m in moves if getattr(m, "kind", "") == "arc")
    assert (arc.start["X"], arc.end["X"]) == pytest.approx((10.0 * k, -10.0 * k))
    assert (arc.center["X"], arc.center["Y"]) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert r.ok, (r.alarms, [c for c in r.checks if not c.ok])
