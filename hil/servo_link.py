"""G10 L40/L41/L45/L46 on the bench: the interpreter's servo parameter requests go out over the
bench's own link (SDO on SimLink, EtherCAT CoE or CANopen) or over the drives' RS-485 port
(Modbus RTU), in the cycle the program reaches the block (G10 stops preview, so the motion before
it has finished).

Station ``I`` is the drive's place on the bench, 1 = the first axis (axes in order, then the
spindles): the EtherCAT / SimLink position + 1, the CANopen node-ID (`CanopenLink.for_bench`
numbers nodes the same way).  Over Modbus ``I`` is the drive's RS-485 station number (P3-00).
Delta parameter Pn-xx is object ``0x2000 + n*0x100 + xx`` sub 0 / Modbus register ``0x100*n + 2*xx``
(`virtual_bus.servo_params`, the one mapping `hil servo` uses too).

The reply's result (#20024) is 0, the SDO abort code or the Modbus exception code the drive
answered, or `RESULT_NO_ANSWER` when nothing came back.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

from fieldbus.link import BusError
from nc.interp.servo import RESULT_NO_ANSWER, ServoAccess, ServoReply
from virtual_bus.servo_params import coe_index

SDO_TEXT = {0x06020000: "object does not exist", 0x06010002: "read-only", 0x06090030: "value out of range",
            0x06070010: "data length does not match", 0x06090011: "sub-index does not exist",
            0x08000022: "not in this device state"}


def decode(data: bytes) -> int:
    """An SDO upload as a number: 1- and 2-byte objects unsigned (statusword, modes …), 4 and
    8 bytes signed (positions, velocities, Delta parameters are INTEGER32)."""
    return int.from_bytes(data[:8], "little", signed=len(data) >= 4)


def encode(value: int, size: int) -> bytes:
    """`value` in `size` bytes, two's complement when negative."""
    return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")


@dataclass
class BusServoAccess:
    """The `ServoPort.handler` of a bench run: ``link`` has sdo_read / sdo_write (or not),
    ``modbus`` is an open `fieldbus.modbus.ModbusRtuMaster` for L40/L41, or None."""

    link: Any
    drives: list[str]  # axis and spindle names in station order
    modbus: Any = None

    def __call__(self, req: ServoAccess) -> ServoReply:
        try:
            if req.kind == "param" and self.modbus is not None:
                return self._modbus(req)
            return self._sdo(req)
        except BusError as exc:
            return ServoReply(None, RESULT_NO_ANSWER, f"bus error {exc.alarm.code_text}: {exc.alarm.message}")

    def _sdo(self, req: ServoAccess) -> ServoReply:
        if not callable(getattr(self.link, "sdo_read", None)):
            return ServoReply(None, RESULT_NO_ANSWER, "this bus has no SDO access")
        if not 1 <= req.station <= len(self.drives):
            return ServoReply(None, RESULT_NO_ANSWER, f"no drive at station {req.station} "
                                                      f"(the bench has {len(self.drives)}: {', '.join(self.drives)})")
        pos = req.station - 1
        index, sub = (coe_index(req.index, req.sub), 0) if req.kind == "param" else (req.index, req.sub)
        where = f"{self.drives[pos]} (station {req.station}) object 0x{index:04X}:{sub}"
        try:
            if req.value is not None:
                # Delta parameters are INTEGER32; any other object is written in the size it reads as.
                size = 4 if req.kind == "param" else len(self.link.sdo_read(pos, index, sub))
                self.link.sdo_write(pos, index, sub, encode(req.value, size))
            data = self.link.sdo_read(pos, index, sub, 4 if req.kind == "param" else 0)
        except BusError:
            raise
        except Exception as exc:  # an SDO abort from the drive: ServoParamError, SdoAbort, SdoAbortedError
            code = getattr(exc, "code", None)
            if not isinstance(code, int):
                raise
            text = SDO_TEXT.get(code, str(exc))
            return ServoReply(None, code, f"{where}: SDO abort 0x{code:08X} ({text})")
        value = struct.unpack("<i", data[:4])[0] if req.kind == "param" else decode(data)
        return ServoReply(value)

    def _modbus(self, req: ServoAccess) -> ServoReply:
        from fieldbus.modbus import ModbusError

        m = self.modbus
        m.unit = req.station
        try:
            if req.value is not None:
                m.write_param(req.index, req.sub, req.value)
            value = m.read_param(req.index, req.sub)
        except ModbusError as exc:
            return ServoReply(None, exc.code or RESULT_NO_ANSWER, f"Modbus RTU station {req.station}: {exc}")
        return ServoReply(value)
