"""Real time is asked for before the bus is opened (decisions E23).

`--realtime` asks for SCHED_FIFO, the CPU and mlockall; mlockall alone takes ≈ 0.1 s on a process of this size.
Asked after the bus is in OP, the first cycle's process data came that much later, and an EtherCAT slave whose
SM watchdog is 100 ms (an ESC's default, and the virtual slaves') dropped to SAFE-OP+ERR with AL status 0x001B:
`hil run … --bus ethercat:… --realtime` stopped at cycle 5. Here the pacer runs on a fake monotonic clock and
the request for real time costs 110 ms of it; the bus's watchdog is a check on that clock."""

from __future__ import annotations

import pytest

import hil.clock
import hil.placement  # noqa: F401  (bound to the real acquire_realtime before the tests below patch it)
from hil.bench import RealtimeConfig, default_lathe
from hil.clock import Granted, RealTimeClock
from hil.runner import BenchRunner
from hil.session import make_link
from nc.program import parse_program
from tests.test_realtime_stretch import FakeTime

WATCHDOG_NS = 100_000_000  # an ESC's process-data watchdog: 1000 ticks of 100 µs
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nX30.\nM30\n"


def _paced_run(monkeypatch, cost_ns: int):
    ft = FakeTime()
    asked: list[int] = []

    def acquire(config, owner):
        ft.t += cost_ns  # what mlockall and the scheduler take
        asked.append(ft.t)
        return Granted(sched="SCHED_FIFO", priority=config.priority, memory_locked=True)

    monkeypatch.setattr(hil.clock, "acquire_realtime", acquire)
    bench = default_lathe()
    link = make_link(bench)
    seen: dict[str, int] = {}
    gaps: list[int] = []
    real_open, real_exchange = link.open, link.exchange

    def open_():
        real_open()
        seen["op"] = seen["last"] = ft.t  # the slaves are in OP from here: their watchdog runs

    def exchange(rx):
        gaps.append(ft.t - seen["last"])
        seen["last"] = ft.t
        return real_exchange(rx)

    monkeypatch.setattr(link, "open", open_)
    monkeypatch.setattr(link, "exchange", exchange)
    clock = RealTimeClock(bench.cycle, RealtimeConfig(busy_wait=100e-6, lock_memory=False), now_ns=ft.now,
                          sleep=ft.sleep)
    runner = BenchRunner(bench, link, None, clock=clock)
    result = runner.run_program(parse_program(PROGRAM, name="p.nc"))
    return result, asked, seen, gaps, runner


def test_real_time_is_granted_before_the_bus_is_in_op(monkeypatch):
    result, asked, seen, gaps, runner = _paced_run(monkeypatch, cost_ns=110_000_000)
    assert result.ok, result.alarms
    assert len(asked) == 1 and asked[0] <= seen["op"]  # asked once, before the open
    assert gaps and gaps[0] < WATCHDOG_NS  # OP → first process data within the watchdog
    assert result.granted.startswith("SCHED_FIFO prio 80")


@pytest.mark.parametrize("twice", [False, True])
def test_start_without_prepare_still_asks_once(monkeypatch, twice):
    """A clock started without `prepare` (a caller of its own) asks for real time at start, and only once; stop
    gives it back, so a clock started again asks again."""
    calls: list[str] = []
    monkeypatch.setattr(hil.clock, "acquire_realtime", lambda config, owner: calls.append("acquire") or Granted())
    monkeypatch.setattr(hil.clock, "release_realtime", lambda owner: calls.append("release"))
    ft = FakeTime()
    clk = RealTimeClock(0.001, RealtimeConfig(lock_memory=False), now_ns=ft.now, sleep=ft.sleep)
    if twice:
        clk.prepare()
    clk.start()
    clk.stop()
    clk.start()
    clk.stop()
    assert calls == ["acquire", "release", "acquire", "release"]
