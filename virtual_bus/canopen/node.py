"""A simulated CiA 402 servo on CAN: python-canopen's `LocalNode` for the communication objects
(SDO server, NMT slave, heartbeat producer, EMCY producer) and `virtual_bus.drive.Cia402Drive`
for the drive.

`LocalNode` leaves the PDO logic to the application (its docstring; canopen#328/#555/#558:
TPDOs are never sent on SYNC by themselves), so this class reads the 0x1400/0x1600 and
0x1800/0x1A00 records the master wrote, latches RPDOs, and on every SYNC applies them, steps the
drive by the interpolation time period (0x60C2) and sends its TPDOs.
"""

from __future__ import annotations

import logging
import struct
from dataclasses import dataclass

import canopen
from canopen import objectdictionary as odmod
from canopen.sdo.exceptions import SdoAbortedError

from fieldbus.canopen.emcy import Emcy, emcy_for_delta
from fieldbus.canopen.objects import ASDA_B3_EDS, MAX_PDO_BYTES, MAX_PDOS, OBJECT_ATTRS
from fieldbus.cia402 import State
from fieldbus.pdo import PdoEntry, PdoLayout, RxPdo, copy_rx
from virtual_bus.canopen.master_watch import MasterWatch
from virtual_bus.drive import Cia402Drive
from virtual_bus.drive_modes import MODE_OBJECTS, check_value
from virtual_bus.servo_params import ServoParamError, ServoParams, coe_objects

log = logging.getLogger("virtual_bus.canopen")

ABORT_COMMAND = 0x05040001  # client command specifier not valid or unknown (block transfers)
ABORT_UNSUPPORTED_ACCESS = 0x06010000
ABORT_NOT_MAPPABLE = 0x06040041
ABORT_PDO_LENGTH = 0x06040042
ABORT_VALUE_RANGE = 0x06090030

_RX_OBJECTS = {0x6040, 0x607A, 0x6060, 0x60FF, 0x60B8, 0x60FE, 0x6071}
_SIGNED = {odmod.INTEGER8, odmod.INTEGER16, odmod.INTEGER32}


@dataclass
class _Pdo:
    cob_id: int
    layout: PdoLayout


