"""`CanopenLink`: the bench's bus link over CANopen (CiA 301 + CiA 402), on python-canopen.

open():  node scan → NMT reset communication → boot-ups → identity and device type over SDO →
         heartbeat producer (0x1017), interpolation time period (0x60C2) and the RPDO/TPDO
         communication and mapping records (0x1400/0x1600, 0x1800/0x1A00) written over SDO →
         NMT operational.
exchange(): RPDOs out, one SYNC, the TPDOs every node sends on that SYNC in; heartbeat consumer,
         NMT state watch and EMCYs checked after each cycle, faults raised as `BusError`.

Interfaces: `virtual` (in-process, lock-step: delivery is pumped, time is simulated, nothing
sleeps), and any python-can interface in real time (`socketcan` on benches, `udp_multicast`
between processes in tests). The same code configures and runs all of them.

Why one file of ~500 lines: the node bring-up over SDO, the SYNC exchange and the heartbeat/NMT/EMCY
watch share the nodes' state and python-canopen's network object; the node records live in nodes.py.
"""

from __future__ import annotations

import itertools
import logging
import threading
import time
from time import perf_counter_ns
from collections.abc import Callable, Sequence
from typing import Any

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from fieldbus.canopen.budget import DEFAULT_BITRATE, BusLoad, bus_load, check_budget
from fieldbus.canopen.emcy import ALARM_COMMUNICATION, ALARM_PDO_MAPPING, Emcy
from fieldbus.canopen.lockstep import LockstepNetwork
from fieldbus.canopen.netns import check_multicast_allowed
from fieldbus.canopen.nodes import (FaultEpisode, IoNode, IoNodeConfig, Node, NodeConfig, fault_episodes,
                                    interpolation_period)
from fieldbus.canopen.objects import ASDA_B3_EDS, DIO_EDS, MAX_PDOS, frame_layouts
from fieldbus.link import BusError, SlaveInfo
from fieldbus.pdo import ASDA_CSP, ASDA_CSP_CSV, PdoLayout, RxPdo, TxPdo, copy_tx
from nc.alarms import Alarm

log = logging.getLogger("fieldbus.canopen")

ALARM_NOT_FOUND = 0x142B  # fieldbus slave devices not found
ALARM_ESTABLISH = 0x1420  # fieldbus communication establish failed
ALARM_INTERPOLATION = 0x141F  # the servo does not support the interpolation time

NMT_BOOTUP, NMT_STOPPED, NMT_OPERATIONAL, NMT_PREOP = 0, 4, 5, 127
NMT_NAMES = {0: "BOOT-UP", 4: "STOPPED", 5: "OPERATIONAL", 127: "PRE-OPERATIONAL"}
# The master's own heartbeat, on a real transport (decision E34): the drives consume it (0x1016) and stop on
# their own when it stops, as the ASDA-A3's AL180. The highest node ID, which benches leave to the master.
MASTER_NODE_ID = 0x7F
CIA402_DEVICE_PROFILE = 402
CIA401_DEVICE_PROFILE = 401  # generic I/O modules (remote I/O stations)
ALARM_EIO_FAILED = 0x1426  # the system remote module (EIO) failed
ALARM_EIO_MISMATCH = 0x142E  # the EIO connection device type does not match the settings
_channels = itertools.count(1)


