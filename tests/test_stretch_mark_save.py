"""A stretch pass's mark save (hil.stretch_pass._save, issue 17, decisions bench B159 and B170): taken from a real
CAM run's planner at a mark, the planner stepped on (blocks finished, plans solved, its filter fed), then put back
with `_restore_planner`: every field, the queue, the plan's fields, the share zones and the filter are as at the
mark, and the planner steps on to the same setpoints as the first time."""

from __future__ import annotations

import os
import tempfile

import numpy as np

import hil.stretch_pass as sp
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from hil.runner import BenchRunner
from hil.session import make_link
from hil.stretch_state import _restore_planner
from hil.trace import open_trace
from nc.motion.plan_core import state_fields
from nc.program import parse_program
from tests.conftest import ROOT


def _state(pl) -> tuple:
    """What a restore must give back, each part copied (identity of the queue's blocks, the plan's fields)."""
    f = pl.filter
    return (state_fields(pl.state()), list(pl.blocks), pl.plan, None if pl.plan is None else dict(pl.plan.__dict__),
            None if pl._zones is None else list(pl._zones.zones), None if f is None else f.snapshot())


def _setpoints(pl, n: int) -> list:
    return [(np.array(s.positions, copy=True).tolist(), s.line, s.path_velocity) for s in (pl.step() for _ in range(n))]


def test_a_mark_save_puts_the_planner_back_as_it_was_after_steps(monkeypatch):
    caught = []
    real = sp._save

    def save(pl, filt=True):
        saved = real(pl, filt)
        if len(caught) < 40 and pl.plan is not None:
            caught.append(pl)
            if len(caught) == 40:  # far into the run: a full queue, a plan running
                raise KeyboardInterrupt
        return saved

    monkeypatch.setattr(sp, "_save", save)
    bench = load_bench_file(ROOT / "benches" / "mill-3axis.toml")
    runner = BenchRunner(bench, make_link(bench), None)
    runner.trace = open_trace(os.path.join(tempfile.mkdtemp(), "cam.parquet"), runner.trace_columns())
    try:
        runner.run_program(parse_program(cam_program(400), name="cam.nc"))
    except KeyboardInterrupt:
        pass
    pl = caught[-1]
    before = _state(pl)
    saved = real(pl)
    first = _setpoints(pl, 12)  # a dozen cycles: blocks finished, a new plan, the filter's windows moved
    assert len(pl.blocks) < len(before[1]) and pl.plan is not before[2]
    _restore_planner(pl, saved)
    after = _state(pl)
    assert after[0].keys() == before[0].keys()
    assert all(after[0][k] is v or after[0][k] == v for k, v in before[0].items() if not isinstance(v, np.ndarray))
    assert all(np.array_equal(after[0][k], v) for k, v in before[0].items() if isinstance(v, np.ndarray))
    assert [id(b) for b in after[1]] == [id(b) for b in before[1]] and pl.blocks is before[0]["blocks"]
    assert after[2] is before[2] and after[3].keys() == before[3].keys()
    assert all(after[3][k] is v or after[3][k] == v for k, v in before[3].items())
    assert after[4] == before[4] and pl.filter.same_state(before[5])
    assert _setpoints(pl, 12) == first
