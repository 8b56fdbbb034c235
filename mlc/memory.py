"""MLC device memory: M bits, D words (16-bit, with 32-bit integer and float pairs), the
user alarm bits A0–A511, and the X (input) / Y (output) bits of the remote I/O modules
(X0–X1023, Y0–Y1023, numbered decimally like M and D; see mlc/remote_io.py for how modules map).

Word order of a pair (NC5 App. B never states it, ambiguity B4): by default the LOW word sits at
the LOWER address (``D31048`` = low 16 bits, ``D31049`` = high 16 bits), which is how Delta's DVP/AS
PLCs store 32-bit ``DD`` devices. ``word_order="high-first"`` swaps it for benches that need it.
Floats are IEEE-754 single precision in the same two words.
"""

from __future__ import annotations

import re
import struct
import sys
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

M_SIZE = 100_000  # M0 … M99999 (covers the special blocks M2xxxx … M5xxxx)
D_SIZE = 100_000
A_SIZE = 512  # user-defined alarms A0 … A511 (NC5 App. A.1)
_NO_ALARMS = bytes(A_SIZE)
XY_SIZE = 1024  # remote I/O points X0 … X1023 / Y0 … Y1023 (docs/decisions/mlc.md, D11)

_ADDR = re.compile(r"^\s*([MDAXY])\s*(\d{1,5})\s*$", re.IGNORECASE)

_F32, _U32 = struct.Struct("<f"), struct.Struct("<I")  # compiled once: f32 ↔ raw pairs are per-scan work

_F32N = tuple(struct.Struct(f"<{k}f") for k in range(33))  # k floats in a row (the drive status)

WordOrder = Literal["low-first", "high-first"]


class DeviceError(ValueError):
    """An address that does not name a device."""


def parse_address(text: str) -> tuple[str, int]:
    """``"M21000"`` → ``("M", 21000)``; raises DeviceError for anything else."""
    m = _ADDR.match(text)
    if not m:
        raise DeviceError(f"{text!r} is not a device address (M<n>, D<n>, A<n>, X<n> or Y<n>)")
    kind, n = m.group(1).upper(), int(m.group(2))
    size = {"M": M_SIZE, "D": D_SIZE, "A": A_SIZE, "X": XY_SIZE, "Y": XY_SIZE}[kind]
    if n >= size:
        raise DeviceError(f"{text!r} is outside the {kind} device range 0…{size - 1}")
    return kind, n