class CanopenLink:
    def __init__(self, nodes: Sequence[NodeConfig], interface: str, channel: str = "", cycle: float = 0.001,
                 bitrate: int = DEFAULT_BITRATE, heartbeat_period: float | None = None,
                 heartbeat_timeout: float | None = None, tpdo_timeout: float | None = None,
                 io_nodes: Sequence[IoNodeConfig] = ()) -> None:
        if not nodes:
            raise ValueError("a CANopen bus needs at least one node")
        if interface == "udp_multicast" and not channel:
            raise ValueError("canopen:udp_multicast needs an explicit multicast group, e.g. "
                             "canopen:udp_multicast:239.74.163.2")
        check_multicast_allowed(interface)
        self.nodes_cfg = list(nodes)
        self.interface = interface
        self.lockstep = interface == "virtual"
        self.channel = channel or (f"deltahil-canopen-{next(_channels)}" if self.lockstep else
                                   "can0" if interface == "socketcan" else "")
        self.cycle_time = cycle
        self.bitrate = bitrate
        # Heartbeat producer (0x1017) / consumer time: tight in lock-step, where time is exact; on a
        # real wire wide enough that thread and network jitter of a non-RT host never trips it.
        self.heartbeat_period = heartbeat_period or (0.02 if self.lockstep else 0.1)
        self.heartbeat_timeout = heartbeat_timeout or 2.5 * self.heartbeat_period
        self.tpdo_timeout = tpdo_timeout if tpdo_timeout is not None else max(0.8 * cycle, 0.002)
        self.ip_period = interpolation_period(cycle)
        for cfg in self.nodes_cfg:
            frame_layouts(cfg.layout)  # refuse layouts that don't fit the node's PDOs
        self.io_cfg = list(io_nodes)  # remote I/O stations, after the drives (CiA 401)
        self.budget: BusLoad = bus_load([c.layout for c in self.nodes_cfg], cycle, bitrate, self.heartbeat_period,
                                        [(c.inputs, c.outputs) for c in self.io_cfg])
        # Raises BusBudgetError above 100 % on a wire with a bitrate; the virtual bus only warns.
        self.budget_note = check_budget(self.budget, enforce=not self.lockstep)
        if self.budget_note:
            log.warning("%s", self.budget_note)
        self.network: canopen.Network | None = None
        self.peers: list[Callable[[], None]] = []  # in-process slaves pumped in lock-step
        self.on_close: list[Callable[[], None]] = []
        self.time = 0.0
        self.cycles = 0
        self.infos: list[SlaveInfo] = []
        self.found: list[int] = []
        self._nodes: list[Node] = []
        self._io: list[IoNode] = []
        self._opened = False
        self._lock = threading.Condition()
        self._emcys: list[tuple[Node, Emcy]] = []
        self.faults: list[tuple[str, FaultEpisode]] = []  # (drive, episode) in the order they began
        self._next_sync = 0.0
        self._next_heartbeat = 0  # perf_counter_ns when the master's next heartbeat is due (real transports)
        self._opened_at = 0.0
        self.capture: Any = None  # fieldbus.capture.CanCapture: `hil run --capture FILE.asc`
        # True: the caller holds the cycle (a real-time clock), so exchange() sends the SYNC at once (E24)
        self.paced = False
        self._pending = 0  # TPDOs of the current SYNC not yet received (counted down by the receive thread)
        self.wait_ns = 0  # the last exchange's time in sending, the SYNC and the wait for the TPDOs (E25)

    @classmethod
    def for_bench(cls, bench: Any, interface: str, channel: str = "") -> "CanopenLink":
        """Node IDs 1, 2, … in axis order, then the spindles; CSP set for axes, CSP+CSV for spindles."""
        eds = getattr(bench, "canopen_eds", None) or ASDA_B3_EDS
        nodes = [NodeConfig(i + 1, a.name, ASDA_CSP, getattr(a, "canopen_eds", "") or eds)
                 for i, a in enumerate(bench.axes)]
        nodes += [NodeConfig(len(nodes) + k + 1, s.name, ASDA_CSP_CSV, getattr(s, "canopen_eds", "") or eds)
                  for k, s in enumerate(bench.spindles)]
        io = [IoNodeConfig(st.canopen_node, st.map.name, st.map.inputs, st.map.outputs, st.canopen_tpdo,
                           getattr(st, "canopen_eds", ""))
              for st in getattr(bench, "io", [])]  # [[io]] stations (mlc/remote_io.py)
        return cls(nodes, interface, channel, bench.cycle,
                   bitrate=int(getattr(bench, "canopen_bitrate", None) or DEFAULT_BITRATE), io_nodes=io)

    # ---- clock ------------------------------------------------------------------------
    def _now(self) -> float:
        return self.time if self.lockstep else time.monotonic()

    def _wait(self, done: Callable[[], bool], timeout: float) -> bool:
        """Lock-step: everything was delivered already. Real time: wait for the receive thread."""
        if self.lockstep:
            return done()
        end = time.monotonic() + timeout
        with self._lock:
            while not done():
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._lock.wait(left)
        return True

    # ---- open ---------------------------------------------------------------------------
    def open(self) -> list[SlaveInfo]:
        if self.lockstep:
            net = LockstepNetwork(self.channel, auto_deliver=True)
            net.peers = self.peers
            self.network = net
        else:
            self.network = canopen.Network()
            try:
                self.network.connect(**connect_args(self.interface, self.channel, self.bitrate))
            except (can.CanError, OSError, ValueError, ImportError) as exc:  # no such interface / channel
                raise BusError(Alarm(ALARM_ESTABLISH, f"cannot open CAN interface {self.interface}"
                                                      f"{':' + self.channel if self.channel else ''}: {exc}")) from None
        net = self.network
        if self.capture is not None:  # every frame from NMT reset on; lock-step frames carry simulated time
            t0 = time.time()
            self.capture.tap(net.bus, (lambda: t0 + self.time) if self.lockstep else time.time,
                             self.channel if not self.lockstep else "virtual")
        for cfg in self.nodes_cfg:
            remote = canopen.RemoteNode(cfg.node_id, canopen.import_od(str(cfg.eds), cfg.node_id))
            net.add_node(remote)
            rx, tx = frame_layouts(cfg.layout)
            node = Node(cfg, remote, rx, tx)
            self._nodes.append(node)
            net.subscribe(0x700 + cfg.node_id, self._heartbeat_cb(node))
            net.subscribe(0x80 + cfg.node_id, self._emcy_cb(node))
        for icfg in self.io_cfg:
            io = IoNode(icfg, canopen.RemoteNode(icfg.node_id, canopen.import_od(str(icfg.eds or DIO_EDS),
                                                                                  icfg.node_id)))
            net.add_node(io.remote)
            self._io.append(io)
            net.subscribe(0x700 + icfg.node_id, self._heartbeat_cb(io))
        self._scan()
        self._nmt_all(0x82, "RESET COMMUNICATION")
        every = self._nodes + self._io
        if not self._wait(lambda: all(n.nmt_state == NMT_BOOTUP or n.nmt_state == NMT_PREOP for n in every), 1.0):
            missing = [n for n in every if n.nmt_state is None]
            self._fail(Alarm(ALARM_NOT_FOUND, "no boot-up after NMT reset communication from "
                             + ", ".join(self._label(n) for n in missing), axis=missing[0].cfg.name))
        self._nmt_all(0x80, "PRE-OPERATIONAL")
        self.infos = [self._identify(i, n) for i, n in enumerate(self._nodes)]
        self.infos += [self._identify_io(len(self.infos) + k, n) for k, n in enumerate(self._io)]
        for n in self._nodes:
            self._configure(n)
        for io in self._io:
            self._configure_io(io)
        self._nmt_all(0x01, "OPERATIONAL")
        now = self._now()
        with self._lock:
            for n, info in zip(self._nodes + self._io, self.infos):
                n.last_heartbeat = now
                n.nmt_state = None  # known again from the first heartbeat after NMT start
                info.state = "OPERATIONAL"
        self._opened_at = now
        self._opened = True
        self._next_sync = time.monotonic()
        return self.infos

    def _scan(self) -> None:
        """python-canopen's NodeScanner asks every ID for 0x1000; our nodes must be among those answering."""
        net = self.network
        net.scanner.reset()
        net.scanner.search()
        want = {n.cfg.node_id for n in self._nodes + self._io}
        self._wait(lambda: want <= set(net.scanner.nodes), 0.5)
        self.found = sorted(net.scanner.nodes)
        missing = [n for n in self._nodes + self._io if n.cfg.node_id not in self.found]
        if missing:
            self._fail(Alarm(ALARM_NOT_FOUND, "CANopen node scan on " + self.describe_bus() + " found "
                             + (", ".join(map(str, self.found)) or "no node") + "; missing "
                             + ", ".join(self._label(n) for n in missing), axis=missing[0].cfg.name))

    def _nmt_all(self, code: int, name: str) -> None:
        for n in self._nodes + self._io:
            if code == 0x82:
                n.nmt_state = None
            n.remote.nmt.send_command(code)
        log.info("NMT %s sent to nodes %s", name, [n.cfg.node_id for n in self._nodes + self._io])

    def _identity(self, n: Node | IoNode) -> tuple[int, int, int]:
        """Device type (0x1000), vendor and product code (0x1018) of a node, over SDO."""
        sdo = n.remote.sdo
        return (self._sdo(n, lambda: sdo[0x1000].raw, 0x1000), self._sdo(n, lambda: sdo[0x1018][1].raw, 0x1018),
                self._sdo(n, lambda: sdo[0x1018][2].raw, 0x1018))

    def _identify(self, pos: int, n: Node) -> SlaveInfo:
        device_type, vendor, product = self._identity(n)
        if device_type & 0xFFFF != CIA402_DEVICE_PROFILE:
            self._fail(Alarm(ALARM_PDO_MAPPING, f"{self._label(n)} is not a CiA 402 drive "
                             f"(device type 0x{device_type:08X})", axis=n.cfg.name))
        return SlaveInfo(pos, n.cfg.name, "drive", vendor, product, "PRE-OPERATIONAL", n.cfg.layout.name)

    def _configure(self, n: Node) -> None:
        sdo, nid = n.remote.sdo, n.cfg.node_id
        value, index = self.ip_period
        self._sdo(n, lambda: setattr(sdo[0x60C2][1], "raw", value), 0x60C2)
        self._sdo(n, lambda: setattr(sdo[0x60C2][2], "raw", index), 0x60C2)
        self._sdo(n, lambda: setattr(sdo[0x1017], "raw", int(round(self.heartbeat_period * 1000))), 0x1017)
        if not self.lockstep:
            self._watch_master(n)
        for maps, frames, base in ((n.remote.rpdo, n.rx_frames, 0x200), (n.remote.tpdo, n.tx_frames, 0x180)):
            for k in range(MAX_PDOS):
                m = maps[k + 1]
                m.clear()
                m.cob_id = base + 0x100 * k + nid
                m.trans_type = 1  # synchronous: RPDOs act, TPDOs are sent, on every SYNC
                m.rtr_allowed = False
                m.enabled = k < len(frames)
                if m.enabled:
                    for e in (frames[k].rx or frames[k].tx):
                        m.add_variable(e.index, e.subindex, e.bits)
                com = m.com_record.od.index
                self._sdo(n, m.save, com, f"{'RPDO' if base == 0x200 else 'TPDO'}{k + 1} "
                                          f"(0x{com:04X}/0x{m.map_array.od.index:04X})")
        # The library subscribed its own PdoMap handlers; we decode TPDOs with our structs instead.
        for k, frame in enumerate(n.tx_frames):
            cob = 0x180 + 0x100 * k + nid
            self.network.unsubscribe(cob)
            n.tx_cobs[cob] = frame
            self.network.subscribe(cob, self._tpdo_cb(n))

    # ---- remote I/O stations (CiA 401) ------------------------------------------------------------
    def _identify_io(self, pos: int, n: IoNode) -> SlaveInfo:
        device_type, vendor, product = self._identity(n)
        if device_type & 0xFFFF != CIA401_DEVICE_PROFILE:
            self._fail(Alarm(ALARM_EIO_MISMATCH, f"{self._label(n)} is not a CiA 401 I/O station "
                             f"(device type 0x{device_type:08X})"))
        return SlaveInfo(pos, n.cfg.name, "io", vendor, product, "PRE-OPERATIONAL", "cia401")

    def _configure_io(self, n: IoNode) -> None:
        """Heartbeat, TPDO1 = the input bytes (0x6000:1…), RPDO1 = the output bytes (0x6200:1…); the
        other PDOs off. Outputs act on SYNC; inputs come on SYNC or on change (`cfg.tpdo`)."""
        sdo, nid, cfg = n.remote.sdo, n.cfg.node_id, n.cfg
        self._sdo(n, lambda: setattr(sdo[0x1017], "raw", int(round(self.heartbeat_period * 1000))), 0x1017)
        for maps, base, index, points, trans in ((n.remote.rpdo, 0x200, 0x6200, cfg.outputs, 1),
                                                 (n.remote.tpdo, 0x180, 0x6000, cfg.inputs,
                                                  1 if cfg.tpdo == "sync" else 255)):
            m = maps[1]
            m.clear()
            m.cob_id = base + nid
            m.trans_type = trans
            m.rtr_allowed = False
            if base == 0x180 and trans == 255:
                m.inhibit_time, m.event_timer = 0, 0
            m.enabled = points > 0
            for sub in range(1, (points + 7) // 8 + 1):
                m.add_variable(index, sub, 8)
            self._sdo(n, m.save, m.com_record.od.index, f"{'RPDO' if base == 0x200 else 'TPDO'}1 of the I/O station")
        if cfg.inputs:  # our decoder instead of the library's PdoMap handler
            self.network.unsubscribe(0x180 + nid)
            self.network.subscribe(0x180 + nid, self._io_tpdo_cb(n))

    def _io_tpdo_cb(self, n: IoNode) -> Callable[[int, bytes, float], None]:
        def cb(can_id: int, data: bytes, timestamp: float) -> None:
            with self._lock:
                n.inputs = int.from_bytes(bytes(data), "little") & ((1 << n.cfg.inputs) - 1)
                n.received = True
                self._lock.notify_all()
        return cb

    def io_ok(self, k: int) -> bool:
        """Station k is on the bus and OPERATIONAL (its inputs are current)."""
        if not self._opened or k >= len(self._io):
            return False
        n = self._io[k]
        return not n.lost and n.nmt_state in (None, NMT_OPERATIONAL)

    def io_inputs(self, k: int) -> int:
        """Station k's inputs from its last TPDO; 0 while it is not OPERATIONAL (the safe state)."""
        return self._io[k].inputs if self.io_ok(k) else 0

    def set_io_outputs(self, k: int, value: int) -> None:
        """Outputs station k's RPDO carries from the next cycle on."""
        if k < len(self._io):
            self._io[k].outputs = value & ((1 << self._io[k].cfg.outputs) - 1)

    def _watch_master(self, n: Node) -> None:
        """The drive consumes the master's heartbeat within the time the master gives the drives' own (E34); a
        drive without 0x1016, or one that refuses it, runs as before, only without stopping by itself when the
        master dies (said once in the log)."""
        sdo = n.remote.sdo
        if 0x1016 not in sdo or n.cfg.node_id == MASTER_NODE_ID:
            return
        consumer = MASTER_NODE_ID << 16 | int(round(self.heartbeat_timeout * 1000))

        def watch() -> None:
            try:
                sdo[0x1016][1].raw = consumer
            except SdoAbortedError as exc:
                log.warning("%s refused the master's heartbeat to watch (0x1016:1, SDO abort 0x%08X, %s): it "
                            "will not stop by itself if this master dies", self._label(n), exc.code, _abort_text(exc))

        self._sdo(n, watch, 0x1016)  # (no answer at all is the usual bring-up alarm)

    def _sdo(self, n: Node, op: Callable[[], Any], index: int, what: str = "") -> Any:
        try:
            return op()
        except SdoAbortedError as exc:
            code = (ALARM_INTERPOLATION if index == 0x60C2 else
                    ALARM_PDO_MAPPING if 0x1400 <= index <= 0x1BFF else ALARM_ESTABLISH)
            self._fail(Alarm(code, f"SDO abort 0x{exc.code:08X} ({_abort_text(exc)}) from {self._label(n)} "
                                   f"writing {what or f'object 0x{index:04X}'}", axis=n.cfg.name))
        except SdoCommunicationError as exc:
            self._fail(Alarm(ALARM_NOT_FOUND, f"{self._label(n)} does not answer SDO 0x{index:04X}: {exc}",
                             axis=n.cfg.name))

    def _fail(self, alarm: Alarm) -> None:
        raise BusError(alarm)

    # ---- receive callbacks (the Notifier thread in real time) -----------------------------
    def _heartbeat_cb(self, n: Node) -> Callable[[int, bytes, float], None]:
        def cb(can_id: int, data: bytes, timestamp: float) -> None:
            with self._lock:
                n.nmt_state = data[0] & 0x7F if data else None
                n.last_heartbeat = self._now()
                self._lock.notify_all()
        return cb

    def _emcy_cb(self, n: Node) -> Callable[[int, bytes, float], None]:
        def cb(can_id: int, data: bytes, timestamp: float) -> None:
            with self._lock:
                self._emcys.append((n, Emcy.decode(data)))
        return cb

    def _tpdo_cb(self, n: Node) -> Callable[[int, bytes, float], None]:
        def cb(can_id: int, data: bytes, timestamp: float) -> None:
            frame = n.tx_cobs[can_id]
            if len(data) < frame.tx_bytes:
                return  # a short TPDO is not processed (CiA 301 PDO length error)
            with self._lock:
                frame.unpack_tx(data, into=n.tx)
                if can_id not in n.received and not n.lost:
                    n.received.add(can_id)
                    # the cycle's waiter is woken once, by its last TPDO, not by each (E26)
                    self._pending -= 1
                    if self._pending == 0:
                        self._lock.notify_all()
        return cb

    # ---- the cycle ------------------------------------------------------------------------
    def exchange(self, outputs: Sequence[Any]) -> list[Any]:
        if len(outputs) != len(self._nodes or self.nodes_cfg):
            raise ValueError(f"{len(outputs)} output images for {len(self.nodes_cfg)} CANopen nodes")
        if not self._opened:
            return [TxPdo() for _ in self.nodes_cfg]
        net = self.network
        live = [n for n in self._nodes if not n.lost]
        frames = [(0x200 + 0x100 * k + n.cfg.node_id, frame.pack_rx(rx))
                  for n, rx in zip(self._nodes, outputs) if not n.lost for k, frame in enumerate(n.rx_frames)]
        for io in self._io:  # remote I/O outputs (mlc/remote_io.py), acting on this SYNC
            if not io.lost and io.cfg.outputs:
                frames.append((0x200 + io.cfg.node_id, io.outputs.to_bytes((io.cfg.outputs + 7) // 8, "little")))
        t0 = perf_counter_ns()  # from here to the last TPDO: the wait for the bus (decisions E25)
        if not self.lockstep and not self.paced:
            # The SYNC producer holds the bench cycle against a caller that does not pace itself (lock-step over a
            # real transport); a real-time clock paces the caller, and the SYNC goes when it asks (decisions E24)
            self._next_sync += self.cycle_time
            delay = self._next_sync - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                self._next_sync = time.monotonic()
        with self._lock:
            for n in live:
                n.received.clear()
            self._pending = sum(len(n.tx_frames) for n in live)  # TPDOs this SYNC must bring
        send = net.send_raw if self.lockstep else net.send_message
        if not self.lockstep and t0 >= self._next_heartbeat:  # the master's heartbeat (E34), OPERATIONAL
            self._next_heartbeat = t0 + int(self.heartbeat_period * 1e9)
            frames.append((0x700 + MASTER_NODE_ID, b"\x05"))
        for cob, data in frames:
            send(cob, data)
        net.sync.transmit()  # lock-step: delivers RPDOs + SYNC, the slaves answer, we collect
        self.cycles += 1
        if self.lockstep:
            self.time += self.cycle_time
        else:
            self._wait(lambda: self._pending <= 0, self.tpdo_timeout)
        self.wait_ns = perf_counter_ns() - t0
        with self._lock:
            for n in live:
                if len(n.received) < len(n.tx_frames):
                    n.tpdo_misses += 1  # keep the last values: the heartbeat decides if the node is gone
            out = [copy_tx(n.tx) for n in self._nodes]
            emcys, self._emcys = self._emcys, []
        self._supervise(emcys)
        return out

    def _supervise(self, emcys: list[tuple[Node, Emcy]]) -> None:
        alarm = fault_episodes(self._nodes, emcys, self.faults, self._label)
        now = self._now()
        for n in self._nodes:
            if n.lost:
                continue
            if now - n.last_heartbeat > self.heartbeat_timeout + 1e-9:
                self._lose(n)
                raise BusError(Alarm(ALARM_COMMUNICATION, f"heartbeat of {self._label(n)} lost: none for "
                                     f"{(now - n.last_heartbeat) * 1000:.0f} ms (consumer time "
                                     f"{self.heartbeat_timeout * 1000:g} ms)", axis=n.cfg.name))
            # A heartbeat sent just before the node saw NMT start may still say PRE-OPERATIONAL.
            if n.nmt_state not in (None, NMT_OPERATIONAL) and n.last_heartbeat - self._opened_at > self.heartbeat_period:
                state = NMT_NAMES.get(n.nmt_state, str(n.nmt_state))
                self._lose(n)
                raise BusError(Alarm(ALARM_COMMUNICATION, f"{self._label(n)} left OPERATIONAL: heartbeat "
                                     f"reports {state}", axis=n.cfg.name))
        for io in self._io:  # a station gone: its inputs read 0 from now on (io_ok), then the alarm
            if io.lost:
                continue
            silent = now - io.last_heartbeat > self.heartbeat_timeout + 1e-9
            left = io.nmt_state not in (None, NMT_OPERATIONAL) and io.last_heartbeat - self._opened_at > self.heartbeat_period
            if silent or left:
                io.lost = True
                io.inputs = 0
                if self.infos:
                    self.infos[len(self._nodes) + self._io.index(io)].state = "LOST"
                why = (f"no heartbeat for {(now - io.last_heartbeat) * 1000:.0f} ms" if silent else
                       f"heartbeat reports {NMT_NAMES.get(io.nmt_state, str(io.nmt_state))}")
                raise BusError(Alarm(ALARM_EIO_FAILED, f"remote I/O station {self._label(io)} lost: {why}"))
        if alarm is not None:
            raise BusError(alarm)

    def _lose(self, n: Node) -> None:
        """A lost node reads 'not ready to switch on' and is no longer served or supervised."""
        n.lost = True
        n.tx = TxPdo(position_actual=n.tx.position_actual, error_code=n.tx.error_code)
        if self.infos:
            self.infos[self._nodes.index(n)].state = "LOST"

    # ---- close ----------------------------------------------------------------------------
    def close(self) -> None:
        net, self.network = self.network, None
        self._opened = False
        try:
            if net is not None and net.bus is not None:
                for n in self._nodes + self._io:
                    if not n.lost:
                        n.remote.nmt.send_command(0x02)  # NMT stop: no more PDOs; I/O outputs to their safe state
                net.disconnect()
        except (can.CanError, OSError) as exc:
            log.warning("closing the CANopen network: %s", exc)
        finally:
            for fn in self.on_close:
                fn()

    # ---- acyclic SDO (servo parameters, issue 8); same signature as EthercatLink.sdo_read ----
    def sdo_read(self, position: int, index: int, sub: int = 0, size: int = 0) -> bytes:
        """SDO upload from the node at `position` (bench order); SdoAbortedError (`.code`) when
        the node refuses, BusError when it does not answer."""
        return self._acyclic(position, index, lambda sdo: sdo.upload(index, sub))

    def sdo_write(self, position: int, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        self._acyclic(position, index, lambda sdo: sdo.download(index, sub, data))

    def _acyclic(self, position: int, index: int, op: Callable[[Any], Any]) -> Any:
        n = self._nodes[position]
        try:
            return op(n.remote.sdo)
        except SdoCommunicationError as exc:
            raise BusError(Alarm(ALARM_NOT_FOUND, f"{self._label(n)} does not answer SDO 0x{index:04X}: {exc}",
                                 axis=n.cfg.name)) from None

    # ---- helpers ----------------------------------------------------------------------------
    def describe_bus(self) -> str:
        return f"canopen:{self.interface}" + (f":{self.channel}" if self.channel else "")

    @staticmethod
    def _label(n: Node) -> str:
        return f"node {n.cfg.node_id} ({n.cfg.name})"

    @property
    def tpdo_misses(self) -> dict[str, int]:
        return {n.cfg.name: n.tpdo_misses for n in self._nodes}


# python-can interfaces whose bit timing is not the process's to set: socketcan's is the kernel's
# (`ip link set can0 type can bitrate …`), udp_multicast and virtual have none.
_BITRATE_SET_ELSEWHERE = {"socketcan", "udp_multicast", "virtual"}


def connect_args(interface: str, channel: str, bitrate: int) -> dict[str, Any]:
    """python-can bus arguments: the bench's bitrate goes to the adapters that configure it themselves
    (pcan, kvaser, ixxat, slcan, gs_usb …)."""
    args: dict[str, Any] = {"interface": interface, "channel": channel}
    if interface not in _BITRATE_SET_ELSEWHERE:
        args["bitrate"] = bitrate
    return args


def _abort_text(exc: SdoAbortedError) -> str:
    text = str(exc)  # "Code 0x06040041, Object cannot be mapped to the PDO"
    return text.split(", ", 1)[-1] if text.startswith("Code ") else text
