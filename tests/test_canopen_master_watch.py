"""A served virtual CANopen drive watches its master's heartbeat (0x1016) on its own clock (decision E34): no
heartbeat within the consumer time while it is OPERATIONAL and enabled raises AL180 (EMCY 0x8130 with the Delta
number), and the drive brakes on its fault reaction to standstill with no SYNC to step it. In-process, on
python-can's `virtual` interface: a second network plays the master."""

from __future__ import annotations

import time

import canopen
import pytest

from fieldbus.canopen.emcy import Emcy
from fieldbus.cia402 import State
from hil.bench import default_lathe
from hil.session import sim_slaves
from virtual_bus.canopen.nodes import SlaveBus

MASTER = 0x7F


@pytest.fixture
def line(request):
    channel = f"watch-{request.node.name}"
    nodes_net, master = canopen.Network(), canopen.Network()
    nodes_net.connect(interface="virtual", channel=channel)
    master.connect(interface="virtual", channel=channel)
    bus = SlaveBus(sim_slaves(default_lathe())[:1], nodes_net)
    log: list[str] = []
    bus.log = log.append
    emcys: list[Emcy] = []
    master.subscribe(0x81, lambda cob, data, ts: emcys.append(Emcy.decode(data)))
    x = bus.slaves[0]
    x.node.nmt.state = "OPERATIONAL"
    yield bus, x, master, log, emcys
    bus.close()
    master.disconnect()


def _consume(x, window_ms: int, producer: int = MASTER) -> None:
    """What `hil run` writes at bring-up over SDO (fieldbus/canopen/link.py `_configure`)."""
    x.node.set_data(0x1016, 1, (producer << 16 | window_ms).to_bytes(4, "little"))


def _wait(cond, timeout: float = 3.0) -> bool:
    end = time.monotonic() + timeout
    while not cond() and time.monotonic() < end:
        time.sleep(0.005)
    return cond()


def test_no_master_heartbeat_raises_al180_and_the_drive_brakes_to_standstill(line):
    bus, x, master, log, emcys = line
    _consume(x, 50)
    bus.watch_master(every=0.005)
    d = x.drive
    d.state, d.velocity, d.position = State.OPERATION_ENABLED, 1.0e6, 0.0
    for _ in range(10):  # the master's heartbeat every 20 ms, then it is gone
        master.send_message(0x700 + MASTER, b"\x05")
        time.sleep(0.02)
        assert d.state is State.OPERATION_ENABLED  # watched, and alive
    assert _wait(lambda: d.state is State.FAULT)
    assert d.error_code == 0x0180 and abs(d.velocity) < 1.0
    decel = d.params.quick_stop_decel  # braked on the quick-stop ramp: v²/2a (the position was frozen before)
    assert abs(d.position - 1.0e6 ** 2 / (2 * decel)) < 1.0e6 * x.interpolation_period
    assert _wait(lambda: emcys) and emcys[0].code == 0x8130 and emcys[0].delta_alarm == 0x0180
    assert log[0] == "node 1 (X): watching the heartbeat of node 127 (consumer time 50 ms)"
    assert "node 1 (X): no heartbeat from node 127 for 50 ms: AL180 (heartbeat event), EMCY 0x8130" in log
    assert any(m.startswith("node 1 (X): drive braked from 1000000 counts/s to standstill in 0.005 s") for m in log)


def test_without_a_consumer_time_or_a_first_heartbeat_nothing_is_watched(line):
    bus, x, master, log, _ = line
    bus.watch_master(every=0.005)
    d = x.drive
    d.state, d.velocity = State.OPERATION_ENABLED, 1.0e6
    master.send_message(0x700 + MASTER, b"\x05")  # 0x1016 not set: a master that asks for no watch
    time.sleep(0.1)
    _consume(x, 50)  # set, but no heartbeat came since: not armed (CiA 301)
    time.sleep(0.1)
    assert d.state is State.OPERATION_ENABLED and not log


def test_a_master_that_stops_the_node_first_is_not_lost(line):
    """`hil run`'s orderly end: NMT stop, then no more heartbeats; a drive no longer OPERATIONAL stays as it is."""
    bus, x, master, log, emcys = line
    _consume(x, 50)
    bus.watch_master(every=0.005)
    d = x.drive
    d.state = State.OPERATION_ENABLED
    master.send_message(0x700 + MASTER, b"\x05")
    assert _wait(lambda: log)
    x.node.nmt.state = "STOPPED"
    time.sleep(0.15)
    assert d.state is State.OPERATION_ENABLED and not emcys and len(log) == 1


def _master_side(channel: str, reject: int | None):
    """A drive node on `channel` (refusing 0x1016:1 with `reject`), and the link's view of it as a master."""
    from fieldbus.canopen.link import CanopenLink
    from fieldbus.canopen.nodes import Node, NodeConfig
    from fieldbus.pdo import ASDA_CSP
    from virtual_bus.canopen.node import Cia402Slave

    slave_net, net = canopen.Network(), canopen.Network()
    slave_net.connect(interface="virtual", channel=channel)
    net.connect(interface="virtual", channel=channel)
    slave = Cia402Slave(1, sim_slaves(default_lathe())[0],
                        reject_writes={(0x1016, 1): reject} if reject is not None else None)
    slave.attach(slave_net)
    cfg = NodeConfig(1, "X", ASDA_CSP)
    node = Node(cfg, net.add_node(1, str(cfg.eds)), [], [])
    link = CanopenLink([cfg], "virtual", channel)
    return slave, node, link, (slave_net, net)


def test_the_master_sets_the_drives_consumer_time_and_a_refusal_only_warns(caplog):
    """`hil run` on a real transport writes 0x1016:1 = 127 << 16 | 2.5 heartbeat periods (E34); a drive that
    refuses it is run anyway, with a warning that it will not stop by itself."""
    for reject, channel in ((None, "mw-ok"), (0x06090030, "mw-refused")):
        slave, node, link, nets = _master_side(channel, reject)
        try:
            link._watch_master(node)
        finally:
            for n in nets:
                n.disconnect()
        if reject is None:
            assert slave._value(0x1016, 1) == 0x7F << 16 | 50  # a virtual link's heartbeat: 20 ms, × 2.5
        else:
            assert slave._value(0x1016, 1) == 0
            assert "refused the master's heartbeat to watch (0x1016:1, SDO abort 0x06090030" in caplog.text
            assert "it will not stop by itself if this master dies" in caplog.text