class Cia402Slave:
    def __init__(self, node_id: int, drive: Cia402Drive, eds: str = str(ASDA_B3_EDS),
                 reject_writes: dict[tuple[int, int], int] | None = None) -> None:
        self.node = canopen.LocalNode(node_id, canopen.import_od(eds, node_id))
        self.drive = drive
        self.rx = RxPdo(mode=drive.mode)
        self._power_on_mode = drive.mode
        # Fault injection: (index, subindex) → SDO abort code the firmware answers a write with.
        self.reject_writes = dict(reject_writes or {})
        self.alive = True
        self.network: canopen.Network | None = None
        self.syncs = 0
        self.emcys_sent: list[Emcy] = []
        # SYNCs between a fault and its EMCY: 0 = the EMCY leaves before that SYNC's TPDOs (as a drive
        # that reports at once); 1+ = the master sees the statusword fault bit first.
        self.emcy_delay = 0
        self._emcy_queue: list[tuple[int, Emcy]] = []  # (SYNC count it is due at, EMCY)
        self._rpdos: dict[int, PdoLayout] = {}
        self._tpdos: list[_Pdo] = []
        self._latched: dict[int, bytes] = {}
        self._dirty = True
        self._period: float | None = None  # 0x60C2 in seconds, see interpolation_period
        self._fault_reported = 0
        self.watch: MasterWatch | None = None  # the master's heartbeat, in `hil sim canopen` (serve) only
        self._add_servo_params()
        self._mode_defaults()
        self.node.add_read_callback(self._on_read)
        self.node.add_write_callback(self._on_write)

    @property
    def node_id(self) -> int:
        return self.node.id

    # ---- network ---------------------------------------------------------------------------
    def attach(self, network: canopen.Network) -> None:
        """Join the bus and power up: boot-up message, then PRE-OPERATIONAL (CiA 301)."""
        self.network = network
        network.add_node(self.node)
        # SDO requests pass our gate first: none in STOPPED, block transfers aborted (CiA 301)
        network.unsubscribe(self.node.sdo.rx_cobid, self.node.sdo.on_request)
        network.subscribe(self.node.sdo.rx_cobid, self._on_sdo)
        network.subscribe(0, self._after_nmt)  # after the NmtSlave's own handler
        self.node.nmt.send_command(0x82)  # INITIALISING: sends the boot-up
        self.node.nmt.send_command(0x80)  # PRE-OPERATIONAL: starts the heartbeat from 0x1017

    def power_off(self) -> None:
        """The node vanishes from the bus (cable pulled, supply lost): no SDO, PDO, heartbeat."""
        self.alive = False
        self.node.nmt.stop_heartbeat()
        if self.network is not None:
            self.network.unsubscribe(0, self._after_nmt)
            self.network.unsubscribe(self.node.sdo.rx_cobid, self._on_sdo)
            self.network.subscribe(self.node.sdo.rx_cobid, self.node.sdo.on_request)  # remove_network takes it off
            for cob in self._rpdos:
                self.network.unsubscribe(cob, self._on_rpdo)
            self.node.remove_network()

    @property
    def nmt_state(self) -> str:
        return self.node.nmt.state

    def _on_sdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        """CiA 301: the SDO server is not available in STOPPED (no answer at all); this node does
        not do block transfers, so their initiate requests abort with 0x05040001."""
        if not self.alive or self.node.nmt.state == "STOPPED" or not data:
            return
        if data[0] >> 5 in (5, 6) and len(data) >= 4 and self.network is not None:
            index, sub = struct.unpack_from("<HB", data, 1)
            self.network.send_message(self.node.sdo.tx_cobid, struct.pack("<BHBI", 0x80, index, sub, ABORT_COMMAND))
            return
        self.node.sdo.on_request(can_id, data, timestamp)

    def _power_on_profile(self) -> None:
        """NMT Reset Node: the application restarts with its power-on values: the CiA 402 objects
        from the EDS, the drive out of any fault (a persisting cause faults it again), no RPDO data."""
        for index in [i for i in self.node.data_store if 0x6000 <= i <= 0x9FFF]:
            del self.node.data_store[index]
        self._period = None
        d = self.drive
        d.modes.reset()  # the profile modes' objects and the home origin (a real drive forgets it too)
        self._mode_defaults()
        d.external_fault = 0
        d.error_code = 0
        d.state = State.SWITCH_ON_DISABLED
        d.mode = self._power_on_mode
        self.rx = RxPdo(mode=d.mode)
        d.apply(copy_rx(self.rx))
        self._emcy_queue.clear()
        self._fault_reported = 0

    def _after_nmt(self, can_id: int, data: bytes, timestamp: float) -> None:
        cmd, target = struct.unpack_from("BB", data)
        if target not in (0, self.node_id) or not self.alive:
            return
        if cmd in (0x81, 0x82):
            # Reset node / communication: communication objects back to their EDS defaults.
            for index in [i for i in self.node.data_store if 0x1000 <= i <= 0x1FFF]:
                del self.node.data_store[index]
            if cmd == 0x81:
                self._power_on_profile()
            self.node.nmt.stop_heartbeat()
            self._dirty = True
            self.node.nmt.send_command(0x82)  # boot-up
            self.node.nmt.send_command(0x80)
        self._refresh_mapping()

    # ---- object dictionary callbacks ---------------------------------------------------------
    def _add_servo_params(self) -> None:
        """Delta parameters Pn-xx as objects 0x2000 + n*0x100 + xx (INTEGER32), served from the
        drive's `ServoParams` so SDO, Modbus and the drive see one table (issue 8)."""
        od = self.node.object_dictionary
        for index, p in coe_objects():
            var = odmod.ODVariable(p.label, index, 0)
            var.data_type = odmod.INTEGER32
            var.access_type = "rw" if p.writable else "ro"
            od.add_object(var)

    def _mode_defaults(self) -> None:
        """The profile modes' objects (virtual_bus/drive_modes.py) start at the EDS defaults."""
        for (index, sub), attr in MODE_OBJECTS.items():
            var = self._od_var(index, sub)
            if var is not None and var.default is not None:
                setattr(self.drive.modes.objects, attr, int(var.default))

    def _on_read(self, index: int, subindex: int, od: odmod.ODVariable):
        mode_attr = MODE_OBJECTS.get((index, subindex))
        if mode_attr is not None:
            return getattr(self.drive.modes.objects, mode_attr)
        if 0x2000 <= index <= 0x26FF:
            return self.drive.servo_params.read(ServoParams.from_index(index, subindex))
        attr = OBJECT_ATTRS.get((index, subindex))
        if attr is None:
            if index == 0x1001:
                return 0x01 if self.drive.state in (State.FAULT, State.FAULT_REACTION_ACTIVE) else 0
            return None
        if index in _RX_OBJECTS:
            return getattr(self.rx, attr)
        return getattr(self.drive.feedback(), attr)

    def _on_write(self, index: int, subindex: int, od: odmod.ODVariable, data: bytes) -> None:
        code = self.reject_writes.get((index, subindex))
        if code is not None:
            raise SdoAbortedError(code)
        if index == 0x60C2:
            self._period = None  # read again at the next SYNC, once the value is stored
        if 0x2000 <= index <= 0x26FF:  # a servo parameter: the drive checks range and access
            try:
                self.drive.servo_params.sdo_write(index, subindex, data)
            except ServoParamError as exc:
                raise SdoAbortedError(exc.code) from None
            return
        if 0x1400 <= index <= 0x1BFF:
            self._check_mapping_write(index, subindex, od.decode_raw(data))
            self._dirty = True
            return
        if index == 0x6060:  # CiA 402: only the modes 0x6502 advertises (0 = no mode)
            mode, supported = od.decode_raw(data), self._value(0x6502, 0)
            if mode != 0 and not (1 <= mode <= 32 and supported >> (mode - 1) & 1):
                raise SdoAbortedError(ABORT_VALUE_RANGE)
        mode_attr = MODE_OBJECTS.get((index, subindex))
        if mode_attr is not None:  # the drive's profile-mode objects: it checks what it can run
            value = od.decode_raw(data)
            if not check_value(index, subindex, value, self.drive.modes.objects):
                raise SdoAbortedError(ABORT_VALUE_RANGE)
            setattr(self.drive.modes.objects, mode_attr, value)
            return
        attr = OBJECT_ATTRS.get((index, subindex))
        if attr is not None and index in _RX_OBJECTS:
            setattr(self.rx, attr, od.decode_raw(data))
            # Acyclic (SDO) device control acts at once, a target as well as the controlword: NMT states
            # govern PDOs, not the application (a target written in PRE-OPERATIONAL moved nothing before).
            self.drive.apply(copy_rx(self.rx))

    def _check_mapping_write(self, index: int, subindex: int, value: int) -> None:
        if index & 0xFF00 in (0x1400, 0x1800) and subindex == 1:
            # CiA 301 7.5.2.35/37: while a PDO exists (bit 31 clear) its CAN-ID (bits 0-29) stays; CANopenNode
            # answers 0x06090030. Setting bit 31 with a new ID in one write, as python-canopen does, is allowed.
            old = self._value(index, 1)
            if not (old | value) & 0x80000000 and (old ^ value) & 0x3FFFFFFF:
                raise SdoAbortedError(ABORT_VALUE_RANGE)
        if index & 0xFF00 in (0x1600, 0x1A00):
            # CiA 301 7.5.2.36/38: a mapping changes only while its PDO is invalid (COB-ID bit 31 set)
            # and, for the entries, while sub 0 is 0; sub 0 never above the entries the object has.
            com = (0x1400 if index & 0xFF00 == 0x1600 else 0x1800) + (index & 0xFF)
            if not self._value(com, 1) & 0x80000000 or (subindex >= 1 and self._value(index, 0)):
                raise SdoAbortedError(ABORT_UNSUPPORTED_ACCESS)
            if subindex == 0 and value > max(self.node.object_dictionary[index].subindices):
                raise SdoAbortedError(ABORT_PDO_LENGTH)
        if index & 0xFF00 in (0x1600, 0x1A00) and subindex >= 1 and value:
            obj, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
            rx = index & 0xFF00 == 0x1600
            if (obj, sub) not in OBJECT_ATTRS or (obj in _RX_OBJECTS) != rx or bits % 8:
                raise SdoAbortedError(ABORT_NOT_MAPPABLE)
            var = self._od_var(obj, sub)
            if var is None or not var.pdo_mappable or len(var) != bits:
                raise SdoAbortedError(ABORT_NOT_MAPPABLE)
        if index & 0xFF00 in (0x1600, 0x1A00) and subindex == 0 and value:
            total = sum(self._value(index, k) & 0xFF for k in range(1, value + 1))
            if total > 8 * MAX_PDO_BYTES:
                raise SdoAbortedError(ABORT_PDO_LENGTH)

    def _od_var(self, index: int, subindex: int) -> odmod.ODVariable | None:
        od = self.node.object_dictionary
        if index not in od:
            return None
        obj = od[index]
        if isinstance(obj, odmod.ODVariable):
            return obj
        return obj[subindex] if subindex in obj else None

    def _value(self, index: int, subindex: int) -> int:
        var = self._od_var(index, subindex)
        return var.decode_raw(self.node.get_data(index, subindex))

    # ---- PDO mapping --------------------------------------------------------------------------
    def _refresh_mapping(self) -> None:
        """Rebuild the RPDO/TPDO codecs from the communication and mapping records."""
        if not self._dirty or self.network is None:
            return
        self._dirty = False
        for cob in self._rpdos:
            self.network.unsubscribe(cob, self._on_rpdo)
        self._rpdos, self._tpdos, self._latched = {}, [], {}
        for k in range(MAX_PDOS):
            for com, mapping, rx in ((0x1400, 0x1600, True), (0x1800, 0x1A00, False)):
                cob = self._value(com + k, 1)
                if cob & 0x80000000 or self._value(com + k, 2) > 240:
                    continue  # disabled, or not synchronous (only SYNC-driven PDOs are simulated)
                entries = []
                for s in range(1, self._value(mapping + k, 0) + 1):
                    v = self._value(mapping + k, s)
                    obj, sub = v >> 16, (v >> 8) & 0xFF
                    var = self._od_var(obj, sub)
                    entries.append(PdoEntry(obj, sub, v & 0xFF, OBJECT_ATTRS[(obj, sub)],
                                            var is not None and var.data_type in _SIGNED))
                layout = PdoLayout(f"node{self.node_id}-{'r' if rx else 't'}pdo{k + 1}",
                                   tuple(entries) if rx else (), () if rx else tuple(entries))
                if rx:
                    self._rpdos[cob & 0x7FF] = layout
                else:
                    self._tpdos.append(_Pdo(cob & 0x7FF, layout))
        for cob in self._rpdos:
            self.network.subscribe(cob, self._on_rpdo)

    def _on_rpdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        layout = self._rpdos.get(can_id)
        if layout is not None and len(data) >= layout.rx_bytes:
            self._latched[can_id] = bytes(data)  # synchronous RPDO: acts on the next SYNC

    # ---- SYNC ---------------------------------------------------------------------------------
    @property
    def interpolation_period(self) -> float:
        if self._period is None:  # two object reads a SYNC otherwise; dropped when 0x60C2 changes
            self._period = self._value(0x60C2, 1) * 10.0 ** self._value(0x60C2, 2)
        return self._period

    def on_sync(self) -> None:
        """One SYNC: latched RPDOs act, the drive runs one interpolation period, TPDOs go out."""
        if not self.alive:
            return
        self._refresh_mapping()
        self.syncs += 1
        if self.watch is not None:
            self.watch.synced()
        dt = self.interpolation_period
        operational = self.node.nmt.state == "OPERATIONAL"
        if operational:
            for cob, data in self._latched.items():
                self._rpdos[cob].unpack_rx(data, into=self.rx)
            self._latched.clear()
            tx = self.drive.exchange(copy_rx(self.rx), dt)
        else:
            self.drive.step(dt)
            tx = self.drive.feedback()
        self._emcy(tx.error_code)
        due = [e for at, e in self._emcy_queue if at <= self.syncs]
        self._emcy_queue = [(at, e) for at, e in self._emcy_queue if at > self.syncs]
        for emcy in due:
            self._send_emcy(emcy)
        if operational and self.network is not None:
            for pdo in self._tpdos:
                self.network.send_message(pdo.cob_id, pdo.layout.pack_tx(tx))

    def _emcy(self, error_code: int) -> None:
        faulted = self.drive.state in (State.FAULT, State.FAULT_REACTION_ACTIVE)
        if faulted and error_code and error_code != self._fault_reported:
            self._emcy_queue.append((self.syncs + self.emcy_delay, emcy_for_delta(error_code)))
            self._fault_reported = error_code
        elif not faulted and self._fault_reported:
            self._emcy_queue.append((self.syncs + self.emcy_delay, Emcy(0x0000, 0x00, 0)))  # error reset
            self._fault_reported = 0

    def report_fault(self, emcy: Emcy) -> None:
        """Send a fault's EMCY now, not at a SYNC (the master may send none any more: master_watch.py)."""
        self._fault_reported = self.drive.error_code
        self._send_emcy(emcy)

    def _send_emcy(self, emcy: Emcy) -> None:
        """On the COB-ID of 0x1014; none when its bit 31 says the EMCY is not valid (CiA 301)."""
        cob = self._value(0x1014, 0)
        if cob & 0x80000000 or self.network is None:
            return
        self.emcys_sent.append(emcy)
        self.node.emcy.cob_id = cob & 0x7FF
        self.node.emcy.send(emcy.code, emcy.register, emcy.encode()[3:])
