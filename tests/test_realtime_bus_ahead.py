"""Real time on a field bus: the next cycle's refill and feed reads worked out in the slack after the cycle before
(issue 17, decision bench B60, hil/bus_ahead.py).

On a fake clock over the in-process virtual CANopen network (a field-bus link: the exchange comes after the tick)
the run's trace equals stepping's (`DELTAHIL_STRETCH=0`) in every column, `period` and `late` included, with the
same alarms and end, while refills and feeds were worked out ahead; where the NC does not run quietly (an M code,
macro statements, a dwell, a soft-limit alarm, a stop, an override, a hold, G96, feed per revolution, threads)
the cycles step as before. The root test runs the CAM program in real time over virtual EtherCAT slaves in their
own network namespace and compares its setpoints with lock-step's.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from benchmarks.bench_motion import cam_program
from hil import api
from hil.bus_ahead import BusAhead
from hil.clock import RealTimeClock
from hil.stretch import ENV
from tests.conftest import ROOT
from tests.test_realtime_cam import _same, events_equal_stepping
from tests.test_realtime_stretch import StopAt, fake_clock
from virtual_bus.ethercat.veth import SimProcess, can_create

MILL = str(ROOT / "benches" / "mill-3axis.toml")
LATHE = str(ROOT / "benches" / "lathe-2axis.toml")
BUS = "canopen:virtual"


def _run(monkeypatch, tmp_path, text: str, on: str, bench: str = MILL, stop_at: int | None = None, **kw) -> dict:
    """A real-time run of `text` over the virtual CANopen network on a fake clock: its trace columns, result and
    the work ahead it made (None with DELTAHIL_STRETCH=0)."""
    monkeypatch.setenv(ENV, on)
    fake_clock(monkeypatch)
    made: list[BusAhead | None] = []
    for_runner = BusAhead.for_runner.__func__

    def spy(cls, runner):
        made.append(for_runner(cls, runner))
        if stop_at is not None and not any(isinstance(s, StopAt) for s in runner.trace_sources):
            runner.trace_sources.append(StopAt(stop_at))
        return made[-1]

    monkeypatch.setattr(BusAhead, "for_runner", classmethod(spy))
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    path = tmp_path / f"rt{on}.parquet"
    res = api.run(str(prog), bench, bus=BUS, trace=str(path), realtime=True, check=False, trace_signals=None, **kw)
    assert type(res.runner.clock) is RealTimeClock
    table = pq.read_table(path)
    return {"cols": {c: table.column(c).to_pylist() for c in table.column_names}, "res": res,
            "st": made[0] if made else None}


def test_the_cam_programs_refills_and_feeds_are_worked_out_ahead_and_equal_stepping(monkeypatch, tmp_path):
    text = cam_program(300)
    a = _run(monkeypatch, tmp_path, text, "0")
    b = _run(monkeypatch, tmp_path, text, "1")
    _same(a, b)
    assert a["st"] is None and b["res"].run.ok
    st = b["st"]
    assert st.ahead_used > 30 and st.peeks > 30  # block ends' refills and feeds' events made in the slack


@pytest.mark.parametrize("inserts, alarm", [
    ({60: "M08", 120: "#100=#100+1", 121: "#101=#100*2", 180: "G04 P10", 240: "M09"}, None),
    ({200: "X400. Y0.5"}, "0x0A01"),  # beyond the 300 mm soft limit: the moves before it run out, then the alarm
])
def test_other_events_in_the_cam_program_step_as_before(monkeypatch, tmp_path, inserts, alarm):
    b = events_equal_stepping(lambda text, on: _run(monkeypatch, tmp_path, text, on), 300, inserts, alarm)
    assert b["st"].peeks > 10


@pytest.mark.parametrize("kw", [{"stop_at": 250}, {"feed_override": 80.0},
                                {"events": ["t=0.15:feed-hold", "t=0.25:cycle-start"]}],
                         ids=["stop", "override", "hold-resume"])
def test_a_stop_an_override_and_a_hold_equal_stepping(monkeypatch, tmp_path, kw):
    """A stop lands on the next cycle; the feed override at 80 % (the refill ahead is made at 80 %, and taken where
    the scan wrote the same); a hold and a cycle start run the Delta MLC (a refill ahead is taken only where its gated user scan wrote nothing:
    the channel's signature as the refill read it)."""
    text = cam_program(600)  # ≈ 700 cycles
    a = _run(monkeypatch, tmp_path, text, "0", **kw)
    b = _run(monkeypatch, tmp_path, text, "1", **kw)
    _same(a, b)
    if "stop_at" in kw:
        assert b["res"].run.stopped_by == "SIGINT" and b["res"].run.cycles < 500
    else:
        assert b["st"].ahead_used > 0
    if "events" in kw:
        assert type(b["res"].runner.mlc).__name__ != "BasicMlc"


def test_the_lathe_demo_on_the_basic_mlc_equals_stepping(monkeypatch, tmp_path):
    """G96, feed per revolution, threads and M/S codes: the refill that would read spindle feedback is left to the
    cycle's step, a feed is read ahead only where it takes plain moves."""
    text = (ROOT / "examples" / "lathe_demo.nc").read_text()
    a = _run(monkeypatch, tmp_path, text, "0", bench=LATHE, mlc="basic")
    b = _run(monkeypatch, tmp_path, text, "1", bench=LATHE, mlc="basic")
    _same(a, b)
    assert b["res"].run.ok and b["st"].ahead_used > 0


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_the_cam_program_in_real_time_over_virtual_ethercat_sets_lock_steps_positions(tmp_path):
    """Real time, a real clock: the setpoints every cycle sent are lock-step's on the sim bus (the NC reads no
    feedback in a plain CAM program), within 1e-9 mm, without an alarm."""
    pytest.importorskip("pysoem", reason="the EtherCAT master needs pysoem")
    prog = tmp_path / "cam.nc"
    prog.write_text(cam_program(400) + "\n")
    rt, ls = tmp_path / "rt.parquet", tmp_path / "ls.parquet"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop(ENV, None)
    with SimProcess("--bench", MILL, tag="rtba") as sim:
        p = subprocess.run([sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", MILL, "--bus",
                            f"ethercat:{sim.iface}", "--realtime", "--no-check", "--trace", str(rt)],
                           capture_output=True, text=True, timeout=180, cwd=ROOT, env=env)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stdout + p.stderr
    api.run(str(prog), MILL, trace=str(ls), check=False, trace_signals=None)
    a, b = pq.read_table(rt), pq.read_table(ls)
    cols = [c for c in b.column_names if c.endswith("_cmd") and not c.startswith("S")]
    ra, rb = _from_motion(a, cols), _from_motion(b, cols)
    assert cols and len(ra) == len(rb) > 300  # (the bring-ups' cycles differ: compared from the first move on)
    assert max(abs(p - q) for x, y in zip(ra, rb) for p, q in zip(x, y)) < 1e-9
    assert not any(a.column("alarm").to_pylist())


def _from_motion(table, cols: list[str]) -> list[tuple[float, ...]]:
    """The commanded positions from the first cycle that moves to the last that does."""
    rows = list(zip(*(table.column(c).to_pylist() for c in cols)))
    moving = [i for i in range(1, len(rows)) if rows[i] != rows[i - 1]]
    return rows[moving[0] - 1:moving[-1] + 1]


def test_a_drive_fault_in_the_feedback_equals_stepping(monkeypatch, tmp_path):
    """X's following-error window shrunk: the drive faults mid-program (CiA 402 FAULT in the feedback, the bench's
    alarm): the refill made ahead of that cycle is not taken (the alarm changed the channel), the stop is stepping's.
    (2200 counts, 0.0172 mm: X's following error peaks at 2292 counts in the program's first speed-up to F3000 and
    crosses 2200 at cycle 45, where 2300 tripped before decision motion 83 (c), whose setpoints no longer overshoot
    the feed there: 53.3 mm/s before, a peak of 2486 counts.)"""
    bench = tmp_path / "mill-tight.toml"
    bench.write_text((ROOT / "benches" / "mill-3axis.toml").read_text().replace(
        'name = "X"\n', 'name = "X"\ndrive = { following_error_window = 2200 }\n', 1))
    text = cam_program(300)
    a = _run(monkeypatch, tmp_path, text, "0", bench=str(bench))
    b = _run(monkeypatch, tmp_path, text, "1", bench=str(bench))
    _same(a, b)
    assert b["res"].alarms and not b["res"].run.finished
    assert b["st"].ahead_used > 0
