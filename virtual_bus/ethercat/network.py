"""The virtual line: a chain of software ESCs behind one raw socket (AF_PACKET, EtherType 0x88A4).

A frame walks the chain in order; every slave processes every datagram (auto-increment
addresses count down as they pass, working counters go up), then the frame goes back to the
master with the locally administered bit set in the source MAC, as an ESC's port 0 returns it.
"""

from __future__ import annotations

import errno
import socket
import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from virtual_bus.ethercat.esc import Esc
from virtual_bus.ethercat.registers import (APRD, APRW, APWR, ARMW, BRD, BRW, BWR, FPRD, FPRW, FPWR, FRMW, LRD, LRW,
                                            LWR, R_AL_CODE)
from virtual_bus.ethercat.faults import Fault

ETH_P_ECAT = 0x88A4
_HEAD = struct.Struct("<BBHHH")  # datagram header: cmd, index, ADP, ADO, length (+ flags)
_U16 = struct.Struct("<H")
_READS = {APRD, FPRD, BRD}
_WRITES = {APWR, FPWR, BWR}
_RW = {APRW, FPRW, BRW}
_FIXED = {FPRD, FPWR, FPRW, FRMW}


@dataclass
class Chain:
    slaves: Sequence[Esc]
    faults: list[Fault] = field(default_factory=list)
    pd_frames: int = 0  # process-data frames seen (frames with a logical datagram)
    frames: int = 0
    log: Callable[[str], None] = lambda msg: None
    _applied: set[int] = field(default_factory=set)
    _left: set[int] = field(default_factory=set)

    def __post_init__(self) -> None:
        for f in self.faults:  # bring-up refusals are the slave's own answer, not keyed to frames
            if f.kind == "refuse" and f.slave < len(self.slaves):
                self.slaves[f.slave].refuse[f.at] = int(f.arg)

    # ---- faults ---------------------------------------------------------------------------
    def _fault_step(self, is_pd: bool) -> tuple[bool, float]:
        """Apply faults due at this frame. Returns (drop the frame, delay in s)."""
        drop, delay = False, 0.0
        n = self.pd_frames
        for k, f in enumerate(self.faults):
            on = f.active(n) and (is_pd or f.kind == "leave")
            if f.kind == "drop" and on and is_pd:
                drop = True
            elif f.kind == "late" and on and is_pd:
                delay = max(delay, f.arg / 1000.0)
            elif f.kind == "leave":
                if on and f.slave not in self._left:
                    self._left.add(f.slave)
                    self.log(f"slave {f.slave} left the line at frame {n}")
                elif not on and f.slave in self._left and n >= f.at:
                    self._left.discard(f.slave)
                    self.log(f"slave {f.slave} back on the line at frame {n}")
            elif f.kind == "drift":
                if on and is_pd and f.slave < len(self.slaves):
                    self.slaves[f.slave].clock_base_ns += int(f.arg)
            elif f.kind == "wkc" and f.slave < len(self.slaves):
                self.slaves[f.slave].wkc_fault = on
            elif k not in self._applied and n >= f.at and f.slave < len(self.slaves) and is_pd:
                self._applied.add(k)
                s = self.slaves[f.slave]
                if f.kind == "alerr":
                    s.al_error(int(f.arg), min(s.al_state, 4))
                    self.log(f"slave {f.slave} AL error 0x{int(f.arg):04X} at frame {n}")
                elif f.kind == "drivefault":
                    app = s.app
                    if hasattr(app, "drive"):
                        app.drive.external_fault = int(f.arg)
                        self.log(f"slave {f.slave} drive fault 0x{int(f.arg):04X} at frame {n}")
        return drop, delay

    def reachable(self) -> Sequence[Esc]:
        """Slaves the frame reaches: a slave that left the line cuts off everything behind it."""
        if not self._left:
            return self.slaves  # the usual frame: the whole line, no list built
        out = []
        for i, s in enumerate(self.slaves):
            if i in self._left:
                break
            out.append(s)
        return out

    # ---- frames ---------------------------------------------------------------------------
    def process(self, frame: bytes | memoryview) -> tuple[bytes | None, float]:
        """Process one Ethernet frame; returns (answer or None if lost, delay in s)."""
        if len(frame) < 16 or frame[12] != ETH_P_ECAT >> 8 or frame[13] != ETH_P_ECAT & 0xFF:
            return None, 0.0
        hdr = _U16.unpack_from(frame, 14)[0]
        if hdr >> 12 != 1:
            return None, 0.0
        buf = bytearray(frame)
        view = memoryview(buf)
        # The datagrams are found once per frame (their lengths do not change on the way); frames with
        # a logical datagram are the process-data cycle.
        is_pd, pos, end, size = False, 16, min(16 + (hdr & 0x7FF), len(buf)), len(buf)
        grams = []
        while pos + 12 <= size:
            cmd, _idx, adp, ado, ln = _HEAD.unpack_from(buf, pos)
            n = ln & 0x7FF
            if LRD <= cmd <= LRW:
                is_pd = True
            wpos = pos + 10 + n
            if wpos + 2 <= size:
                grams.append((pos, cmd, adp | (ado << 16), wpos, view[pos + 10:wpos]))
            pos = wpos + 2
            if not ln & 0x8000 or wpos + 2 > size:
                break
        self.frames += 1
        drop, delay = self._fault_step(is_pd) if self.faults else (False, 0.0)
        if is_pd:
            self.pd_frames += 1
        if drop:
            return None, 0.0
        line = self.reachable() if self._left else self.slaves
        now = time.monotonic_ns()
        count = len(line)
        wkc = [0] * len(grams)  # working counter increments, added to the frame once every slave has seen it
        for i, s in enumerate(line):
            s.position, s.chain_len, s.frame_ns = i, count, now
            s.check_watchdog(now)
            # one slave's pass over the frame's datagrams, in order
            for k, (pos, cmd, logical, _wpos, data) in enumerate(grams):
                if LRD <= cmd <= LRW:
                    inc = s.logical(cmd, logical, data)  # the address is not changed on the way
                elif cmd == FRMW:  # the DC time every cycle's frame carries; a fixed address is not changed either
                    inc = s.frmw(logical & 0xFFFF, logical >> 16, data)
                else:
                    adp = _U16.unpack_from(buf, pos + 2)[0]  # auto-increment addresses count down on the way
                    inc, new_adp = self._datagram(s, cmd, adp, logical >> 16, data)
                    if new_adp != adp:
                        _U16.pack_into(buf, pos + 2, new_adp)
                if inc:
                    wkc[k] += inc
            s.idle()
        for (_pos, _cmd, _logical, wpos, _data), inc in zip(grams, wkc):
            if inc:
                _U16.pack_into(buf, wpos, (_U16.unpack_from(buf, wpos)[0] + inc) & 0xFFFF)
        buf[6] |= 0x02
        return bytes(buf), delay

    @staticmethod
    def _datagram(s: Esc, cmd: int, adp: int, ado: int, data: memoryview) -> tuple[int, int]:
        n = len(data)
        if cmd in _FIXED:  # first: the FRMW that distributes DC time rides in every cycle's frame
            addressed = s.fixed_address(adp)
            new_adp = adp
        elif cmd in (APRD, APWR, APRW, ARMW):
            addressed = adp == 0
            new_adp = (adp + 1) & 0xFFFF
        elif cmd in (BRD, BWR, BRW):
            addressed = True
            new_adp = (adp + 1) & 0xFFFF
        elif cmd in (LRD, LWR, LRW):
            return s.logical(cmd, adp | (ado << 16), data), adp
        else:
            return 0, adp
        inc = 0
        if cmd in (ARMW, FRMW):
            if addressed:
                got = s.read(ado, n)
                if got is not None:
                    data[:] = got
                    inc = 1
            else:
                s.dc_write(ado, bytes(data))
                inc = 1
            return (0 if s.wkc_fault else inc), new_adp
        if not addressed:
            return 0, new_adp
        if cmd in _READS:
            got = s.read(ado, n)
            if got is not None:
                if cmd == BRD:
                    data[:] = bytes(a | b for a, b in zip(data, got))
                else:
                    data[:] = got
                inc = 1
        elif cmd in _WRITES:
            inc = 1 if s.write(ado, bytes(data)) else 0
        elif cmd in _RW:
            old = s.read(ado, n)
            ok = s.write(ado, bytes(data))
            if old is not None:
                data[:] = old if cmd != BRW else bytes(a | b for a, b in zip(data, old))
                inc += 1
            inc += 2 if ok else 0
        return (0 if s.wkc_fault else inc), new_adp

    def tick(self) -> None:
        """Between frames: the process-data watchdog keeps running."""
        now = time.monotonic_ns()
        for s in self.reachable():
            s.check_watchdog(now)
            s.coast(now)
            while s.events:
                self.log(f"{s.name}: {s.events.pop(0)}")

    def states(self) -> list[tuple[str, int, int]]:
        return [(s.name, s.al_state, s.u16(R_AL_CODE)) for s in self.slaves]


