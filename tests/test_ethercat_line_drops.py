"""The virtual slaves' line (`hil sim ethercat`) when the kernel refuses an answer for lack of buffers
(ENOBUFS: the master stalled on a loaded host and the veth queue filled): that frame is lost, as on a real
line, and the simulator goes on answering; any other socket error still ends it."""

from __future__ import annotations

import errno

import pytest

from virtual_bus.ethercat.network import RawSocketLine


class _Chain:
    def process(self, frame):
        return bytes(frame).upper(), 0.0  # an answer the test can tell from the frame

    def tick(self) -> None:
        pass


class _Sock:
    """Hands out the frames in turn; `send` fails for the frames listed in `refuse` with `err`."""

    def __init__(self, line: RawSocketLine, frames: list[bytes], refuse: set[int], err: int) -> None:
        self.line, self.frames, self.refuse, self.err = line, frames, refuse, err
        self.sent: list[bytes] = []
        self.k = -1

    def recv_into(self, buf: bytearray) -> int:
        self.k += 1
        if self.k >= len(self.frames):
            self.line.running = False
            raise BlockingIOError
        f = self.frames[self.k]
        buf[:len(f)] = f
        return len(f)

    def send(self, data: bytes) -> int:
        if self.k in self.refuse:
            raise OSError(self.err, "No buffer space available")
        self.sent.append(data)
        return len(data)


def _line(frames: list[bytes], refuse: set[int], err: int) -> tuple[RawSocketLine, _Sock]:
    line = RawSocketLine.__new__(RawSocketLine)  # no raw socket: the serve loop alone
    line.chain, line.iface, line.ignores_outgoing, line.running, line.dropped = _Chain(), "veth-test", True, True, 0
    line.sock = _Sock(line, frames, refuse, err)
    return line, line.sock


def test_answers_the_kernel_refuses_are_lost_frames_and_the_line_goes_on() -> None:
    line, sock = _line([b"f0", b"f1", b"f2", b"f3"], refuse={1, 2}, err=errno.ENOBUFS)
    line.serve()
    assert sock.sent == [b"F0", b"F3"]  # the frames after the refused ones are answered
    assert line.dropped == 2


def test_another_socket_error_still_ends_the_simulator() -> None:
    line, sock = _line([b"f0", b"f1"], refuse={0}, err=errno.ENETDOWN)
    with pytest.raises(OSError) as info:
        line.serve()
    assert info.value.errno == errno.ENETDOWN
    assert sock.sent == []
