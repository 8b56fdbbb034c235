"""Bus captures for `hil run --capture FILE`: what a bench engineer opens in Wireshark or a CAN tool.

EtherCAT: every EtherCAT frame on the master's interface (out and in) as pcapng, link type DLT_EN10MB
(EtherCAT rides in Ethernet frames with ethertype 0x88A4, which Wireshark's ecat dissector decodes). Other
traffic the host puts on that interface (an IPv6 router solicitation when the link comes up, LLDP) is
left out: it is not the bus's.
The capture runs as its own process (`python -m fieldbus.capture IFACE FILE`) on an AF_PACKET
socket, so it never takes the cyclic process's CPU or GIL.

CAN (CANopen): every frame the master sends or receives, through python-can's writers chosen by the
file's suffix (.asc, .blf, .log), stamped with the link's clock (simulated time in lock-step).
"""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

ETH_P_ALL = 0x0003
ETHERTYPE_ECAT = b"\x88\xa4"
PACKET_OUTGOING = 4
LINKTYPE_ETHERNET = 1
CAN_SUFFIXES = (".asc", ".blf", ".log")
ETHERCAT_SUFFIXES = (".pcapng",)


class PcapngWriter:
    """Section header, one Ethernet interface (ns timestamps), one enhanced packet block per frame
    (pcapng spec, IETF draft-ietf-opsawg-pcapng) with its direction in epb_flags."""

    def __init__(self, out: BinaryIO, iface: str, snaplen: int = 65535) -> None:
        self.out = out
        shb = struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1)
        self._block(0x0A0D0D0A, shb)
        opts = _option(2, iface.encode()) + _option(9, bytes([9])) + _option(0, b"")  # if_name, if_tsresol 1e-9
        self._block(0x00000001, struct.pack("<HHI", LINKTYPE_ETHERNET, 0, snaplen) + opts)

    def frame(self, data: bytes, t_ns: int, outbound: bool | None = None) -> None:
        head = struct.pack("<IIIII", 0, t_ns >> 32, t_ns & 0xFFFFFFFF, len(data), len(data))
        opts = b""
        if outbound is not None:  # epb_flags bits 0-1: 01 inbound, 10 outbound
            opts = _option(2, struct.pack("<I", 2 if outbound else 1)) + _option(0, b"")
        self._block(0x00000006, head + _pad(data) + opts)

    def _block(self, kind: int, body: bytes) -> None:
        n = 12 + len(body)
        self.out.write(struct.pack("<II", kind, n) + body + struct.pack("<I", n))


def _pad(b: bytes) -> bytes:
    return b + b"\0" * (-len(b) % 4)


def _option(code: int, value: bytes) -> bytes:
    return struct.pack("<HH", code, len(value)) + _pad(value)


def sniff(iface: str, path: str, stop: threading.Event, ready: Callable[[], None] = lambda: None) -> int:
    """Write every EtherCAT frame seen on `iface` to `path` until `stop`; returns the number of frames."""
    # ETH_P_ALL, filtered here: a socket bound to 0x88A4 alone would not see the master's outgoing frames
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)  # a 1 ms bus is 2000 frames/s
    sock.bind((iface, 0))
    sock.settimeout(0.05)
    n = 0
    with open(path, "wb") as f:
        w = PcapngWriter(f, iface)
        f.flush()
        ready()
        while not stop.is_set():
            try:
                data, addr = sock.recvfrom(65535)
            except TimeoutError:
                continue
            except InterruptedError:
                continue
            if data[12:14] != ETHERTYPE_ECAT:
                continue
            w.frame(data, time.time_ns(), outbound=addr[2] == PACKET_OUTGOING)
            n += 1
        sock.setblocking(False)
        while True:  # what the kernel still holds
            try:
                data, addr = sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            if data[12:14] == ETHERTYPE_ECAT:
                w.frame(data, time.time_ns(), outbound=addr[2] == PACKET_OUTGOING)
                n += 1
    sock.close()
    return n


class EthercatCapture:
    """The sniffer process for the length of a run."""

    def __init__(self, iface: str, path: str) -> None:
        self.path = path
        self.proc = subprocess.Popen([sys.executable, "-m", "fieldbus.capture", iface, path],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline() if self.proc.stdout else ""
        if not line.startswith("ready"):
            err = self.proc.communicate(timeout=5)[1].strip().splitlines()
            raise OSError(f"cannot capture on {iface}: {err[-1] if err else 'capture process ended'}")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.communicate()


class CanCapture:
    """Taps a python-can bus: every frame sent through it and received from it goes to a
    `can.Logger` (the writer for the file's suffix)."""

    def __init__(self, path: str) -> None:
        import can

        self.path = path
        self.writer = can.Logger(path)
        self._lock = threading.Lock()
        self._now: Callable[[], float] = time.time
        self._closed = False

    def tap(self, bus: Any, now: Callable[[], float], channel: str = "") -> None:
        """Wrap `bus.send`/`bus.recv`; `now` stamps the frames (the link's clock, + the wall-clock
        start in lock-step so the log's date is today's)."""
        self._now = now
        send, recv = bus.send, bus.recv

        def tsend(msg: Any, timeout: float | None = None) -> None:
            send(msg, timeout)
            self._log(msg, channel, rx=False)

        def trecv(timeout: float | None = None) -> Any:
            msg = recv(timeout)
            if msg is not None:
                self._log(msg, channel, rx=True)
            return msg

        bus.send, bus.recv = tsend, trecv

    def _log(self, msg: Any, channel: str, rx: bool) -> None:
        import can

        copy = can.Message(timestamp=self._now(), arbitration_id=msg.arbitration_id, is_extended_id=msg.is_extended_id,
                           is_remote_frame=msg.is_remote_frame, is_error_frame=msg.is_error_frame, dlc=msg.dlc,
                           data=bytes(msg.data), is_rx=rx, channel=channel or msg.channel)
        with self._lock:
            if not self._closed:
                self.writer.on_message_received(copy)

    def close(self) -> None:
        with self._lock:
            if not self._closed:
                self._closed = True
                self.writer.stop()


def check_suffix(path: str, bus_kind: str) -> None:
    """ValueError naming the suffixes the bus's capture takes."""
    suffix = Path(path).suffix.lower()
    ok = ETHERCAT_SUFFIXES if bus_kind == "ethercat" else CAN_SUFFIXES if bus_kind == "canopen" else ()
    if not ok:
        raise ValueError("--capture records a bus: give --bus ethercat:IFACE or canopen:… (the sim bus has no frames)")
    if suffix not in ok:
        raise ValueError(f"--capture {path}: a {bus_kind} capture is written as {', '.join(ok)}")


def open_capture(path: str, link: Any, bus_kind: str, iface: str = "") -> EthercatCapture | CanCapture:
    """Start the capture a run's bus takes: the sniffer on the EtherCAT NIC now, or a CAN tap that
    the CANopen link installs on its bus when it opens (`link.capture`)."""
    check_suffix(path, bus_kind)
    if bus_kind == "ethercat":
        return EthercatCapture(iface, path)
    cap = CanCapture(path)
    link.capture = cap
    return cap


def _main(argv: list[str]) -> int:
    iface, path = argv
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    # Ctrl-C and Ctrl-\ reach the whole group: keep recording the controlled stop (B94)
    for sig in (signal.SIGINT, signal.SIGHUP, signal.SIGQUIT):
        signal.signal(sig, signal.SIG_IGN)
    try:
        sniff(iface, path, stop, ready=lambda: print("ready", flush=True))
    except OSError as exc:
        print(f"capture: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(_main(sys.argv[1:]))
