"""Real-time runs take stretches too (issue 17, decision B21): the planner's samples and the drive models of
a stretch are computed ahead, in the period's slack, and each period's cycle only takes its share, with its
own tick (pacing, overrun check, timing). On a fake monotonic clock a `--realtime` run is deterministic, so
the run with stretches (DELTAHIL_STRETCH=1) and without (0) must give the same trace in every column,
`period` and `late` included, the same alarms, end record and final positions."""

from __future__ import annotations

import io

import pyarrow.parquet as pq
import pytest

import hil.clock
from hil import api
from hil.bench import RealtimeConfig
from hil.clock import Granted, RealTimeClock
from hil.commands.run import print_timing
from hil.stretch import ENV, RT_CYCLES, Stretcher
from hil.stretch_realtime import COLD_CYCLES
from tests.conftest import ROOT

DEMO = str(ROOT / "examples" / "lathe_demo.nc")


class FakeTime:
    """A monotonic clock that advances 1 µs per read and by what is slept (woken 30 µs late)."""

    def __init__(self) -> None:
        self.t = 1_000_000_000
        self.on_sleep = None  # called on every sleep (a signal arriving while the pacer waits)

    def now(self) -> int:
        self.t += 1_000
        return self.t

    def sleep(self, s: float) -> None:
        self.t += int(round(s * 1e6)) * 1_000 + 30_000
        if self.on_sleep is not None:
            self.on_sleep()


class StopAt:
    """A trace column that asks for a stop in cycle `at`, as a SIGINT's handler does between two cycles."""

    columns = ["stop_asked"]

    def __init__(self, at: int) -> None:
        self.at = at

    def values(self, runner):
        if runner.cycle == self.at:
            runner.request_stop("SIGINT")
        return [float(runner.stop_request is not None)]


def fake_clock(monkeypatch) -> tuple[FakeTime, list[RealTimeClock]]:
    """Real-time runs from now on paced by a `FakeTime` (deterministic), without SCHED_FIFO; the clocks made."""
    ft = FakeTime()
    clocks: list[RealTimeClock] = []

    def make_clock(cycle, realtime, config=None):
        assert realtime
        clk = RealTimeClock(cycle, RealtimeConfig(busy_wait=100e-6, lock_memory=False), now_ns=ft.now,
                            sleep=ft.sleep)
        clocks.append(clk)
        return clk

    monkeypatch.setattr(hil.clock, "make_clock", make_clock)
    monkeypatch.setattr(hil.clock, "acquire_realtime", lambda config, owner: Granted())  # no SCHED_FIFO in tests
    return ft, clocks


def _run(monkeypatch, tmp_path, on: str, stop_at: int | None = None, signal_at: int | None = None,
         **kw) -> tuple[dict, api.Result]:
    """A real-time run of the lathe demo on a fake clock; `stop_at`: a trace column asks for a stop in that cycle;
    `signal_at`: a SIGINT's stop is asked while the pacer waits for that cycle (ticks counted by the clock)."""
    monkeypatch.setenv(ENV, on)
    ft, clocks = fake_clock(monkeypatch)
    runners: list = []
    from hil.runner import BenchRunner

    real_init = BenchRunner.__init__

    def init(self, *a, **k):
        real_init(self, *a, **k)
        runners.append(self)
        if stop_at is not None and not any(isinstance(src, StopAt) for src in self.trace_sources):
            self.trace_sources.append(StopAt(stop_at))

    monkeypatch.setattr(BenchRunner, "__init__", init)
    if signal_at is not None:
        def on_sleep():
            if clocks[0]._n + 1 == signal_at:
                runners[0].request_stop("SIGINT")

        ft.on_sleep = on_sleep
    path = tmp_path / f"rt{on}.parquet"
    res = api.run(DEMO, trace=str(path), realtime=True, check=False, **kw)
    assert clocks and type(res.runner.clock) is RealTimeClock
    table = pq.read_table(path)
    return {c: table.column(c).to_pylist() for c in table.column_names}, res


def _same(a: tuple, b: tuple) -> None:
    (ca, ra), (cb, rb) = a, b
    assert list(ca) == list(cb)
    for c in ca:
        assert ca[c] == cb[c], f"column {c} differs from row {next(i for i, (x, y) in enumerate(zip(ca[c], cb[c])) if x != y)}"
    assert [x.code_text for x in ra.alarms] == [x.code_text for x in rb.alarms]
    assert ra.run.final == rb.run.final and ra.run.cycles == rb.run.cycles
    assert ra.run.stopped_by == rb.run.stopped_by
    assert ra.run.stretched == 0


