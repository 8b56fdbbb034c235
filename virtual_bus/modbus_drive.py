"""A simulated Delta drive answering Modbus RTU on a pseudo-terminal, as on its RS-485 port.

``PtyModbusDrive(params).start()`` opens a pty pair (os.openpty), answers requests on the master
side in a thread, and exposes ``device`` (the slave side's path) for a pyserial client.  The
register map is ``fieldbus.modbus``'s: Pn-xx at 0x0100*n + 2*xx, low word first; a write to
the high word commits the 32-bit value (a 0x10 write of both words commits at once).
"""

from __future__ import annotations

import os
import select
import struct
import threading
import tty
from dataclasses import dataclass, field

from fieldbus.modbus import (ILLEGAL_ADDRESS, ILLEGAL_FUNCTION, ILLEGAL_VALUE, READ_HOLDING, WRITE_MULTIPLE,
                             WRITE_SINGLE, check_crc, frame, join32, split32)
from virtual_bus.servo_params import ServoParamError, ServoParams


@dataclass
class PtyModbusDrive:
    params: ServoParams
    unit: int = 0x7F
    device: str = ""
    requests: int = 0
    _master: int = -1
    _slave: int = -1
    _stop: threading.Event = field(default_factory=threading.Event)
    _thread: threading.Thread | None = None

    def start(self) -> "PtyModbusDrive":
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # binary frames: no echo, no line discipline
        self.device = os.ttyname(self._slave)
        self._thread = threading.Thread(target=self._serve, name="modbus-drive", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(1.0)
        for fd in (self._master, self._slave):
            if fd >= 0:
                os.close(fd)
        self._master = self._slave = -1

    def __enter__(self) -> "PtyModbusDrive":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # ---- serving --------------------------------------------------------------------------
    def _serve(self) -> None:
        buf = b""
        while not self._stop.is_set():
            r, _, _ = select.select([self._master], [], [], 0.05)
            if not r:
                buf = b""  # an inter-frame silence ends any partial frame (RTU's 3.5-character rule)
                continue
            try:
                buf += os.read(self._master, 256)
            except OSError:
                return
            while (n := _frame_length(buf)) and len(buf) >= n:
                adu, buf = buf[:n], buf[n:]
                reply = self.handle(adu)
                if reply:
                    os.write(self._master, reply)

    def handle(self, adu: bytes) -> bytes | None:
        """One request ADU → reply ADU (None: not for this station, or a corrupt frame)."""
        if not check_crc(adu) or adu[0] != self.unit:
            return None
        self.requests += 1
        fc = adu[1]
        try:
            if fc == READ_HOLDING:
                addr, count = struct.unpack(">HH", adu[2:6])
                regs = [self._read_register(addr + k) for k in range(count)]
                return frame(bytes([self.unit, fc, 2 * count]) + struct.pack(f">{count}H", *regs))
            if fc == WRITE_SINGLE:
                addr, value = struct.unpack(">HH", adu[2:6])
                self._write_registers(addr, [value])
                return frame(adu[:6])
            if fc == WRITE_MULTIPLE:
                addr, count = struct.unpack(">HH", adu[2:6])
                values = list(struct.unpack(f">{count}H", adu[7:7 + 2 * count]))
                self._write_registers(addr, values)
                return frame(adu[:6])
            return self._exception(fc, ILLEGAL_FUNCTION)
        except ServoParamError as exc:
            return self._exception(fc, ILLEGAL_ADDRESS if exc.code == 0x06020000 else ILLEGAL_VALUE)

    def _exception(self, fc: int, code: int) -> bytes:
        return frame(bytes([self.unit, fc | 0x80, code]))

    @staticmethod
    def _param_of(address: int) -> tuple[tuple[int, int], int]:
        """Register address → ((group, number), 0 for the low word / 1 for the high word)."""
        group, offset = address >> 8, address & 0xFF
        return (group, offset // 2), offset % 2

    def _read_register(self, address: int) -> int:
        param, word = self._param_of(address)
        low, high = split32(self.params.read(param))
        return high if word else low

    def _write_registers(self, address: int, values: list[int]) -> None:
        pending: dict[tuple[int, int], list[int]] = {}
        for k, v in enumerate(values):
            param, word = self._param_of(address + k)
            if param not in pending:
                pending[param] = list(split32(self.params.read(param)))
            pending[param][word] = v
        for param, (low, high) in pending.items():
            # a lone low-word write (function 0x06) carries a 16-bit value: sign-extend it
            single = len(values) == 1 and (address & 1) == 0
            value = join32(low, 0xFFFF if low & 0x8000 else 0) if single else join32(low, high)
            self.params.write(param, value)


def _frame_length(buf: bytes) -> int | None:
    """Length of the request ADU at the start of buf, once enough of it is there to tell."""
    if len(buf) < 2:
        return None
    fc = buf[1]
    if fc in (READ_HOLDING, WRITE_SINGLE):
        return 8
    if fc == WRITE_MULTIPLE:
        return 9 + buf[6] if len(buf) >= 7 else None
    return 4  # unknown function: unit, fc, crc → answered with ILLEGAL_FUNCTION
