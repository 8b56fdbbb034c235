"""CANopen bus faults each raise their Delta alarm and stop the bench in a controlled way:
node loss (heartbeat consumer timeout), an EMCY from a faulted drive, and SDO aborts while the
master configures the drives. All in lock-step on the virtual bus, timed in simulated cycles."""

from __future__ import annotations

import pytest

from fieldbus.canopen.link import CanopenLink
from fieldbus.cia402 import State
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program
from virtual_bus.canopen import attach_lockstep

# 0.8 s of motion on both axes (Z 200 mm at 1000 mm/min ... plenty of time to fault mid-move)
PROGRAM = "G21 G18 G98\nG01 X40. Z-100. F1000\nM30\n"


def _bench_run(on_cycle=None, prepare=None):
    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    if prepare:
        prepare(nodes)
    runner = BenchRunner(bench, link, on_cycle=on_cycle)
    result = runner.run_program(parse_program(PROGRAM, name="move.nc"))
    return runner, link, nodes, result


def test_node_loss_is_found_by_heartbeat_timeout_and_stops_the_rest():
    lost_at = []

    def pull_cable(r):
        if r.cycle == 300:
            nodes["Z"].power_off()
            lost_at.append(r.cycle)

    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    runner = BenchRunner(bench, link, on_cycle=pull_cable)
    seen = []
    runner.on_cycle = lambda r: (pull_cable(r), seen.append((r.cycle, len(r.result.alarms))))
    result = runner.run_program(parse_program(PROGRAM, name="move.nc"))

    assert not result.ok and lost_at == [300]
    alarm = result.alarms[0]
    assert (alarm.code, alarm.axis, alarm.info) == (0x0601, "Z", None)
    assert "heartbeat of node 2 (Z) lost" in alarm.message
    # Detected after the consumer time (50 ms) and no later than one producer period (20 ms) more.
    first_alarm_cycle = next(c for c, n in seen if n)
    assert 300 + 50 <= first_alarm_cycle <= 300 + 50 + 20 + 1
    # Controlled stop: the others were disabled by the master, the lost node was not served any more.
    x, s1 = nodes["X"].drive, nodes["S1"].drive
    assert x.state in (State.SWITCH_ON_DISABLED, State.READY_TO_SWITCH_ON)
    assert s1.state in (State.SWITCH_ON_DISABLED, State.READY_TO_SWITCH_ON)
    assert link.infos[1].state == "LOST"
    assert len([a for a in result.alarms if a.code == 0x0601]) == 1  # raised once, not every cycle


def test_emcy_from_a_faulted_drive_raises_the_delta_servo_alarm():
    def estop(r):
        if r.cycle == 300:
            nodes["X"].drive.external_fault = 0x13  # ASDA AL013: emergency stop input

    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    result = BenchRunner(bench, link, on_cycle=estop).run_program(parse_program(PROGRAM, name="move.nc"))

    assert not result.ok
    first = result.alarms[0]
    assert (first.code, first.axis, first.info) == (0xF002, "X", 0x13)
    assert "EMCY 0x5441" in first.message and "node 1 (X)" in first.message
    sent = nodes["X"].emcys_sent
    assert [(e.code, e.delta_alarm) for e in sent] == [(0x5441, 0x13)]
    # The faulted drive ramps down by itself; the master disables the others.
    assert nodes["X"].drive.state is State.FAULT
    assert nodes["Z"].drive.state in (State.SWITCH_ON_DISABLED, State.READY_TO_SWITCH_ON)


@pytest.mark.parametrize("obj, abort, alarm", [
    ((0x60C2, 1), 0x06090030, 0x141F),  # interpolation time not supported by the servo
    ((0x1A01, 1), 0x06040041, 0x141E),  # object cannot be mapped: PDO mapping mismatch
    ((0x1017, 0), 0x08000020, 0x1420),  # data cannot be stored: communication establish failed
])
def test_sdo_abort_during_configuration_raises_its_alarm_before_anything_moves(obj, abort, alarm):
    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    nodes["Z"].reject_writes[obj] = abort
    result = BenchRunner(bench, link).run_program(parse_program(PROGRAM, name="move.nc"))
    assert not result.ok
    a = result.alarms[0]
    assert (a.code, a.axis, a.info) == (alarm, "Z", None)
    assert f"SDO abort 0x{abort:08X}" in a.message and f"0x{obj[0]:04X}" in a.message
    assert result.enable_cycles == 0
    # Nothing was enabled, nothing moved.
    assert all(s.drive.state is State.SWITCH_ON_DISABLED for s in nodes.slaves)
    assert nodes["X"].drive.position == 60 * 256_000 and nodes["Z"].drive.position == 100 * 128_000


def test_a_drive_that_cannot_map_an_object_aborts_the_mapping_write():
    """Not injected: the simulated firmware refuses to map an object that is not PDO-mappable."""
    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    link.open()
    try:
        sdo = link.network[1].sdo
        from canopen.sdo.exceptions import SdoAbortedError

        with pytest.raises(SdoAbortedError) as exc:
            sdo[0x1600][1].raw = 0x60650020  # 0x6065 following error window: not mappable
        assert exc.value.code == 0x06040041
    finally:
        link.close()
    assert nodes["X"].nmt_state == "STOPPED"