@pytest.mark.parametrize("kw", [{}, {"events": ["t=2:feed-hold", "t=2.6:cycle-start", "t=4:set D21002=50"]}],
                         ids=["plain", "hold-resume-override"])
def test_a_realtime_run_with_stretches_equals_stepping(monkeypatch, tmp_path, kw):
    taken = _taken_starts(monkeypatch)  # B22: stretch starts worked out in the slacks of the stretch before, taken
    lengths = _stretch_lengths(monkeypatch)
    rows = _paced_rows(monkeypatch)
    a = _run(monkeypatch, tmp_path, "0", **kw)
    b = _run(monkeypatch, tmp_path, "1", **kw)
    _same(a, b)
    r = b[1].run
    if not kw:  # (--at events are read cycle by cycle: no paced bulk, stretches start as in B21)
        assert len(taken) > 500 and sum(taken) > 0.9 * len(taken)  # most starts were worked out ahead and taken
        assert max(lengths) == RT_CYCLES  # the prepared ones; a cold start takes COLD_CYCLES (B23)
        # B36: a paced cycle's trace row is written in its own slack (after its outputs), not in the bulk part's
        assert len(rows) > 0.8 * r.cycles and all(rows)
    else:
        assert not rows
    assert r.ok and r.realtime and r.overruns == 0
    assert r.stretched > 0.8 * r.cycles  # most cycles come from stretches, each paced on its own
    assert set(a[0]["period"][1:]) == {0.001}  # every cycle ticked: a 1 ms period on the fake clock
    assert r.timing["between"]["count"] == r.cycles - 1  # the work between cycles is measured in every period
    out = io.StringIO()
    print_timing(r, out)  # `hil run --realtime`'s summary: the slack's work beside the cycle work
    lines = {ln[:15].strip(): ln[15:] for ln in out.getvalue().splitlines()}
    b = r.timing["between"]
    assert lines["between cycles"] == "  ".join(f"{k} {b[k] * 1e6:.1f} µs" for k in ("p50", "p99", "max"))
    assert "cycle work" in lines and b["max"] > 0


def test_stretches_are_the_default_in_real_time_too(monkeypatch):
    """B37: without DELTAHIL_STRETCH a real-time run takes stretches as a lock-step one does; `0` steps every cycle
    in both, `ahead` (B31) steps every cycle in real time with its refill and exchange ahead."""
    from hil.stretch import ahead_wanted, wanted

    monkeypatch.delenv(ENV, raising=False)
    assert wanted(realtime=True) and wanted(realtime=False) and not ahead_wanted()
    for value, rt, lockstep, ahead in (("0", False, False, False), ("1", True, True, False),
                                       ("ahead", False, True, True)):
        monkeypatch.setenv(ENV, value)
        assert (wanted(realtime=True), wanted(realtime=False), ahead_wanted()) == (rt, lockstep, ahead)


def test_starts_worked_out_ahead_and_dropped_leave_the_run_as_stepping(monkeypatch, tmp_path):
    """B22: every start worked out in the slacks before it is dropped (as when what it read changed): the planner
    and the drives were left as found (the filter's share zones too, which sampling pops), so the run still
    equals stepping. Failed before the zones were saved with the planner: Z_cmd from cycle 1161 on."""
    monkeypatch.setattr(Stretcher, "_same", lambda self, *args: False)
    lengths = _stretch_lengths(monkeypatch)
    a = _run(monkeypatch, tmp_path, "0")
    b = _run(monkeypatch, tmp_path, "1")
    _same(a, b)
    assert b[1].run.stretched > 0.8 * b[1].run.cycles
    # B23: a start nothing prepared works out only COLD_CYCLES cycles in its slack (here: every start)
    assert max(lengths) == COLD_CYCLES and sum(lengths) == b[1].run.stretched


