"""Modbus RTU master for Delta ASDA servo parameters over the drive's RS-485 port (pyserial).

Parameter Pn-xx sits at register ``0x0100*n + 2*xx``; each parameter is a 32-bit pair, LOW word at
the lower address.  Function codes: 0x03 read holding registers, 0x06 write one register (the low
word only — enough for 16-bit parameters), 0x10 write multiple registers (the 32-bit pair).
Frames end with the Modbus CRC-16 (poly 0xA001 reflected, init 0xFFFF, low byte first).
An exception response raises ``ModbusError`` with the Modbus exception code.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import serial

READ_HOLDING = 0x03
WRITE_SINGLE = 0x06
WRITE_MULTIPLE = 0x10
# exception codes
ILLEGAL_FUNCTION = 0x01
ILLEGAL_ADDRESS = 0x02
ILLEGAL_VALUE = 0x03


def crc16(data: bytes) -> int:
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def frame(pdu: bytes) -> bytes:
    """ADU = PDU + CRC (low byte first)."""
    return pdu + struct.pack("<H", crc16(pdu))


def check_crc(adu: bytes) -> bool:
    return len(adu) >= 4 and crc16(adu[:-2]) == struct.unpack("<H", adu[-2:])[0]


def param_address(group: int, number: int) -> int:
    return 0x0100 * group + 2 * number


def split32(value: int) -> tuple[int, int]:
    """A signed 32-bit value as (low word, high word)."""
    u = value & 0xFFFFFFFF
    return u & 0xFFFF, u >> 16


def join32(low: int, high: int) -> int:
    u = (high << 16) | low
    return u - (1 << 32) if u & 0x80000000 else u


class ModbusError(Exception):
    def __init__(self, code: int, message: str) -> None:
        self.code = code
        super().__init__(message)


@dataclass
class ModbusRtuMaster:
    port: serial.Serial
    unit: int = 0x7F  # ASDA P3-00 factory station address

    @classmethod
    def open(cls, device: str, unit: int = 0x7F, baudrate: int = 38400, timeout: float = 0.5) -> "ModbusRtuMaster":
        # ASDA RS-485 default framing for RTU: 8 data bits, no parity, 2 stop bits (P3-02 = 6, 8N2)
        return cls(serial.Serial(device, baudrate=baudrate, bytesize=8, parity="N", stopbits=2, timeout=timeout),
                   unit)

    def close(self) -> None:
        self.port.close()

    # ---- servo parameters -----------------------------------------------------------------
    def read_param(self, group: int, number: int) -> int:
        low, high = self.read_registers(param_address(group, number), 2)
        return join32(low, high)

    def write_param(self, group: int, number: int, value: int) -> None:
        self.write_registers(param_address(group, number), list(split32(value)))

    # ---- function codes -------------------------------------------------------------------
    def read_registers(self, address: int, count: int) -> list[int]:
        reply = self._transact(struct.pack(">BBHH", self.unit, READ_HOLDING, address, count), 5 + 2 * count)
        return list(struct.unpack(f">{count}H", reply[3:3 + 2 * count]))

    def write_register(self, address: int, value: int) -> None:
        self._transact(struct.pack(">BBHH", self.unit, WRITE_SINGLE, address, value & 0xFFFF), 8)

    def write_registers(self, address: int, values: list[int]) -> None:
        pdu = struct.pack(">BBHHB", self.unit, WRITE_MULTIPLE, address, len(values), 2 * len(values))
        pdu += struct.pack(f">{len(values)}H", *values)
        self._transact(pdu, 8)

    def _transact(self, request: bytes, reply_len: int) -> bytes:
        self.port.reset_input_buffer()
        self.port.write(frame(request))
        self.port.flush()
        head = self.port.read(2)
        if len(head) < 2:
            raise ModbusError(0, f"no answer from station {self.unit} (timeout)")
        if head[1] & 0x80:  # exception response: unit, fc|0x80, code, crc
            rest = self.port.read(3)
            adu = head + rest
            if not check_crc(adu):
                raise ModbusError(0, "exception reply with a bad CRC")
            raise ModbusError(adu[2], f"station {self.unit} answered exception 0x{adu[2]:02X} to function "
                                      f"0x{request[1]:02X}")
        adu = head + self.port.read(reply_len - 2)
        if len(adu) < reply_len:
            raise ModbusError(0, f"short answer from station {self.unit}: {len(adu)} of {reply_len} bytes")
        if not check_crc(adu):
            raise ModbusError(0, f"bad CRC in the answer from station {self.unit}")
        if adu[0] != self.unit or adu[1] != request[1]:
            raise ModbusError(0, f"answer for station {adu[0]} function 0x{adu[1]:02X} does not match the request")
        return adu
