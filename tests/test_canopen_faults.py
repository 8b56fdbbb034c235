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
from tests.fault_helpers import Recorder, assert_stopped_after_alarm
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
    rec = Recorder(chain=lambda r: (pull_cable(r), seen.append((r.cycle, len(r.result.alarms)))))
    runner.on_cycle = rec
    result = runner.run_program(parse_program(PROGRAM, name="move.nc"))
    assert_stopped_after_alarm(rec, result, lost=("Z",))  # X brakes along the path; Z's feedback is gone

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
    rec = Recorder(chain=estop)
    result = BenchRunner(bench, link, on_cycle=rec).run_program(parse_program(PROGRAM, name="move.nc"))
    assert_stopped_after_alarm(rec, result)  # X on its fault reaction, Z along the path

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
            sdo[0x1600][1].raw = 0x60400010  # the PDO is valid: its mapping cannot change (CiA 301)
        assert exc.value.code == 0x06010000
        sdo[0x1400][1].raw = sdo[0x1400][1].raw | 0x80000000  # invalidate the RPDO, then clear sub 0
        sdo[0x1600][0].raw = 0
        with pytest.raises(SdoAbortedError) as exc:
            sdo[0x1600][1].raw = 0x60650020  # 0x6065 following error window: not mappable
        assert exc.value.code == 0x06040041
    finally:
        link.close()
    assert nodes["X"].nmt_state == "STOPPED"


# ---- one alarm per drive fault (EMCY and statusword fault bit are two signs of one fault) ------------
def _fault_run(prepare):
    """The move with X faulting (ASDA AL013) at cycle 300; `prepare(nodes)` sets up the drive."""
    def estop(r):
        if r.cycle == 300:
            nodes["X"].drive.external_fault = 0x13

    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    prepare(nodes)
    result = BenchRunner(bench, link, on_cycle=estop).run_program(parse_program(PROGRAM, name="move.nc"))
    assert not result.ok and nodes["X"].drive.state is State.FAULT
    return result, link, nodes


def test_emcy_first_one_alarm_with_the_emcy_code():
    result, link, nodes = _fault_run(lambda nodes: None)
    assert [(a.code, a.axis, a.info) for a in result.alarms] == [(0xF002, "X", 0x13)]
    assert "EMCY 0x5441" in result.alarms[0].message and "AL013" in result.alarms[0].message
    (name, episode), = link.faults
    assert (name, episode.reported_by, episode.fault_bit_seen) == ("X", "EMCY", True)
    assert [e.code for e in episode.emcys] == [0x5441]


def test_statusword_first_one_alarm_and_the_late_emcy_joins_it():
    def late_emcy(nodes):
        nodes["X"].emcy_delay = 3  # the TPDO with the fault bit arrives 3 cycles before the EMCY

    result, link, nodes = _fault_run(late_emcy)
    assert [(a.code, a.axis, a.info) for a in result.alarms] == [(0xF002, "X", 0x13)]
    assert "drive error code 0x0013" in result.alarms[0].message  # from 0x603F in the TPDO
    assert [(e.code, e.delta_alarm) for e in nodes["X"].emcys_sent] == [(0x5441, 0x13)]  # it did come
    (name, episode), = link.faults
    assert (name, episode.reported_by) == ("X", "statusword")
    assert [e.code for e in episode.emcys] == [0x5441]  # received, raised nothing


def test_emcy_disabled_the_statusword_still_raises_the_alarm():
    def no_emcy(nodes):
        # COB-ID EMCY (0x1014) bit 31: the drive has no valid EMCY (CiA 301); survives NMT reset
        nodes["X"].node.object_dictionary[0x1014].default = 0x80000000 | (0x80 + 1)

    result, link, nodes = _fault_run(no_emcy)
    assert [(a.code, a.axis, a.info) for a in result.alarms] == [(0xF002, "X", 0x13)]
    assert nodes["X"].emcys_sent == []
    assert [(n, e.reported_by, e.emcys) for n, e in link.faults] == [("X", "statusword", [])]


def test_an_episode_lasts_until_the_fault_reset_then_the_next_fault_is_raised_again():
    """Link level, the drives disabled: a second EMCY (another alarm code) of the same fault raises
    nothing; after fault reset (fault bit falls) the next fault is a new alarm."""
    from fieldbus.cia402 import Cia402Master
    from fieldbus.link import BusError
    from fieldbus.pdo import RxPdo

    bench = default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    masters = [Cia402Master() for _ in range(3)]
    rx = [RxPdo(mode=8), RxPdo(mode=8), RxPdo(mode=9)]
    raised = []

    def cycles(n):
        for _ in range(n):
            try:
                tx = link.exchange(rx)
            except BusError as exc:
                raised.append(exc.alarm)
                continue
            for m, r, t in zip(masters, rx, tx):
                r.controlword = m.step(t.statusword)

    link.open()
    try:
        cycles(5)
        z = nodes["Z"].drive
        z.external_fault = 0x09  # AL009 following error
        cycles(5)
        z.external_fault = 0x07  # the drive adds AL007 while still in fault: a second EMCY
        z.error_code = 0x07
        cycles(5)
        assert [(a.axis, a.info) for a in raised] == [("Z", 0x09)]
        assert [e.delta_alarm for e in link.faults[0][1].emcys] == [0x09, 0x07]
        z.external_fault = 0
        masters[1].fault_reset()
        cycles(5)
        assert z.state is State.SWITCH_ON_DISABLED and link._nodes[1].fault is None
        z.external_fault = 0x13  # a new fault: emergency stop input
        cycles(5)
    finally:
        link.close()
    assert [(a.code, a.axis, a.info) for a in raised] == [(0xF002, "Z", 0x09), (0xF002, "Z", 0x13)]
    assert [(n, e.reported_by) for n, e in link.faults] == [("Z", "EMCY"), ("Z", "EMCY")]
