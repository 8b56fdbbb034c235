"""Fitted runs' windows worked out ahead, by another process (decision bench B86).

A window's fit (`RunFeed._fix`: the smoothing spline, its spans, the joint onto the span before, the tolerance
check) costs 7–35 ms of CPU. A run in real time does it in the cycle whose push completes the window, and that
cycle overran by as much (a 400-segment CAM polyline on the mill bench: 55 ms of cycle work, 91 overruns). A
window's result is a pure function of its inputs: the window's vertices, how many of its moves go out, whether
the run ends there, and the span the window before ended with. So another process that runs the same program
offline (hil/fit_ahead.py) works every window out ahead and sends it here, keyed by those inputs; the cycle
takes it from here instead of fitting. Where that process saw other inputs (an override, a variable the MLC
set, a run cut by a feed hold), the key differs, the cycle fits the window itself, as before: the result is the
same bits either way, only where the CPU is spent differs.

The key of a window chains the key of the window that made its joint's span (`Held.key`): equal keys, equal
spans before, so equal results.

A window travels as one pickle per span (decision bench B98): unpickling a window's 80 spans is 1.5-3.5 ms, more
than a period, so the run decodes them a span at a time in its slacks (`FitReceiver.work_part`, called by the
real-time clock while time is left before the next tick) and the cycle that needs the window takes it decoded.
"""

from __future__ import annotations

import hashlib
import pickle
import struct
from collections import OrderedDict
from typing import Any, Protocol

import numpy as np

MISSING = object()  # not known here: the caller works it out
KEY_SIZE = 16
KEEP = 64  # results kept after they are read: a stretch pass may read a window again after a restore
MARK = b"\0" * KEY_SIZE  # a message of this key alone: the sender's run is past its start (`FitSender.mark`)


def window_key(prev: bytes, pts: np.ndarray, first: int, n: int, end: bool) -> bytes:
    """The window's inputs as a key (`prev`: the key of the window whose last span the joint is made on)."""
    h = hashlib.blake2b(prev, digest_size=KEY_SIZE)
    h.update(np.ascontiguousarray(pts, dtype=float).tobytes())
    h.update(struct.pack("<iiq?", pts.shape[0], first, n, end))
    return h.digest()


class FitMemo(Protocol):
    def get(self, key: bytes) -> Any:
        """The window's result (spans, or None: as lines), or MISSING."""

    def put(self, key: bytes, result: Any) -> None:
        """A result worked out here."""


class FitSender:
    """The working-ahead side: every window it works out goes to the connection. `capacity`: the pipe's size in
    bytes; a message is written only once it fits whole, so the reader (a paced cycle) never finds half a
    message and waits for the rest from a process the scheduler may have put aside."""

    def __init__(self, conn, capacity: int = 0) -> None:
        self.conn = conn
        self.capacity = capacity
        self.sent = 0
        self._pending: tuple[bytes, Any, list | None] | None = None  # the window fitted last, not sent yet

    def _room(self, size: int) -> None:
        import fcntl
        import termios
        import time

        queued = bytearray(4)
        while True:
            fcntl.ioctl(self.conn.fileno(), termios.FIONREAD, queued)
            if int.from_bytes(queued, "little") + size <= self.capacity:
                return
            time.sleep(0.002)

    def get(self, key: bytes) -> Any:
        return MISSING

    def put(self, key: bytes, result: Any) -> None:
        """The window pickled now, as it was cut, a pickle per span (the run decodes a window a span at a time in
        its slacks, B98); sent at `flush` (hil.fit_ahead: at the start of this process's next cycle) or with the next
        window: by then its look-ahead has taken the window's spans, and their limits (`span_limits`, B99) go with
        them."""
        self.flush()
        for sp in result or ():  # the ends the look-ahead asks for at every junction, worked out here (kept in the
            sp._end(True)  # span, so they travel with it): in the run's cycle they cost more than the fit
            sp._end(False)
        parts = None if result is None else [pickle.dumps(sp, protocol=pickle.HIGHEST_PROTOCOL) for sp in result]
        self._pending = (key, result, parts)

    def flush(self) -> None:
        """The window held back by `put`, sent now with the limits this process's look-ahead left on its spans."""
        if self._pending is None:
            return
        (key, result, parts), self._pending = self._pending, None
        # each span's limits a pickle of its own, of plain floats: the run decodes them with their span, a part a slack
        limits = None if result is None else [_plain(sp.__dict__.get("_limits")) for sp in result]
        msg = key + pickle.dumps((parts, limits), protocol=pickle.HIGHEST_PROTOCOL)
        if self.capacity:
            self._room(len(msg) + 8)  # (send_bytes' length header)
        self.conn.send_bytes(msg)
        self.sent += 1

    def mark(self) -> None:
        """Every window of the run's first cycles is sent (hil.fit_ahead: the run may start)."""
        self.flush()
        self.conn.send_bytes(MARK)


