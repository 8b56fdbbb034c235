"""A simulated CiA 401 digital I/O station on CAN: python-canopen's `LocalNode` for SDO, NMT and the
heartbeat; this class for the process data (`LocalNode` leaves PDOs to the application).

Objects (fieldbus/canopen/eds/delta_dio_401.eds): inputs 0x6000:1…8 (8 points per byte), outputs
0x6200:1…8, error mode/value 0x6206/0x6207, global interrupt enable 0x6005. TPDO1 carries the
inputs: with a synchronous transmission type (1…240) on every SYNC, with 254/255 at once when an
input changes (and once after NMT start, so the master learns the initial state). RPDO1 carries
the outputs and acts on the next SYNC (synchronous) or at once (254/255). When the station leaves
OPERATIONAL (NMT stop, pre-operational, reset) every output whose error-mode bit is set takes its
error value (CiA 401 default: off) — the outputs' safe state.
"""

from __future__ import annotations

import struct
from pathlib import Path

import canopen
from canopen import objectdictionary as odmod
from canopen.sdo.exceptions import SdoAbortedError

from fieldbus.canopen.lockstep import LockstepNetwork
from fieldbus.canopen.objects import DIO_EDS

ABORT_NOT_MAPPABLE = 0x06040041
INPUTS, OUTPUTS = 0x6000, 0x6200
SYNC_TYPES = range(1, 241)