def test_the_slack_budget_bounds_the_parts_of_the_next_start_a_slack_takes(monkeypatch, tmp_path):
    """B33: a paced slack takes one part of the next start, and more while SLACK_BUDGET_NS has not gone since its
    outputs were written. On the fake clock (1 µs a read) a budget of 0 leaves one part a slack (B22), so a cold
    start's COLD_CYCLES (4) stretch has too few slacks for the 4-5 parts and most of them are not prepared; the
    default budget prepares them. Both runs equal stepping in every column."""
    import hil.stretch_realtime

    a = _run(monkeypatch, tmp_path, "0")
    runs = {}
    for budget in (0, hil.stretch_realtime.SLACK_BUDGET_NS):
        monkeypatch.setattr(hil.stretch_realtime, "SLACK_BUDGET_NS", budget)
        taken = _taken_starts(monkeypatch)
        lengths = _stretch_lengths(monkeypatch)
        b = _run(monkeypatch, tmp_path, "1")
        _same(a, b)
        runs[budget] = (sum(taken), lengths.count(COLD_CYCLES), len(lengths))
    (one_part, cold_one, n_one), (budgeted, cold, n) = runs.values()
    assert COLD_CYCLES == 4 and budgeted > 0.9 * n  # nearly every start prepared in the slacks before it
    assert cold_one > 2 * cold and one_part < budgeted  # one part a slack: after a cold start the next is cold too


def _taken_starts(monkeypatch) -> list[bool]:
    """Each start that found one worked out ahead (B22): True where it took it (filled as the runs go)."""
    taken: list[bool] = []
    spec_start = Stretcher._spec_start

    def spy(self, *args):
        had = self._taken is not None
        started = spec_start(self, *args)
        if had:
            taken.append(started is not None)
        return started

    monkeypatch.setattr(Stretcher, "_spec_start", spy)
    return taken


def _paced_rows(monkeypatch) -> list[bool]:
    """Each trace row a paced cycle wrote itself (B36): True where its outputs were written before it (filled as
    the runs go)."""
    rows: list[bool] = []
    paced_rows = Stretcher._paced_rows

    def spy(self, r, *args):
        row = paced_rows(self, r, *args)
        if row is None:
            return None

        def counted(c, timing):
            rows.append(r.clock._written)
            row(c, timing)

        return counted

    monkeypatch.setattr(Stretcher, "_paced_rows", spy)
    return rows


def _stretch_lengths(monkeypatch) -> list[int]:
    """The cycles of each stretch Stretcher.run takes (filled as the runs go)."""
    lengths: list[int] = []
    run = Stretcher.run

    def spy(self, limit):
        c0 = self.cycles
        started = run(self, limit)
        if started:
            lengths.append(self.cycles - c0)
        return started

    monkeypatch.setattr(Stretcher, "run", spy)
    return lengths


def _made_stretchers(monkeypatch) -> list[Stretcher]:
    """Each Stretcher the runs make (filled as the runs go)."""
    made: list[Stretcher] = []
    init = Stretcher.__init__

    def spy(self, *args):
        init(self, *args)
        made.append(self)

    monkeypatch.setattr(Stretcher, "__init__", spy)
    return made


def test_a_stop_inside_a_stretch_is_taken_at_the_next_cycle(monkeypatch, tmp_path):
    a = _run(monkeypatch, tmp_path, "0", stop_at=5000)
    b = _run(monkeypatch, tmp_path, "1", stop_at=5000)
    _same(a, b)
    cols, res = b
    assert res.run.stopped_by == "SIGINT" and not res.run.finished
    assert cols["stop_asked"].index(1.0) == 4999  # asked in cycle 5000; its stop starts in cycle 5001 both ways


@pytest.mark.parametrize("at", [3000, 3001, 5000])
def test_a_signal_while_a_stretch_is_paced_lands_on_the_same_cycle(monkeypatch, tmp_path, at):
    """The plain run's stretches are paced with only their outputs per cycle (the rest at once after their last
    cycle): a SIGINT while the pacer waits for a cycle ends the stretch after that cycle, as stepping does.
    Cycles 3000 and 5000 are the last paced cycle of their stretches (one cycle late before the fix), 3001 is not."""
    a = _run(monkeypatch, tmp_path, "0", signal_at=at)
    b = _run(monkeypatch, tmp_path, "1", signal_at=at)
    _same(a, b)
    r = b[1].run
    assert r.stopped_by == "SIGINT" and not r.finished and r.stretched > 0.9 * at
    assert b[1].runner.trace is not None