class FitReceiver:
    """The cycle's side: what the connection brought, read without waiting (`wait`: until the key or the sender's
    end arrives, for lock-step tests that must not race the sender). Counts what was found and what was not."""

    def __init__(self, conn, wait: bool = False) -> None:
        self.conn = conn
        self.wait = wait
        self.blobs: OrderedDict[bytes, bytes] = OrderedDict()
        self.found: set[bytes] = set()  # windows taken from the sender (a set: a restored pass reads one again)
        self.fitted: set[bytes] = set()  # windows the cycle worked out itself
        self.closed = False  # the sender ended (its program done, or it failed)
        self.marked = False  # the sender is past the run's first cycles
        # B98: windows decoded ahead, in the run's slacks (key → spans, or None), and the one being decoded (its
        # key, its spans' pickles, those decoded so far); a window is handed out decoded once, then from its blob
        self.ready: dict[bytes, list | None] = {}
        self._part: tuple[bytes, tuple, list] | None = None
        self.decoded_ahead = 0  # windows handed out decoded ahead

    def _read(self) -> None:
        msg = self.conn.recv_bytes()
        if msg == MARK:
            self.marked = True
            return
        self.blobs[msg[:KEY_SIZE]] = msg[KEY_SIZE:]
        while len(self.blobs) > KEEP:
            self.ready.pop(self.blobs.popitem(last=False)[0], None)

    def _drain(self, key: bytes) -> None:
        """Read up to the key (the sender's windows come in the run's order: mostly the next message is it)."""
        try:
            while not self.closed and key not in self.blobs and (self.wait or self.conn.poll()):
                self._read()
        except (EOFError, OSError):
            self.closed = True

    def get(self, key: bytes) -> Any:
        if key in self.ready:  # decoded in the slacks before (B98)
            self.found.add(key)
            self.decoded_ahead += 1
            return self.ready.pop(key)
        if key not in self.blobs:
            self._drain(key)
        blob = self.blobs.get(key)
        if blob is None:
            return MISSING
        self.found.add(key)
        if self._part is not None and self._part[0] == key:
            self._part = None
        parts, limits = pickle.loads(blob)  # new objects every time: the planner may change its spans
        return None if parts is None else [_span(parts, limits, i) for i in range(len(parts))]

    def work_part(self, read: bool = True) -> bool:
        """One small part of the work ahead (B98), in a slack: a message read from the connection (not without
        `read`), or one span of the next window not handed out yet decoded. False: nothing to do."""
        if read and not self.closed:
            try:
                if self.conn.poll():
                    self._read()
                    return True
            except (EOFError, OSError):
                self.closed = True
        part = self._part
        if part is None:
            key = next((k for k in self.blobs if k not in self.found and k not in self.ready), None)
            if key is None:
                return False
            parts, limits = pickle.loads(self.blobs[key])  # the spans' pickles (bytes: no span decoded yet)
            if not parts:
                self.ready[key] = parts
                return True
            self._part = part = (key, (parts, limits), [])
        key, (parts, limits), done = part
        done.append(_span(parts, limits, len(done)))
        if len(done) == len(parts):
            self._part = None
            if key in self.blobs and key not in self.found:
                self.ready[key] = done
        return True

    def put(self, key: bytes, result: Any) -> None:
        self.fitted.add(key)


def _span(parts: list[bytes], limits: list | None, i: int) -> Any:
    """Span i of a window as sent: its pickle, with the limits the sender's look-ahead worked out (B99)."""
    sp = pickle.loads(parts[i])
    if limits is not None:
        known = pickle.loads(limits[i])
        if known is not None:
            sp.__dict__["_limits"] = known
    return sp


def _plain(limits: tuple | None) -> bytes:
    """A span's limits as the look-ahead left them ((velocity caps, acceleration and jerk limits, (v, a, j))),
    pickled with the caps as a tuple of floats (the look-ahead compares them element for element)."""
    if limits is not None:
        limits = (tuple(limits[0].tolist()), *limits[1:])
    return pickle.dumps(limits, protocol=pickle.HIGHEST_PROTOCOL)
