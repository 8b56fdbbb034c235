"""EMCY frames ↔ Delta alarms.

An EMCY carries a CiA 301/402 error code (16 bit), the error register (0x1001) and five
manufacturer bytes. Delta ASDA drives put their own alarm number (the one the drive panel shows,
e.g. AL009) in the first two manufacturer bytes; the NC shows it as 0xF002 with that number
(NC5 App. A, 0xF002). EMCYs without a Delta number are mapped by their CiA error class.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from nc.alarms import SERVO_ALARM, Alarm

# Delta ASDA alarm → CiA 402 EMCY error code the simulated drive reports it with.
DELTA_TO_CIA: dict[int, int] = {
    0x0007: 0x8400,  # overspeed → velocity speed controller
    0x0009: 0x8611,  # excessive position deviation → following error
    0x0013: 0x5441,  # emergency stop input → drive interlock
    0x0014: 0xFF00,  # reverse inhibit limit (device specific)
    0x0015: 0xFF00,  # forward inhibit limit (device specific)
    0x0180: 0x8130,  # heartbeat event (ASDA-A3 AL180: no master heartbeat within 0x1016) → heartbeat error
}

CIA_TEXT: dict[int, str] = {
    0x0000: "error reset or no error", 0x1000: "generic error", 0x2310: "continuous over-current",
    0x3210: "DC link over-voltage", 0x4310: "drive temperature", 0x5441: "interlock (emergency stop)",
    0x8110: "CAN overrun", 0x8120: "CAN error passive", 0x8130: "life guard or heartbeat error",
    0x8140: "recovered from bus off", 0x8210: "PDO not processed due to length error",
    0x8400: "velocity speed controller", 0x8611: "following error", 0xFF00: "device specific",
}

ALARM_COMMUNICATION = 0x0601  # axis: communication disconnected after established (NC5 App. A)
ALARM_PDO_MAPPING = 0x141E  # kernel: system PDO mapping mismatch


@dataclass(frozen=True)
class Emcy:
    code: int
    register: int
    delta_alarm: int  # manufacturer bytes 0-1, 0 if none

    @classmethod
    def decode(cls, data: bytes) -> "Emcy":
        raw = bytes(data).ljust(8, b"\0")
        code, register, delta = struct.unpack_from("<HBH", raw)
        return cls(code, register, delta)

    def encode(self) -> bytes:
        return struct.pack("<HBH3x", self.code, self.register, self.delta_alarm)

    @property
    def text(self) -> str:
        return CIA_TEXT.get(self.code, CIA_TEXT.get(self.code & 0xFF00, "unlisted"))


def emcy_for_delta(delta_alarm: int) -> Emcy:
    """The EMCY a drive sends when it raises this Delta alarm (error register bit 0: generic)."""
    return Emcy(DELTA_TO_CIA.get(delta_alarm, 0xFF00), 0x01, delta_alarm)


def emcy_alarm(emcy: Emcy, node_id: int, axis: str) -> Alarm | None:
    """The Delta alarm an EMCY raises, or None for 'error reset'."""
    if emcy.code == 0x0000:
        return None
    where = f"EMCY 0x{emcy.code:04X} ({emcy.text}) from CANopen node {node_id} ({axis})"
    if emcy.delta_alarm:
        return Alarm(SERVO_ALARM, f"{where}: Delta servo alarm AL{emcy.delta_alarm:03X}", axis=axis,
                     info=emcy.delta_alarm)
    if emcy.code & 0xFF00 == 0x8100:
        return Alarm(ALARM_COMMUNICATION, where, axis=axis)
    if emcy.code & 0xFF00 == 0x8200:
        return Alarm(ALARM_PDO_MAPPING, where, axis=axis)
    return Alarm(SERVO_ALARM, where, axis=axis)
