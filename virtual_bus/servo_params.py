"""Delta ASDA servo parameters P0-xx … P6-xx of a simulated drive, reachable three ways.

- CoE / CANopen SDO: parameter Pn-xx is object ``0x2000 + n*0x100 + xx``, sub-index 0, as the
  ASDA-A2-E / A3-E EtherCAT drives map them; values travel as 32-bit little-endian integers.
- RS-485 Modbus RTU: register address ``0x0100*n + 2*xx``; every parameter is a 32-bit pair of
  16-bit registers, LOW word at the lower address (Delta's order for ASDA parameters).
- Python: ``read("P2-00")`` / ``write("P2-00", 50)``.

The table holds a representative subset (gains, gear ratio, limits, communication settings) with
ranges; values a drive would reject (unknown parameter, read-only, out of range) raise
``ServoParamError`` carrying the CoE abort code a real drive answers with.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Callable
from dataclasses import dataclass, field

# CoE / CiA 301 SDO abort codes
ABORT_NO_OBJECT = 0x06020000
ABORT_READ_ONLY = 0x06010002
ABORT_RANGE = 0x06090030
ABORT_LENGTH = 0x06070010


class ServoParamError(Exception):
    def __init__(self, code: int, message: str) -> None:
        self.code = code
        super().__init__(message)


@dataclass(frozen=True)
class ParamDef:
    group: int
    number: int
    name: str
    default: int
    low: int
    high: int
    writable: bool = True

    @property
    def label(self) -> str:
        return f"P{self.group}-{self.number:02d}"


# A representative ASDA subset; defaults follow the drives' factory values where they are commonly
# quoted, ranges are the parameter's documented span (32-bit where the drive uses one).
ASDA_PARAMS: tuple[ParamDef, ...] = (
    ParamDef(0, 0, "firmware version", 0x1011, 0, 0xFFFF, writable=False),
    ParamDef(0, 1, "current alarm code", 0, 0, 0xFFFF, writable=False),
    ParamDef(0, 2, "drive status display", 0, 0, 127),
    ParamDef(1, 1, "control mode and output direction", 0x000C, 0, 0x110F),
    ParamDef(1, 9, "internal speed command 1 (0.1 rpm)", 1000, -60000, 60000),
    ParamDef(1, 12, "internal torque limit 1 (%)", 100, -500, 500),
    ParamDef(1, 44, "electronic gear numerator N1", 16777216, 1, 536870911),
    ParamDef(1, 45, "electronic gear denominator M", 100000, 1, 2147483647),
    ParamDef(1, 55, "maximum speed limit (rpm)", 5000, 0, 6000),
    ParamDef(2, 0, "position loop gain KPP (rad/s)", 35, 0, 2047),
    ParamDef(2, 2, "position feed-forward gain PFG (%)", 50, 0, 100),
    ParamDef(2, 4, "speed loop gain KVP (rad/s)", 500, 0, 8191),
    ParamDef(2, 6, "speed integral compensation KVI (rad/s)", 100, 0, 1023),
    ParamDef(2, 25, "resonance suppression low-pass filter (0.1 ms)", 2, 0, 100),
    ParamDef(3, 0, "RS-485 station address", 0x7F, 1, 0x7F),
    ParamDef(3, 1, "transmission speed", 0x0203, 0, 0x0055),
    ParamDef(3, 2, "Modbus protocol", 6, 6, 8),
    ParamDef(4, 5, "JOG speed (rpm)", 20, 0, 5000),
    ParamDef(5, 8, "forward software limit (PUU)", 2147483647, -2147483648, 2147483647),
    ParamDef(5, 9, "reverse software limit (PUU)", -2147483648, -2147483648, 2147483647),
    ParamDef(6, 0, "homing definition", 0, 0, 0x10FFFFFF),
)

_LABEL = re.compile(r"^P?([0-6])[-.]?(\d{1,2})$", re.IGNORECASE)


def parse_param(text: str) -> tuple[int, int]:
    """'P2-00', 'p2.0', '2-00' → (2, 0); ValueError on anything else."""
    m = _LABEL.match(text.strip())
    if not m:
        raise ValueError(f"servo parameter {text!r}: expected Pn-xx with n 0-6 (e.g. P2-00)")
    return int(m.group(1)), int(m.group(2))


def coe_index(group: int, number: int) -> int:
    return 0x2000 + group * 0x100 + number


def coe_objects() -> list[tuple[int, ParamDef]]:
    """(object index, definition) of every parameter, for a slave that lists them in its object
    dictionary (virtual EtherCAT and CANopen drives); values stay in the drive's `ServoParams`."""
    return [(coe_index(p.group, p.number), p) for p in ASDA_PARAMS]


def modbus_address(group: int, number: int) -> int:
    return 0x0100 * group + 2 * number


@dataclass
class ServoParams:
    values: dict[tuple[int, int], int] = field(default_factory=lambda: {(p.group, p.number): p.default
                                                                      for p in ASDA_PARAMS})
    on_write: Callable[[int, int, int], None] | None = None  # (group, number, value): the drive reacts

    @staticmethod
    def definition(group: int, number: int) -> ParamDef:
        for p in ASDA_PARAMS:
            if p.group == group and p.number == number:
                return p
        raise ServoParamError(ABORT_NO_OBJECT, f"P{group}-{number:02d} does not exist on this drive")

    def read(self, param: str | tuple[int, int]) -> int:
        g, n = parse_param(param) if isinstance(param, str) else param
        self.definition(g, n)
        return self.values[(g, n)]

    def write(self, param: str | tuple[int, int], value: int, *, force: bool = False) -> None:
        g, n = parse_param(param) if isinstance(param, str) else param
        d = self.definition(g, n)
        if not d.writable and not force:
            raise ServoParamError(ABORT_READ_ONLY, f"{d.label} ({d.name}) is read-only")
        if not d.low <= value <= d.high:
            raise ServoParamError(ABORT_RANGE, f"{d.label} ({d.name}) must be {d.low}..{d.high}, got {value}")
        self.values[(g, n)] = int(value)
        if self.on_write is not None:
            self.on_write(g, n, int(value))

    # ---- CoE object dictionary view -------------------------------------------------------
    @staticmethod
    def from_index(index: int, sub: int) -> tuple[int, int]:
        g, n = (index - 0x2000) >> 8, (index - 0x2000) & 0xFF
        if not 0x2000 <= index <= 0x26FF or sub != 0:
            raise ServoParamError(ABORT_NO_OBJECT, f"object 0x{index:04X}:{sub} is not a servo parameter")
        return g, n

    def sdo_read(self, index: int, sub: int = 0) -> bytes:
        return struct.pack("<i", self.read(self.from_index(index, sub)))

    def sdo_write(self, index: int, sub: int, data: bytes) -> None:
        if len(data) not in (2, 4):
            raise ServoParamError(ABORT_LENGTH, f"object 0x{index:04X}: {len(data)} data bytes")
        value = struct.unpack("<h" if len(data) == 2 else "<i", data)[0]
        self.write(self.from_index(index, sub), value)
