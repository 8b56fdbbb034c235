"""The CAM program in real time (issue 17, decision bench B46): with the basic MLC a stepped cycle's whole channel
step, the feed's pushes and the planner's block ends and solves included, runs in the slack before its tick, so the
cycle's work after its tick is its feedback, the scan and its setpoints. On a fake monotonic clock the run is
deterministic: every trace column, `period` and `late` included, equals plain stepping's (DELTAHIL_STRETCH=0),
and so do the alarms, the end and a stop asked in the middle of the program."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from benchmarks.bench_motion import cam_program
from hil import api
from hil.clock import RealTimeClock
from hil.stretch import ENV, Stretcher
from mlc.basic import BasicMlc
from nc.motion.planner import Planner
from tests.conftest import ROOT
from tests.test_realtime_stretch import StopAt, fake_clock

MILL = str(ROOT / "benches" / "mill-3axis.toml")
_PUSH, _FOR_RUNNER = Planner.push, Stretcher.for_runner.__func__  # (the originals: each run wraps them afresh)


def _program(blocks: int, inserts: dict[int, str]) -> str:
    lines = cam_program(blocks).splitlines()
    for at in sorted(inserts, reverse=True):
        lines.insert(at, inserts[at])
    return "\n".join(lines) + "\n"


def _run(monkeypatch, tmp_path, text: str, on: str, stop_at: int | None = None, **kw) -> dict:
    """A real-time run of `text` on the mill bench on a fake clock: its trace columns, result, the stretcher and
    how many of the planner's pushes ran inside a cycle's work (after its tick, before its outputs)."""
    monkeypatch.setenv(ENV, on)
    _, clocks = fake_clock(monkeypatch)
    pushes = {"in cycle": 0, "all": 0}
    push = _PUSH

    def counted(self, move):
        pushes["all"] += 1
        pushes["in cycle"] += clocks[-1]._start_ns is not None and not clocks[-1]._written
        return push(self, move)

    monkeypatch.setattr(Planner, "push", counted)
    made: list[Stretcher] = []
    for_runner = _FOR_RUNNER

    def spy(cls, runner):
        st = for_runner(cls, runner)
        if st is not None:
            made.append(st)
        if stop_at is not None and not any(isinstance(s, StopAt) for s in runner.trace_sources):
            runner.trace_sources.append(StopAt(stop_at))
        return st

    monkeypatch.setattr(Stretcher, "for_runner", classmethod(spy))
    prog = tmp_path / "cam.nc"
    prog.write_text(text)
    path = tmp_path / f"rt{on}.parquet"
    res = api.run(str(prog), MILL, trace=str(path), realtime=True, check=False, trace_signals=None, **kw)
    assert type(res.runner.clock) is RealTimeClock
    table = pq.read_table(path)
    return {"cols": {c: table.column(c).to_pylist() for c in table.column_names}, "res": res,
            "st": made[0] if made else None, "pushes": pushes}


def _same(a: dict, b: dict) -> None:
    ca, cb = a["cols"], b["cols"]
    assert list(ca) == list(cb)
    for c in ca:
        assert ca[c] == cb[c], f"column {c} differs from row {next(i for i, (x, y) in enumerate(zip(ca[c], cb[c])) if x != y)}"
    ra, rb = a["res"], b["res"]
    assert [x.code_text for x in ra.alarms] == [x.code_text for x in rb.alarms]
    assert ra.run.final == rb.run.final and ra.run.cycles == rb.run.cycles and ra.run.finished == rb.run.finished
    assert ra.run.stopped_by == rb.run.stopped_by


def test_the_cam_programs_feeds_and_solves_run_before_the_tick_and_equal_stepping(monkeypatch, tmp_path):
    text = cam_program(600)
    a = _run(monkeypatch, tmp_path, text, "0")
    b = _run(monkeypatch, tmp_path, text, "1")
    _same(a, b)
    assert a["st"] is None and a["pushes"]["in cycle"] == a["pushes"]["all"] > 600  # stepping: every push in a cycle
    r, st = b["res"].run, b["st"]
    assert r.ok and r.overruns == 0 and set(a["cols"]["period"][1:]) == {0.001}
    stepped = r.cycles - r.stretched
    assert st.steps_ahead > 0.75 * stepped > 100  # the stepped cycles' channel steps ran in the slack before them
    assert b["pushes"]["in cycle"] < 0.02 * b["pushes"]["all"]  # and so did the feeds' pushes


@pytest.mark.parametrize("inserts, alarm", [
    ({150: "M08", 300: "#100=#100+1", 301: "#101=#100*2", 400: "G04 P10", 500: "M09"}, None),
    ({450: "X400. Y0.5"}, "0x0A01"),  # beyond the 300 mm soft limit: the moves before it run out, then the alarm
])
def test_other_events_in_the_cam_program_step_as_before(monkeypatch, tmp_path, inserts, alarm):
    b = events_equal_stepping(lambda text, on: _run(monkeypatch, tmp_path, text, on), 600, inserts, alarm)
    assert b["st"].steps_ahead > 100


def events_equal_stepping(run, blocks: int, inserts: dict[int, str], alarm: str | None) -> dict:
    """The CAM program with `inserts` run stepped ("0") and with the work ahead ("1"): the same trace, and the
    alarm expected (or none); the run with the work ahead, for what it did. Shared with test_realtime_bus_ahead."""
    text = _program(blocks, inserts)
    a, b = run(text, "0"), run(text, "1")
    _same(a, b)
    assert [x.code_text for x in b["res"].alarms] == ([] if alarm is None else [alarm])
    return b


@pytest.mark.parametrize("kw", [{"stop_at": 700}, {"feed_override": 80.0},
                                {"events": ["t=0.3:feed-hold", "t=0.5:cycle-start"]}],
                         ids=["stop", "override", "hold-resume"])
def test_a_stop_an_override_and_a_hold_in_the_cam_program_equal_stepping(monkeypatch, tmp_path, kw):
    """A stop asked in a cycle lands on the next one (the step ahead of it is not made: a stop is pending); with the
    MLC's overrides off 100 % (its scan writes them every cycle) no step is taken ahead; `--at` events (a feed hold
    and a cycle start) write MLC devices, so they run the Delta MLC, which takes no step ahead either."""
    text = cam_program(800)
    a = _run(monkeypatch, tmp_path, text, "0", **kw)
    b = _run(monkeypatch, tmp_path, text, "1", **kw)
    _same(a, b)
    st = b["st"]
    if "feed_override" in kw:
        assert st.steps_ahead == 0
    elif "events" in kw:
        assert type(b["res"].runner.mlc) is not BasicMlc and st.steps_ahead == 0
    else:
        assert st.steps_ahead > 100
    if "stop_at" in kw:
        assert b["res"].run.stopped_by == "SIGINT" and b["res"].run.cycles < 1000


def test_the_lathe_demo_on_the_basic_mlc_equals_stepping(monkeypatch, tmp_path):
    """The lathe demo with the basic MLC: G96, feed per revolution, threads and M/S codes, where the step ahead must
    stand back (a G96 speed, a thread, a code pending) and a G96 move it starts is kept from the scan."""
    from tests.test_realtime_stretch import _run as run_demo, _same as same_demo

    made: list[Stretcher] = []

    def spy(cls, runner):
        st = _FOR_RUNNER(cls, runner)
        made.append(st)
        return st

    monkeypatch.setattr(Stretcher, "for_runner", classmethod(spy))
    a = run_demo(monkeypatch, tmp_path, "0", mlc="basic")
    b = run_demo(monkeypatch, tmp_path, "1", mlc="basic")
    same_demo(a, b)
    r = b[1].run
    assert type(b[1].runner.mlc) is BasicMlc and r.ok
    assert r.stretched > 0.9 * r.cycles and made[-1].steps_ahead > 0  # (most of the rest: G96, threads, codes)
