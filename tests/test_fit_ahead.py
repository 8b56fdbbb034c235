"""Fitted windows worked out ahead by a second process (decision bench B86): the same setpoints as fitting them in
the cycle, every window taken from the child where it saw the run's inputs, the child started again when the axes
stood elsewhere than guessed, and reaped when the run ends."""

from __future__ import annotations

import json
import os

import numpy as np
import pyarrow.parquet as pq
import pytest

from benchmarks.bench_vs_linuxcnc import cam_polyline
import hil.runner
from hil import api, fit_ahead
from hil.bench_file import load_bench_file
from hil.run_output import to_json
from nc.interp import Interpreter
from nc.motion.offline import run as offline_run
from nc.profiles import make_profile
from nc.program.blocks import parse_program
from tests.conftest import ROOT
from tests.test_realtime_stretch import fake_clock

MILL = ROOT / "benches" / "mill-3axis.toml"
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the second process is forked (POSIX)")


@pytest.fixture(scope="module")
def program_text() -> str:
    return cam_polyline(100).text(False)  # 100 segments of ≈ 0.8 mm turning ≈ 15°: fitted, 5 windows


def _columns(path) -> dict:
    t = pq.read_table(path)
    return {c: t.column(c).to_pylist() for c in t.column_names}


def _run(monkeypatch, tmp_path, text: str, mode: str, realtime: bool = False, tag: str = "") -> tuple:
    monkeypatch.setenv("DELTAHIL_FIT_AHEAD", mode)
    prog = tmp_path / "cam.nc"
    prog.write_text(text)
    trace = tmp_path / f"t{mode}{tag}.parquet"
    res = api.run(str(prog), str(MILL), trace=str(trace), realtime=realtime, check=False, trace_signals=None)
    return res, _columns(trace)


def _same(a: dict, b: dict) -> None:
    assert list(a) == list(b)
    for c in a:
        if c not in ("period", "late"):  # (real time: the pacing's own columns)
            assert a[c] == b[c], f"column {c}"


def test_windows_from_the_child_give_the_same_setpoints_as_fitting_in_the_cycle(monkeypatch, tmp_path, program_text):
    off, cols_off = _run(monkeypatch, tmp_path, program_text, "0")
    ahead, cols_ahead = _run(monkeypatch, tmp_path, program_text, "wait")
    assert off.run.fits_ahead is None  # no second process
    found, fitted = ahead.run.fits_ahead
    assert found >= 4 and fitted == 0  # every window taken from the child
    _same(cols_off, cols_ahead)
    assert ahead.run.final == off.run.final and ahead.ok and off.ok


def test_the_child_starts_again_from_where_the_axes_stood(program_text):
    """Guessed wrong before power-up (a real drive stood elsewhere): the child runs the program again from where
    `begin` says, and its windows are those the run needs."""
    cfg = load_bench_file(MILL).motion_config()
    prog = parse_program(program_text, name="cam.nc")
    actual = {"X": 0.0, "Y": 0.0, "Z": 100.0}

    def interp():
        return Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))

    child = fit_ahead.start(interp(), prog, cfg, {"X": 5.0, "Y": -3.0, "Z": 80.0}, wait=True)
    assert child is not None
    try:
        child.begin(dict(actual))
        it = interp()
        it.take_position(actual)
        with_child = offline_run(it.run(prog), cfg, actual, fit_memo=child.memo)
    finally:
        found, fitted = child.close()
    it = interp()
    it.take_position(actual)
    alone = offline_run(it.run(prog), cfg, actual)
    assert found >= 4 and fitted == 0
    assert np.array_equal(with_child.positions, alone.positions)


def test_a_real_time_run_takes_windows_from_the_child_and_reaps_it(monkeypatch, tmp_path, program_text):
    made: list[fit_ahead.FitAhead] = []
    start = fit_ahead.start

    def spy(*a, **k):
        child = start(*a, **k)
        made.append(child)
        return child

    monkeypatch.setattr(fit_ahead, "start", spy)
    # The prefetch waits on the wall clock for the child's first windows (1 s in a run); a loaded CI machine took
    # longer to fork and run the child that far, and the run on its fake clock then finished before any window came.
    # It returns as soon as the child has them, so the longer bound costs nothing where the machine is quiet.
    monkeypatch.setattr(hil.runner, "PREFETCH_S", 60.0)
    fake_clock(monkeypatch)
    rt, cols_rt = _run(monkeypatch, tmp_path, program_text, "auto", realtime=True)
    monkeypatch.setattr(fit_ahead, "start", start)
    off, cols_off = _run(monkeypatch, tmp_path, program_text, "0", realtime=True, tag="rt")
    assert len(made) == 1 and off.run.fits_ahead is None
    found, fitted = rt.run.fits_ahead
    assert found >= 1 and found + fitted >= 4  # (on a fake clock the run may outpace the child: those fitted here)
    _same(cols_off, cols_rt)
    with pytest.raises(ChildProcessError):  # reaped: no child left behind
        os.waitpid(made[0].pid, os.WNOHANG)
    assert json.loads(to_json(rt))["fitted_windows"] == {"ahead": found, "in_cycle": fitted}