@dataclass
class DeviceMemory:
    word_order: WordOrder = "low-first"
    m: bytearray = field(default_factory=lambda: bytearray(M_SIZE))
    d: np.ndarray = field(default_factory=lambda: np.zeros(D_SIZE, dtype=np.uint16))
    a: bytearray = field(default_factory=lambda: bytearray(A_SIZE))
    x: bytearray = field(default_factory=lambda: bytearray(XY_SIZE))  # remote inputs, written by the bus
    y: bytearray = field(default_factory=lambda: bytearray(XY_SIZE))  # remote outputs, written by the MLC

    def __post_init__(self) -> None:
        # Word and byte views of `d` for the per-scan accessors: a memoryview item is a plain int and
        # costs a third of a numpy scalar read or write; pairs pack straight into the bytes.
        self.words = memoryview(self.d).cast("B").cast("H")
        self._b = memoryview(self.d).cast("B")
        self._low_first = self.word_order == "low-first"
        self._f32_in_place = self._low_first and sys.byteorder == "little"

    # ---- bits ---------------------------------------------------------------------------
    def bit(self, n: int) -> bool:
        return bool(self.m[n])

    def set_bit(self, n: int, on: bool | int = True) -> None:
        self.m[n] = 1 if on else 0

    def alarm(self, n: int) -> bool:
        return bool(self.a[n])

    def set_alarm(self, n: int, on: bool = True) -> None:
        if not 0 <= n < A_SIZE:
            raise DeviceError(f"A{n} is outside the user alarm range A0…A{A_SIZE - 1}")
        self.a[n] = 1 if on else 0

    # ---- remote I/O images: `count` consecutive X or Y bits as an integer, point 0 = bit 0 --------
    def bits(self, kind: str, first: int, count: int) -> int:
        area = self.x if kind == "X" else self.y
        return sum(1 << k for k in range(count) if area[first + k])

    def set_bits(self, kind: str, first: int, count: int, value: int) -> None:
        area = self.x if kind == "X" else self.y
        for k in range(count):
            area[first + k] = value >> k & 1

    def no_alarms(self) -> bool:
        """No user alarm active: the usual case, read twice per scan, so compared at C speed with zeros
        (one memcmp, a tenth of counting the zeros)."""
        a = self.a
        return a == _NO_ALARMS if len(a) == A_SIZE else a.count(0) == len(a)

    def active_alarms(self) -> list[int]:
        if self.no_alarms():
            return []
        return [i for i, v in enumerate(self.a) if v]

    # ---- single words ---------------------------------------------------------------------
    def u16(self, n: int) -> int:
        return self.words[n]

    def s16(self, n: int) -> int:
        v = self.words[n]
        return v - 0x10000 if v & 0x8000 else v

    def set_u16(self, n: int, value: int) -> None:
        """Stores the low 16 bits; a negative value is kept as its two's complement."""
        self.words[n] = int(value) & 0xFFFF

    set_s16 = set_u16

    def word_bytes(self, n: int, count: int) -> bytes:
        """The raw bytes of D<n>…D<n+count-1> (to compare a range with what it held before)."""
        return self._b[2 * n:2 * (n + count)].tobytes()

    # ---- pairs ----------------------------------------------------------------------------
    def _pair(self, n: int) -> tuple[int, int]:
        w = self.words
        lo, hi = w[n], w[n + 1]
        return (lo, hi) if self._low_first else (hi, lo)

    def _set_pair(self, n: int, raw: int) -> None:
        lo, hi = raw & 0xFFFF, (raw >> 16) & 0xFFFF
        w = self.words
        if self._low_first:
            w[n], w[n + 1] = lo, hi
        else:
            w[n], w[n + 1] = hi, lo

    def u32(self, n: int) -> int:
        lo, hi = self._pair(n)
        return lo | (hi << 16)

    def s32(self, n: int) -> int:
        v = self.u32(n)
        return v - 0x1_0000_0000 if v & 0x8000_0000 else v

    def set_u32(self, n: int, value: int) -> None:
        self._set_pair(n, int(value) & 0xFFFF_FFFF)

    set_s32 = set_u32

    def f32(self, n: int) -> float:
        if self._f32_in_place and 0 <= n < D_SIZE - 1:  # the low word at n: the float's bytes in place
            return _F32.unpack_from(self._b, 2 * n)[0]
        return _F32.unpack(_U32.pack(self.u32(n)))[0]

    def set_f32(self, n: int, value: float) -> None:
        if self._f32_in_place and 0 <= n < D_SIZE - 1:
            _F32.pack_into(self._b, 2 * n, float(value))
        else:
            self._set_pair(n, _U32.unpack(_F32.pack(float(value)))[0])

    def set_f32s(self, n: int, values: list[float]) -> None:
        """Consecutive floats from D<n> (pairs n, n+2, …): one packed write when the bytes lie in place."""
        k = len(values)
        if self._f32_in_place and 0 <= n and n + 2 * k <= D_SIZE:
            fmt = _F32N[k] if k < len(_F32N) else struct.Struct(f"<{k}f")
            fmt.pack_into(self._b, 2 * n, *values)
        else:
            for i, v in enumerate(values):
                self.set_f32(n + 2 * i, v)

    # ---- by name --------------------------------------------------------------------------
    def get(self, address: str) -> int:
        """The raw value of a device by name: a bit as 0/1, a D word as unsigned 16 bits."""
        kind, n = parse_address(address)
        if kind == "M":
            return self.m[n]
        if kind == "A":
            return self.a[n]
        if kind in "XY":
            return (self.x if kind == "X" else self.y)[n]
        return int(self.d[n])

    def put(self, address: str, value: int) -> None:
        kind, n = parse_address(address)
        if kind == "M":
            self.set_bit(n, bool(value))
        elif kind == "A":
            self.set_alarm(n, bool(value))
        elif kind in "XY":
            (self.x if kind == "X" else self.y)[n] = 1 if value else 0
        else:
            self.set_u16(n, int(value))