SOL_PACKET, PACKET_IGNORE_OUTGOING = 263, 23  # linux/socket.h, linux/if_packet.h (Linux 4.20+)
IDLE_TICK_S = 0.01  # without frames, the watchdog is looked at this often


class RawSocketLine:
    """Serves a `Chain` on an interface until stopped.

    One `recv_into` and one `send` a frame (issue 17): the kernel's receive timeout paces the idle
    watchdog ticks instead of a select() per frame, frames land in a buffer allocated once, and no
    source address is asked for (CPython's recvfrom looks up the interface name of every AF_PACKET
    frame). The kernel drops the copies of our own answers where it can (PACKET_IGNORE_OUTGOING);
    elsewhere recvfrom's packet type still tells them apart."""

    def __init__(self, chain: Chain, iface: str) -> None:
        self.chain = chain
        self.iface = iface
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ECAT))
        self.sock.bind((iface, ETH_P_ECAT))
        usec = int(IDLE_TICK_S * 1e6)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, struct.pack("ll", usec // 1_000_000, usec % 1_000_000))
        try:
            self.sock.setsockopt(SOL_PACKET, PACKET_IGNORE_OUTGOING, 1)
            self.ignores_outgoing = True
        except OSError:
            self.ignores_outgoing = False
        self.running = True
        self.dropped = 0  # answers the kernel refused (ENOBUFS/EAGAIN): frames lost on the wire

    def serve(self, duration: float | None = None) -> None:
        deadline = None if duration is None else time.monotonic() + duration
        sock, chain = self.sock, self.chain
        buf = bytearray(2048)
        view = memoryview(buf)
        while self.running and (deadline is None or time.monotonic() < deadline):
            try:
                if self.ignores_outgoing:
                    n = sock.recv_into(buf)
                else:
                    n, addr = sock.recvfrom_into(buf)
                    if len(addr) > 2 and addr[2] == socket.PACKET_OUTGOING:
                        continue
            except BlockingIOError:  # the receive timeout: no frame for IDLE_TICK_S
                chain.tick()
                continue
            # the frame is a view of the receive buffer: Chain.process copies it before anything else
            answer, delay = chain.process(view[:n])
            if answer is None:
                continue
            if delay:
                time.sleep(delay)
            try:
                sock.send(answer)
            except OSError as exc:
                # The interface's queue was full (a master stalled for a while on a loaded host): on a real
                # line that frame is lost, the master's working counter says so and its own loss handling
                # (retries, then alarm 0x0601) decides, as for any dropped frame. Not the simulator's end.
                if exc.errno not in (errno.ENOBUFS, errno.EAGAIN):
                    raise
                self.dropped += 1

    def close(self) -> None:
        self.running = False
        self.sock.close()
