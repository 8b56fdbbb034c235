"""DC drift monitoring: a drive whose clock runs away from the reference (the slaves' DC model,
0x092C system time difference) stops the run with 0x141F on its axis once the drift passes the
bench's limit (docs/decisions/ethercat.md E8). Needs root (veth pair)."""

from __future__ import annotations

import pytest

from fieldbus.ethercat.link import EthercatLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from nc.program import parse_program
from tests.fault_helpers import Recorder, assert_stopped_after_alarm
from virtual_bus.ethercat.faults import parse_fault
from virtual_bus.ethercat.veth import SimProcess, can_create

REASON = can_create()
needs_veth = pytest.mark.skipif(REASON is not None, reason=REASON or "")

PROGRAM = "G21 G18 G98\nS500 M03\nG01 X80. Z50. F3000\nG01 X100. Z80. F3000\nM30\n"


def run(*faults: str, limit: float = 50_000):
    bench = default_lathe()
    bench.params.update(ethercat_drift_limit_ns=limit, ethercat_drift_check_every=10)
    with SimProcess(*(f"--fault={f}" for f in faults), tag="d") as sim:
        link = EthercatLink.for_bench(bench, sim.iface)
        rec = Recorder()
        result = BenchRunner(bench, link, on_cycle=rec).run_program(parse_program(PROGRAM, name="drift.nc"))
    run.recorder = rec  # type: ignore[attr-defined]
    return result, link


def test_drift_limit_and_check_interval_come_from_the_bench_params():
    bench = default_lathe()
    bench.params.update(ethercat_drift_limit_ns=20_000.0, ethercat_drift_check_every=5.0)
    link = EthercatLink.for_bench(bench, "ecX")
    assert (link.drift_limit_ns, link.drift_check_every) == (20_000, 5)
    assert parse_fault("drift:1@300:20000").arg == 20_000 and parse_fault("drift:1@300:1").active(10_000)


@needs_veth
def test_synchronised_clocks_stay_under_the_limit_and_the_run_completes():
    result, link = run()
    assert result.ok, result.alarms
    assert link.stats.max_drift_ns < 50_000


@needs_veth
def test_runaway_clock_on_z_raises_0x141f_on_z_before_the_program_ends():
    result, link = run("drift:1@400:20000")  # Z's clock gains 20 µs a frame; its loop trims 5 µs
    a = result.alarms[0]
    assert not result.finished
    assert a.code == 0x141F and a.axis == "Z" and a.info > 50_000
    assert "DC drift" in a.message and link.stats.max_drift_ns > 50_000
    assert_stopped_after_alarm(run.recorder, result)


@needs_veth
def test_a_limit_of_zero_only_records_the_drift():
    result, link = run("drift:1@400:20000", limit=0)
    assert result.ok and link.stats.max_drift_ns > 50_000
