"""A stretch's part as `cut_rows` takes it (nc.motion.stretch; compiled in nc.motion.planner_cruise, decisions bench
B190 and B191): on the CAM program (0.01-0.1 mm blocks at F3000, mill-3axis, no share zones) a part that takes the
whole buffer hands out the planner's own buffer arrays and lines, a part of it those rows; either way the rows are
the buffer's values, λ is None, the planner stands at the part's last row, and the stretched trace equals stepping's
column by column."""

from __future__ import annotations

import types

import numpy as np
import pytest

import hil.stretch_pass as stretch_pass
import nc.motion.compiled as compiled
import nc.motion.planner_cruise as planner_cruise
import nc.motion.stretch as stretch
from benchmarks.bench_motion import cam_program
from benchmarks.trace_ab import compare, one
from hil.stretch import ENV
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")


def test_the_stretch_takes_its_parts_with_the_planners_compiled_functions():
    # nc.motion.stretch hands out planner_cruise's functions by their old names (hil/stretch_pass.py imports them)
    assert stretch.cut_rows is planner_cruise.cut_rows and stretch_pass.cut_rows is planner_cruise.cut_rows
    assert stretch.refuses is planner_cruise.refuses and stretch_pass.refuses is planner_cruise.refuses
    if compiled.BUILD == "compiled":  # C functions typed on the planner's fields, not Python functions
        assert not isinstance(planner_cruise.cut_rows, types.FunctionType)
        assert not isinstance(planner_cruise.refuses, types.FunctionType)


def test_a_whole_buffer_part_is_the_buffer_and_a_partial_part_its_rows(monkeypatch, tmp_path):
    prog = tmp_path / "cam.nc"
    prog.write_text(cam_program(300))
    seen: list[tuple[str, bool]] = []
    failed: list[str] = []  # (an assertion raised inside the run would end it as an internal error: kept here)
    take = stretch_pass.cut_rows

    def cut(pl, i, m, mv):
        try:
            return checked(pl, i, m, mv)
        except AssertionError as e:
            failed.append(f"rows {i}..{i + m - 1} of {len(pl._buf_pos)}: {e!r}")
            raise

    def checked(pl, i, m, mv):
        pos, vel, lines = pl._buf_pos, pl._buf_vel, pl._buf_line
        want = (pos[i:i + m].copy(), vel[i:i + m].copy(), lines[i:i + m], pl._buf_state[i + m - 1])
        got = take(pl, i, m, mv)
        raw, lam, ln, v, mv2, _ = got
        whole = i == 0 and m == len(pos)
        if whole:  # the buffer's own objects, not views of all of them
            assert raw is pos and v is vel and ln is lines
        else:
            assert raw.base is not None and np.shares_memory(raw, pos) and np.shares_memory(v, vel)
        assert raw.shape == (m, pos.shape[1]) and v.shape == (m,) and raw.dtype == v.dtype == np.float64
        assert raw.tobytes() == want[0].tobytes() and v.tobytes() == want[1].tobytes() and ln == want[2]
        assert lam is None and mv2 is mv  # mill-3axis has no share zones: λ is 1 throughout
        # the planner as after the part's last step: its row, line and (s, v, a)
        assert pl._buf_i == i + m and pl.position.tobytes() == want[0][-1].tobytes() and pl.line == want[2][-1]
        assert (pl.s, pl.v, pl.a) == want[3]
        seen.append(("whole" if whole else "part", pl._buf_blk is not None))
        return got

    monkeypatch.setattr(stretch_pass, "cut_rows", cut)
    kw = {"bench": MILL, "trace_signals": None}
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), kw, tmp_path / f"{on}.parquet", kept))
    assert failed == []
    assert compare(out[0], out[1]) == []
    assert kept[1].run.ok and kept[1].run.stretched > 0.4 * kept[1].run.cycles
    # both kinds of part, and parts of a cruise's buffer (across its blocks) among them
    assert seen.count(("whole", False)) > 20 and sum(k == "part" for k, _ in seen) > 20, seen
    assert any(c for _, c in seen)


@pytest.mark.parametrize("kind, tags, per_rev, plan, asked, refused", [
    ("line", (), False, "path", False, False),
    ("thread", (), False, None, False, True),
    ("line", ("G31",), False, None, False, True),
    ("line", (), True, "path", False, True),  # a feed-per-revolution path: the measured speed re-plans it
    ("line", (), True, "path", True, False),  # unless the caller samples per revolution
    ("line", (), True, "cruise", False, False),
])
def test_refuses_what_a_stretch_may_not_take(kind, tags, per_rev, plan, asked, refused):
    from nc.motion.limits import MotionConfig
    from nc.motion.plan_state import _Plan
    from nc.motion.planner import Planner

    pl = Planner(MotionConfig(axes=("X", "Y", "Z")), {"X": 0.0, "Y": 0.0, "Z": 0.0})
    pl.plan = None if plan is None else _Plan(plan, None, 1.0, 0.0)
    mv = types.SimpleNamespace(kind=kind, tags=tags, per_rev=per_rev)
    assert stretch.refuses(pl, mv, asked) is refused
