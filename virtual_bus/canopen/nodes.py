"""The simulated drives of one bench on one CAN bus: node IDs 1, 2, … in axis order.

Two ways to run them:
- `attach_lockstep(link, drives)`: in the master's process on python-can's `virtual` bus, pumped
  by the master after each frame it sends (deterministic lock-step, simulated time);
- `serve(drives, interface, channel)`: in their own process on a real python-can interface
  (`socketcan`, or `udp_multicast` inside a network namespace), driven by the master's SYNC in
  real time. This is what `hil sim canopen` runs.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import canopen

from fieldbus.canopen.lockstep import LockstepNetwork
from fieldbus.canopen.objects import ASDA_B3_EDS
from virtual_bus.canopen.master_watch import MasterWatch
from virtual_bus.canopen.node import Cia402Slave
from virtual_bus.drive import Cia402Drive

log = logging.getLogger("virtual_bus.canopen")
WATCH_PERIOD_S = 0.01  # how often a served node looks at its master's heartbeat (and steps a braking drive)


class SlaveBus:
    def __init__(self, drives: Sequence[Cia402Drive], network: canopen.Network, first_id: int = 1,
                 eds: Sequence[str | Path] = ()) -> None:
        """`eds`: each drive's device file (bench `canopen_eds`), the shipped ASDA-B3 EDS where absent."""
        self.network = network
        files = list(eds) + [""] * (len(drives) - len(eds))
        self.slaves = [Cia402Slave(first_id + i, d, str(f or ASDA_B3_EDS)) for i, (d, f) in enumerate(zip(drives, files))]
        self.syncs = 0
        self._lock = threading.Lock()
        self.log: Callable[[str], None] = lambda msg: None  # `hil sim canopen --verbose`
        self._watching: threading.Thread | None = None
        self._closed = threading.Event()
        network.subscribe(0x80, self._on_sync)
        for s in self.slaves:
            s.attach(network)

    def __getitem__(self, name_or_id: str | int) -> Cia402Slave:
        for s in self.slaves:
            if s.node_id == name_or_id or s.drive.name == name_or_id:
                return s
        raise KeyError(name_or_id)

    def _on_sync(self, can_id: int, data: bytes, timestamp: float) -> None:
        with self._lock:
            self.syncs += 1
            for s in self.slaves:
                s.on_sync()
            if isinstance(self.network, LockstepNetwork):
                alive = [s for s in self.slaves if s.alive]
                # Heartbeats run on simulated time: one interpolation period per SYNC.
                self.network.advance(alive[0].interpolation_period if alive else 0.0)

    def watch_master(self, every: float = WATCH_PERIOD_S) -> None:
        """Each drive watches the master's heartbeat (0x1016) from a thread of its own, as a drive's firmware
        does, so a master gone silent is seen without a SYNC (virtual_bus/canopen/master_watch.py, E34)."""
        for s in self.slaves:
            s.watch = MasterWatch(s)
            s.watch.subscribe()

        def loop() -> None:
            while not self._closed.wait(every):
                with self._lock:
                    now = time.monotonic()
                    lines = [(s, m) for s in self.slaves if s.alive and s.watch is not None
                             for m in s.watch.check(now)]
                for s, m in lines:
                    self.log(f"node {s.node_id} ({s.drive.name}): {m}")

        self._watching = threading.Thread(target=loop, name="canopen-master-watch", daemon=True)
        self._watching.start()

    def close(self) -> None:
        self._closed.set()
        for s in self.slaves:
            s.node.nmt.stop_heartbeat()
        self.network.disconnect()


def attach_lockstep(link, drives: Sequence[Cia402Drive]) -> SlaveBus:
    """Put the drives on the link's `virtual` channel and let the link pump them each frame."""
    bus = SlaveBus(drives, LockstepNetwork(link.channel), eds=[c.eds for c in link.nodes_cfg])
    link.peers.append(bus.network.pump)
    link.on_close.append(bus.close)
    return bus


def serve(drives: Sequence[Cia402Drive], interface: str, channel: str, stop: threading.Event | None = None,
          ready: threading.Event | None = None, eds: Sequence[str | Path] = ()) -> SlaveBus:
    """Run the nodes on a real python-can interface until `stop` is set (Ctrl-C in `hil sim`)."""
    network = canopen.Network()
    network.connect(interface=interface, channel=channel)
    bus = SlaveBus(drives, network, eds=eds)
    bus.watch_master()
    log.info("CANopen nodes %s on %s:%s", [s.node_id for s in bus.slaves], interface, channel)
    if ready is not None:
        ready.set()
    if stop is not None:
        try:
            stop.wait()
        finally:
            bus.close()
    return bus
