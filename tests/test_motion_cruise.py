"""Decision motion 44: a block the planner enters at its cap, with zero acceleration, and leaves at its cap
is sampled as constant speed without a solve (`Planner._cruise`); `Planner.per_block` solves every block as
before. Both on benches/mill-3axis.toml: the same setpoints, fewer solves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.bench_motion import cam_program
from benchmarks.bench_vs_linuxcnc import START, cam_polyline, cam_surface, chord_circle
from hil.bench_file import load_bench_file
from nc.interp import Interpreter
from nc.motion.offline import Stream, run
from nc.motion.planner import Planner
from nc.profiles import make_profile
from nc.program.blocks import parse_program
from tests.test_motion_cam import moves

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def both(events_of, start: dict[str, float], monkeypatch) -> list[tuple[Stream, int]]:
    """(stream, ruckig solves) per-block first, then with cruises."""
    out = []
    for per_block in (True, False):
        monkeypatch.setattr(Planner, "per_block", per_block)
        seen: dict = {}
        st = run(events_of(), load_bench_file(BENCH).motion_config(), start,
                 on_cycle=lambda n, ch: seen.setdefault("pl", ch.planner))
        assert st.state.value == "finished" and not st.alarms
        out.append((st, seen["pl"].solves))
    return out


@pytest.mark.parametrize("make", [lambda: chord_circle(10.0), lambda: chord_circle(5.0), cam_polyline,
                                  pytest.param(cam_surface, marks=pytest.mark.slow)])  # ≈ 11 s: -m slow
def test_cruise_gives_the_per_block_setpoints(make, monkeypatch):
    prog = make()
    (ref, ref_solves), (new, new_solves) = both(lambda: moves(prog), dict(zip("XYZ", START)), monkeypatch)
    assert len(new.positions) == len(ref.positions)
    assert np.abs(new.positions - ref.positions).max() <= 1e-9
    assert np.array_equal(new.lines, ref.lines)
    assert new_solves < ref_solves


def test_cam_program_cruises_most_blocks(monkeypatch):
    """The bench benchmark's CAM program (5,000 G01 blocks of 0.01-0.1 mm at F3000) through the interpreter:
    most blocks run at the cap between junctions that allow it. Bit for bit: a plan time one ulp off at one
    block start turns a later solve at a tolerance's edge (path or ramp) and moves the path by up to 0.09 mm."""
    prog = parse_program(cam_program(5000), name="cam.nc")
    (ref, ref_solves), (new, new_solves) = both(
        lambda: Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog), {"X": 0.0, "Y": 0.0, "Z": 100.0},
        monkeypatch)
    assert len(new.positions) == len(ref.positions)
    assert np.array_equal(new.positions, ref.positions)
    assert new_solves < 0.5 * ref_solves, (new_solves, ref_solves)

