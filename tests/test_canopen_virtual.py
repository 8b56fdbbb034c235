"""CANopen on python-can's in-process virtual bus, lock-step: the example program end to end,
the configuration the master writes into the drives, and the bus budget."""

from __future__ import annotations

import re

import pytest

from fieldbus.canopen.budget import BusBudgetError, bus_load, frame_bits
from fieldbus.canopen.link import CanopenLink, interpolation_period
from fieldbus.canopen.objects import map_entry, pdo_frames
from fieldbus.link import SimLink
from fieldbus.pdo import ASDA_CSP, ASDA_CSP_CSV, RxPdo
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import load_program, sim_slaves
from virtual_bus.canopen import attach_lockstep
from tests.conftest import ROOT

DEMO = ROOT / "examples" / "lathe_demo.nc"


def test_lathe_demo_over_canopen_virtual_ends_where_simlink_ends(hil, caplog):
    res = hil("run", DEMO, "--bus", "canopen:virtual")
    assert res.code == 0, res.out + res.err
    assert "result         completed" in res.out
    final = dict(re.findall(r"([XZ]) (-?\d+\.\d+)", res.out.split("final machine position")[1].splitlines()[0]))
    bench = default_lathe()
    ref = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle)).run_program(load_program(str(DEMO)))
    assert ref.ok
    # Same drive model, same integers on the wire, same lock-step cycle: the same end, to the printed digit.
    assert final == {a: f"{v:.4f}" for a, v in ref.final.items()}
    assert final == {"X": "50.0000", "Z": "50.0000"}
    # The virtual bus has no bit timing; the budget still says what a 1 Mbit/s wire would need.
    # (a warning on stderr from the `fieldbus.canopen` logger; pytest captures it here)
    assert "175.5 %" in caplog.text and "at least 1.76 ms" in caplog.text


def _lockstep(bench=None):
    bench = bench or default_lathe()
    link = CanopenLink.for_bench(bench, "virtual", "")
    nodes = attach_lockstep(link, sim_slaves(bench))
    return bench, link, nodes


def test_master_configures_pdos_heartbeat_and_interpolation_period_over_sdo():
    bench, link, nodes = _lockstep()
    infos = link.open()
    try:
        assert [(i.name, i.vendor_id, i.layout) for i in infos] == [
            ("X", 0x1DD, "asda-csp"), ("Z", 0x1DD, "asda-csp"), ("S1", 0x1DD, "asda-csp-csv")]
        assert link.found == [1, 2, 3]
        for slave, layout in zip(nodes.slaves, (ASDA_CSP, ASDA_CSP, ASDA_CSP_CSV)):
            value = slave._value
            assert slave.nmt_state == "OPERATIONAL"
            assert (value(0x60C2, 1), value(0x60C2, 2)) == (1, -3)  # 1 ms = 1 × 10^-3 s
            assert value(0x1017, 0) == 20  # heartbeat producer, ms
            for com, mapping, frames, base in ((0x1400, 0x1600, pdo_frames(layout.rx), 0x200),
                                               (0x1800, 0x1A00, pdo_frames(layout.tx), 0x180)):
                for k in range(4):
                    cob = value(com + k, 1)
                    if k < len(frames):
                        assert cob & 0x7FF == base + 0x100 * k + slave.node_id and not cob & 0x80000000
                        assert value(com + k, 2) == 1  # synchronous, every SYNC
                        assert [value(mapping + k, s) for s in range(1, value(mapping + k, 0) + 1)] == \
                            [map_entry(e) for e in frames[k]]
                    else:
                        assert cob & 0x80000000  # unused PDO disabled
        # One SYNC: every node answers with all its TPDOs, the drive advanced one interpolation period.
        tx = link.exchange([RxPdo(mode=8), RxPdo(mode=8), RxPdo(mode=9)])
        assert [s.syncs for s in nodes.slaves] == [1, 1, 1]
        assert tx[0].position_actual == 60 * 256_000 and tx[1].position_actual == 100 * 128_000
        assert tx[2].mode_display == 9
        assert link.tpdo_misses == {"X": 0, "Z": 0, "S1": 0}
    finally:
        link.close()
    assert [s.nmt_state for s in nodes.slaves] == ["STOPPED"] * 3


def test_bus_load_counts_worst_case_frames():
    assert frame_bits(8) == 135 and frame_bits(0) == 55  # 11-bit ID, worst-case stuffing, 3-bit IFS
    three = [ASDA_CSP, ASDA_CSP, ASDA_CSP_CSV]
    load = bus_load(three, 0.001)
    # SYNC + X, Z: 1 RPDO (7 B) + 3 TPDOs (8, 8, 2 B); spindle: 2 RPDOs (8, 5 B) + 4 TPDOs (8, 8, 8, 5 B)
    assert load.frames_per_cycle == 1 + 2 * 4 + 6
    assert load.bits_per_cycle == 55 + 2 * (125 + 135 + 135 + 75) + (135 + 105) + (3 * 135 + 105)
    assert load.load == pytest.approx(1.745)
    assert bus_load(three, 0.004).load == pytest.approx(0.43625)


@pytest.mark.parametrize("cycle_ms, outcome", [(1.0, "refuse"), (2.0, "warn"), (4.0, "ok")])
def test_budget_refuses_over_100_and_warns_over_70_percent_on_a_real_wire(cycle_ms, outcome):
    bench = default_lathe()
    bench.cycle = cycle_ms / 1000
    if outcome == "refuse":
        with pytest.raises(BusBudgetError, match=r"174\.7 % of 1000 kbit/s.*at least 1\.75 ms"):
            CanopenLink.for_bench(bench, "socketcan", "vcan0")
        return
    link = CanopenLink.for_bench(bench, "socketcan", "vcan0")
    assert (link.budget_note is not None) == (outcome == "warn")
    assert link.ip_period == interpolation_period(bench.cycle) == (int(cycle_ms), -3)


def test_over_budget_bench_exits_2_from_hil_run(hil):
    res = hil("run", DEMO, "--bus", "canopen:socketcan:vcan0")
    assert res.code == 2
    assert "exceeds the bus" in res.err and "Traceback" not in res.err


def test_udp_multicast_needs_an_explicit_group_and_a_private_namespace():
    bench = default_lathe()
    bench.cycle = 0.004
    with pytest.raises(ValueError, match="explicit multicast group"):
        CanopenLink.for_bench(bench, "udp_multicast", "")
    with pytest.raises(ValueError, match="loopback-only network namespace"):
        CanopenLink.for_bench(bench, "udp_multicast", "239.74.163.2")  # this test runs in the host namespace