def test_a_lock_step_run_starts_no_child(monkeypatch, tmp_path, program_text):
    res, _ = _run(monkeypatch, tmp_path, program_text, "auto")  # lock-step: fitting in the cycle misses no deadline
    assert res.run.fits_ahead is None


def test_a_fork_that_fails_leaves_the_windows_to_the_cycle(monkeypatch, tmp_path, program_text):
    def no_fork():
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(fit_ahead.os, "fork", no_fork)
    res, cols = _run(monkeypatch, tmp_path, program_text, "wait")
    _, cols_off = _run(monkeypatch, tmp_path, program_text, "0", tag="off")
    assert res.ok and res.run.fits_ahead is None
    _same(cols_off, cols)


SPAN_NS = 40_000  # a span's unpickling, paced (a window's 80: 1.5-3.5 ms, decision bench B98)
LIMITS_NS = 30_000  # a span's `span_limits` (B99)


def test_windows_are_decoded_a_span_a_slack_and_their_cycle_misses_no_deadline(monkeypatch, tmp_path, program_text):
    """B98-B99 on the fake clock, with a modelled cost: every span's unpickling and limits advance the clock. The run's
    windows are decoded and their spans' limits worked out a span at a time in the slacks before they are needed, so
    no cycle overruns (before: a window's 80 spans decoded and limited in its cycle, ≈ 5.6 ms modelled); the
    setpoints are those of fitting in the cycle, bit for bit."""
    from nc.motion import fit_memo, planner_runs
    from nc.motion.spline_runs import SplineSpan

    ft, _ = fake_clock(monkeypatch)
    real_pickle, real_limits = fit_memo.pickle, planner_runs._span_limits or planner_runs._load_span_limits()

    class CostlyPickle:
        HIGHEST_PROTOCOL = real_pickle.HIGHEST_PROTOCOL
        dumps = staticmethod(real_pickle.dumps)

        @staticmethod
        def loads(blob):
            obj = real_pickle.loads(blob)
            one = isinstance(obj, SplineSpan)
            spans = sum(isinstance(x, SplineSpan) for x in obj) if isinstance(obj, list) else one
            ft.t += SPAN_NS * spans
            return obj

    def costly_limits(*a):
        ft.t += LIMITS_NS
        return real_limits(*a)

    memos: list = []
    begin = fit_ahead.FitAhead.begin

    def begin_then_read_all(self, start):  # every window in hand before the first cycle: no race with the child
        begin(self, start)
        self.memo.wait = True
        self.memo._drain(b"\xff" * fit_memo.KEY_SIZE)  # (no such key: reads to the child's end)
        self.memo.wait = False
        memos.append(self.memo)

    monkeypatch.setattr(fit_memo, "pickle", CostlyPickle)
    monkeypatch.setattr(planner_runs, "_span_limits", costly_limits)
    monkeypatch.setattr(fit_ahead.FitAhead, "begin", begin_then_read_all)
    rt, cols_rt = _run(monkeypatch, tmp_path, program_text, "auto", realtime=True)
    off, cols_off = _run(monkeypatch, tmp_path, program_text, "0", realtime=True, tag="rt")
    assert off.run.overruns >= 5  # fitted in the cycle (whose fit itself costs nothing modelled here)
    assert rt.run.overruns == 0  # (before B98-B99: 5, one a window: its 80 spans decoded and limited in its cycle)
    found, fitted = rt.run.fits_ahead
    assert found == 5 and fitted == 0 and memos[0].decoded_ahead == 5  # every window decoded before its cycle
    _same(cols_off, cols_rt)


def test_the_terminals_ctrl_c_and_ctrl_backslash_leave_the_child_to_the_run(program_text):
    """The terminal sends SIGINT (Ctrl-C) and SIGQUIT (Ctrl-\\) to the whole foreground group: the run stops on them
    (B94) and ends the child itself; the child must not die of them first (it did of SIGQUIT, and the rest of the
    run's windows were then fitted in the cycle)."""
    import signal
    import time

    cfg = load_bench_file(MILL).motion_config()
    prog = parse_program(program_text, name="cam.nc")
    actual = {"X": 0.0, "Y": 0.0, "Z": 100.0}
    child = fit_ahead.start(Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))), prog, cfg, dict(actual), wait=True)
    assert child is not None
    try:
        time.sleep(0.5)  # the child has set its signals up (a signal in the fork's first instant: see B94's note)
        for sig in (signal.SIGINT, signal.SIGQUIT):
            os.kill(child.pid, sig)
        time.sleep(0.2)
        assert os.waitpid(child.pid, os.WNOHANG) == (0, 0)  # still running
        child.begin(dict(actual))
        it = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
        it.take_position(actual)
        offline_run(it.run(prog), cfg, actual, fit_memo=child.memo)
    finally:
        found, fitted = child.close()
    assert found >= 4 and fitted == 0  # every window still came from the child