class Cia401Slave:
    def __init__(self, node_id: int, inputs: int = 16, outputs: int = 16, name: str = "",
                 eds: str | Path = DIO_EDS) -> None:
        self.node = canopen.LocalNode(node_id, canopen.import_od(str(eds), node_id))
        self.name = name or f"DIO node {node_id}"
        self.n_inputs, self.n_outputs = inputs, outputs
        self.inputs = 0  # the station's input terminals, driven by a test or script
        self.outputs = 0  # what its output terminals drive now
        self.history: list[tuple[int, int]] = []  # (SYNC count, outputs) at each change
        self.alive = True
        self.syncs = 0
        self.network: canopen.Network | None = None
        self._latched: bytes | None = None
        self._sent_since_start = False
        self._rpdo_sub: int | None = None  # the COB-ID the RPDO handler listens on
        self.node.add_read_callback(self._on_read)
        self.node.add_write_callback(self._on_write)

    @property
    def node_id(self) -> int:
        return self.node.id

    @property
    def nmt_state(self) -> str:
        return self.node.nmt.state

    # ---- terminals ------------------------------------------------------------------------------
    def set_input(self, point: int, on: bool) -> None:
        before = self.inputs
        self.inputs = (self.inputs | 1 << point) if on else (self.inputs & ~(1 << point))
        if self.inputs != before and self._event_driven() and self._operational():
            self._send_inputs()  # change of state: the TPDO goes out now, not at the next SYNC

    def output(self, point: int) -> bool:
        return bool(self.outputs >> point & 1)

    # ---- network ---------------------------------------------------------------------------------
    def attach(self, network: canopen.Network) -> None:
        self.network = network
        network.add_node(self.node)
        network.subscribe(0, self._after_nmt)
        network.subscribe(0x80, self._on_sync)
        self.node.nmt.send_command(0x82)  # boot-up
        self.node.nmt.send_command(0x80)  # PRE-OPERATIONAL, heartbeat from 0x1017

    def power_off(self) -> None:
        """Off the bus (cable pulled): no SDO, PDO or heartbeat any more; terminals keep their state."""
        self.alive = False
        self.node.nmt.stop_heartbeat()
        if self.network is not None:
            self.network.unsubscribe(0, self._after_nmt)
            self.network.unsubscribe(0x80, self._on_sync)
            self._listen(None)
            self.node.remove_network()

    def _after_nmt(self, can_id: int, data: bytes, timestamp: float) -> None:
        cmd, target = struct.unpack_from("BB", data)
        if target not in (0, self.node_id) or not self.alive:
            return
        if cmd in (0x81, 0x82):  # reset: communication objects back to the EDS defaults
            for index in [i for i in self.node.data_store if 0x1000 <= i <= 0x1FFF]:
                del self.node.data_store[index]
            self.node.nmt.stop_heartbeat()
            self.node.nmt.send_command(0x82)
            self.node.nmt.send_command(0x80)
        if self._operational():
            self._sent_since_start = False
            self._listen(self._rpdo_cob())
        else:
            self._latched = None
            self._error_outputs()

    def _listen(self, cob: int | None) -> None:
        """Move the RPDO handler to `cob` (None: stop listening)."""
        if self.network is None or cob == self._rpdo_sub:
            return
        if self._rpdo_sub is not None:
            self.network.unsubscribe(self._rpdo_sub, self._on_rpdo)
        self._rpdo_sub = cob
        if cob is not None:
            self.network.subscribe(cob, self._on_rpdo)

    def _operational(self) -> bool:
        return self.alive and self.node.nmt.state == "OPERATIONAL"

    # ---- object dictionary ------------------------------------------------------------------------
    def _value(self, index: int, sub: int) -> int:
        od = self.node.object_dictionary[index]
        var = od if isinstance(od, odmod.ODVariable) else od[sub]
        return var.decode_raw(self.node.get_data(index, sub))

    def _on_read(self, index: int, subindex: int, od: odmod.ODVariable):
        if index == INPUTS and subindex >= 1:
            return self.inputs >> 8 * (subindex - 1) & 0xFF
        if index == OUTPUTS and subindex >= 1:
            return self.outputs >> 8 * (subindex - 1) & 0xFF
        return None

    def _on_write(self, index: int, subindex: int, od: odmod.ODVariable, data: bytes) -> None:
        if index in (0x1600, 0x1A00) and subindex >= 1:
            value = od.decode_raw(data)
            want = OUTPUTS if index == 0x1600 else INPUTS
            if value and (value >> 16 != want or value & 0xFF != 8 or not 1 <= (value >> 8) & 0xFF <= 8):
                raise SdoAbortedError(ABORT_NOT_MAPPABLE)
        if index == OUTPUTS and subindex >= 1:  # an SDO write to the outputs acts at once
            self._set_output_byte(subindex, od.decode_raw(data))

    def _set_output_byte(self, sub: int, value: int) -> None:
        shift = 8 * (sub - 1)
        outs = (self.outputs & ~(0xFF << shift)) | (value & 0xFF) << shift
        self._drive_outputs(outs)

    def _drive_outputs(self, outs: int) -> None:
        outs &= (1 << self.n_outputs) - 1
        if outs != self.outputs:
            self.history.append((self.syncs, outs))
        self.outputs = outs

    def _error_outputs(self) -> None:
        """Outputs with their error-mode bit set (0x6206) take the error value (0x6207)."""
        outs = self.outputs
        for sub in range(1, (self.n_outputs + 7) // 8 + 1):
            mode, value, shift = self._value(0x6206, sub), self._value(0x6207, sub), 8 * (sub - 1)
            outs = (outs & ~(mode << shift)) | (value & mode) << shift
        self._drive_outputs(outs)

    # ---- PDOs ---------------------------------------------------------------------------------------
    def _rpdo_cob(self) -> int:
        return self._value(0x1400, 1) & 0x7FF

    def _event_driven(self) -> bool:
        return self._value(0x1800, 2) not in SYNC_TYPES

    def _mapped(self, mapping: int) -> list[int]:
        return [(self._value(mapping, s) >> 8) & 0xFF for s in range(1, self._value(mapping, 0) + 1)]

    def _on_rpdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        if not self._operational() or self._value(0x1400, 1) & 0x80000000:
            return
        if self._value(0x1400, 2) in SYNC_TYPES:
            self._latched = bytes(data)  # synchronous: acts on the next SYNC
        else:
            self._apply_rpdo(bytes(data))

    def _apply_rpdo(self, data: bytes) -> None:
        for k, sub in enumerate(self._mapped(0x1600)):
            if k < len(data):
                self._set_output_byte(sub, data[k])

    def _send_inputs(self) -> None:
        cob = self._value(0x1800, 1)
        if cob & 0x80000000 or self.network is None:
            return
        payload = bytes(self.inputs >> 8 * (sub - 1) & 0xFF for sub in self._mapped(0x1A00))
        self.network.send_message(cob & 0x7FF, payload)
        self._sent_since_start = True

    def _on_sync(self, can_id: int, data: bytes, timestamp: float) -> None:
        """One SYNC: a latched RPDO acts; a synchronous TPDO samples and sends the inputs."""
        if not self._operational():
            return
        self.syncs += 1
        if self._latched is not None:
            self._apply_rpdo(self._latched)
            self._latched = None
        if not self._event_driven() or not self._sent_since_start:
            self._send_inputs()


def attach_lockstep_io(link, slaves: list[Cia401Slave]) -> LockstepNetwork:
    """Put I/O stations on the link's `virtual` channel, pumped by the link after each frame it sends;
    their heartbeats run on simulated time, one bench cycle per SYNC."""
    network = LockstepNetwork(link.channel)
    for s in slaves:
        s.attach(network)
    network.subscribe(0x80, lambda *_: network.advance(link.cycle_time))

    def close() -> None:
        for s in slaves:
            s.node.nmt.stop_heartbeat()
        network.disconnect()

    link.peers.append(network.pump)
    link.on_close.append(close)
    return network