def test_a_signal_after_a_paced_stretch_counted_its_cycles_lands_on_the_same_cycle(monkeypatch, tmp_path):
    """B36: the runner's counters of a paced stretch's cycles (time, cycle, rest counters, the largest following
    error ...) are counted in the slack before the bulk part's, for the cycles paced so far, and the bulk part counts
    the rest. A SIGINT while the pacer waits for the next cycle (after that count) or for the cycle before the
    counted one (before it) ends the stretch there: the bulk part then counts none or all of its cycles, and both
    runs equal stepping in every column."""
    import hil.stretch

    ticks: list[int] = []  # the clock's tick (cycle) in whose slack each count ran
    count_cycles = hil.stretch.count_cycles

    def spy(r, outs, k0, m):
        ticks.append(r.clock._n)
        return count_cycles(r, outs, k0, m)

    monkeypatch.setattr(hil.stretch, "count_cycles", spy)
    _run(monkeypatch, tmp_path, "1")
    assert len(ticks) > 500
    at = ticks[len(ticks) // 3]
    for signal_at, counted in ((at + 1, True), (at - 1, False)):
        del ticks[:]
        a = _run(monkeypatch, tmp_path, "0", signal_at=signal_at)
        b = _run(monkeypatch, tmp_path, "1", signal_at=signal_at)
        _same(a, b)
        assert b[1].run.stopped_by == "SIGINT" and not b[1].run.finished and (at in ticks) == counted


@pytest.mark.parametrize("kw", [{}, {"events": ["t=2:feed-hold", "t=2.6:cycle-start", "t=4:set D21002=50"]}],
                         ids=["plain", "hold-resume-override"])
def test_stepping_with_its_refill_and_exchange_ahead_equals_stepping(monkeypatch, tmp_path, kw):
    """Session 11, route (a): every cycle stepped, but the planner refill a cycle will make (`Stretcher.ahead`) and
    its in-process bus exchange (`BenchRunner._bus_ahead`) worked out in the slack before its tick
    (DELTAHIL_STRETCH=ahead): the same trace as plain stepping in every column, with the refills ahead taken."""
    made = _made_stretchers(monkeypatch)
    a = _run(monkeypatch, tmp_path, "0", **kw)
    assert not made  # plain stepping: no stretcher, nothing ahead
    b = _run(monkeypatch, tmp_path, "ahead", **kw)
    _same(a, b)
    r = b[1].run
    assert r.ok and r.stretched == 0 and b[1].runner._bus_ahead
    assert len(made) == 1 and made[0].stretches == 0 and made[0].ahead_used > 100  # the lathe demo's refills


@pytest.mark.parametrize("on", ["ahead", "1"])
def test_work_ahead_skipped_after_a_long_cycle_leaves_the_run_as_stepping(monkeypatch, tmp_path, on):
    """B34: a stepped cycle's work ahead (its refill, `Stretcher.ahead`, and its in-process bus exchange) is skipped
    when the cycle before it worked longer than AHEAD_WORK_NS (or too little of the period is left); that cycle then
    refills and exchanges itself after its tick. With a threshold of 0 it fires before every stepped cycle (the fake
    clock reads 1 µs a read, so every cycle works > 0): no refill is taken ahead, no exchange runs before its tick,
    and the run still equals stepping in every column; with the default thresholds the fake clock's short cycles
    skip nothing."""
    import hil.stretch_realtime
    from hil.runner import BenchRunner

    made = _made_stretchers(monkeypatch)
    before: list[bool] = []  # per exchange: may it run before its tick (False: the loop skipped it, B34)?
    exchange = BenchRunner._exchange

    def spy_exchange(self, step=None, bus_ahead=True):
        before.append(bus_ahead)
        return exchange(self, step, bus_ahead)

    monkeypatch.setattr(BenchRunner, "_exchange", spy_exchange)
    a = _run(monkeypatch, tmp_path, "0")
    default = _run(monkeypatch, tmp_path, on)
    _same(a, default)
    on_default = made[-1]
    assert on_default.aheads_skipped == 0 and on_default.ahead_used > (100 if on == "ahead" else 10)
    assert all(before)
    del before[:]
    monkeypatch.setattr(hil.stretch_realtime, "AHEAD_WORK_NS", 0)
    b = _run(monkeypatch, tmp_path, on)
    _same(a, b)
    st = made[-1]
    assert st.ahead_used == 0 and st.aheads_skipped >= on_default.ahead_used  # each refill taken ahead before
    assert before.count(False) == st.aheads_skipped  # the skipped cycles exchanged after their tick
    assert b[1].runner._bus_ahead and b[1].run.ok and b[1].run.overruns == 0


def test_a_start_nothing_prepared_needs_time_left_in_the_period(monkeypatch, tmp_path):
    """B35: a start nothing prepared (its samples and drive models in this slack) is taken only while COLD_LEFT_NS of
    the period is left, else the cycle steps. Above the period it never is: every start is refused (the first ones
    are cold, and only stretches prepare the next), the run is stepped and equals stepping in every column."""
    import hil.stretch_realtime

    made = _made_stretchers(monkeypatch)
    a = _run(monkeypatch, tmp_path, "0")
    b = _run(monkeypatch, tmp_path, "1")
    assert made[-1].colds_skipped == 0 and b[1].run.stretched > 0.8 * b[1].run.cycles  # the fake clock's slack
    assert made[-1].starts_skipped == 0  # (B36's guard neither)
    monkeypatch.setattr(hil.stretch_realtime, "COLD_LEFT_NS", 2_000_000)
    b = _run(monkeypatch, tmp_path, "1")
    _same(a, b)
    assert made[-1].colds_skipped > 1000 and b[1].run.stretched == 0 and b[1].run.ok


def test_no_start_is_tried_near_the_next_tick(monkeypatch, tmp_path):
    """B36: no stretch start, prepared or not, is tried while less than START_LEFT_NS of the period is left; the
    cycle steps. On the fake clock's short cycles the default skips none; above the period every start is skipped
    before its checks (no cold start is even refused), and the run equals stepping in every column."""
    import hil.stretch_realtime

    made = _made_stretchers(monkeypatch)
    a = _run(monkeypatch, tmp_path, "0")
    monkeypatch.setattr(hil.stretch_realtime, "START_LEFT_NS", 2_000_000)
    b = _run(monkeypatch, tmp_path, "1")
    _same(a, b)
    st = made[-1]
    assert st.starts_skipped > 10_000 and st.colds_skipped == 0 and st.specs_used == 0
    assert b[1].run.stretched == 0 and b[1].run.ok


def test_the_settle_after_the_program_takes_stretches_and_ends_on_the_same_cycle(monkeypatch, tmp_path):
    """B38: after the program the runner cycles until the axes stand (BenchRunner._settle); those cycles take
    stretches too (standing samples, the drives settling), each ending after the first cycle every axis is at
    rest, so the settle ends on the cycle stepping ends it and the trace equals stepping's in every column."""
    from hil.runner import BenchRunner

    stepped: dict[str, int] = {}
    settle, exchange = BenchRunner._settle, BenchRunner._exchange
    flag = [None]
    ends: list[int] = []

    def spy_settle(self):
        flag[0] = self
        c0 = self.cycle
        try:
            settle(self)
        finally:
            flag[0] = None
        n, _ = stepped.get(self._run_mode, (0, 0))
        stepped[self._run_mode] = (n, self.cycle - c0)
        ends.append(self.cycle)

    def spy_exchange(self, *a, **k):
        if flag[0] is self:
            n, c = stepped.get(self._run_mode, (0, 0))
            stepped[self._run_mode] = (n + 1, c)
        return exchange(self, *a, **k)

    monkeypatch.setattr(BenchRunner, "_settle", spy_settle)
    monkeypatch.setattr(BenchRunner, "_exchange", spy_exchange)
    for mode in ("0", "1"):
        monkeypatch.setattr(BenchRunner, "_run_mode", mode, raising=False)
        if mode == "0":
            a = _run(monkeypatch, tmp_path, mode)
        else:
            b = _run(monkeypatch, tmp_path, mode)
    _same(a, b)
    (steps_0, cycles_0), (steps_1, cycles_1) = stepped["0"], stepped["1"]
    assert cycles_0 == cycles_1 > 20 and steps_0 == cycles_0  # the same settle, every cycle stepped without
    assert steps_1 <= 2  # with stretches: at most a cold start's refusal (B35) stepped
    # the settle ended where the axes stood: their feedback unchanged in its last rows, no following error left
    assert ends[0] == ends[1]
    end = b[0]["cycle"].index(ends[1])
    for axis in ("X", "Z"):
        assert len(set(b[0][f"{axis}_act"][end - 2:end + 1])) == 1 and b[0][f"{axis}_ferr"][end] == 0.0
