"""A user scan that runs only when something it depends on changed (issue 17).

A program that declares ``SCAN_ON_CHANGE = True`` promises that its scan is a function of what it
reads through the scan API (``mlc.m/d/x/y``, ``rising``/``falling``, ``timer``, ``mlc.io``) and of
``mlc.state``: no ``mlc.time``/``scan_count``, no raw ``mlc.mem``, no module globals. Each real scan
records the devices it read (with the values it saw), whether it changed anything (a device, the
I/O images, ``state``, edge or timer memory) and the deadlines of its running timers. The next scan
is skipped when that scan changed nothing, every device it read still holds the value it saw, and
no timer it waits for is due: the scan would read the same inputs with the same state, so it would
again write nothing and change nothing. The outputs it wrote earlier stay in the device memory
(carried), exactly as the skipped scan would have left them. The NC side of the exchange
(mlc/nc_link.py) still runs every cycle.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from operator import itemgetter
from typing import Any

# Areas a recorded read names: (area, index) → the value seen. AREA_IO_INPUTS is the digital image of a
# module without an X mapping (RemoteIo.inputs).
AREA_M, AREA_WORDS, AREA_X, AREA_Y, AREA_A, AREA_IO_INPUTS = range(6)
TIMER_EPS = 1e-12  # ScanContext.timer's own tolerance: a deadline is checked with the same expression
_SCALARS = (int, float, str, bool, type(None))


@dataclass
class ScanRecord:
    """What one real scan read and whether it changed anything."""

    reads: dict[tuple[int, int], Any] = field(default_factory=dict)
    timers: list[tuple[float, float]] = field(default_factory=list)  # (start, seconds) still running, not due
    dirty: bool = False
    checks: tuple | None = None  # the reads grouped by area for `ScanGate.quiet` (made on first use)

    def read(self, area: int, index: int, value: Any) -> None:
        # The first read of a scan is the one the scan decided on (a later read after its own
        # write sees that write, and a scan that changed a device is dirty anyway).
        self.reads.setdefault((area, index), value)


def y_point(y: bytearray, i: int, on: bool | None, rec: ScanRecord | None) -> bool:
    """Write (on given) or read back output point Y<i>, recorded while a scan is."""
    if on is not None:
        if rec is not None and y[i] != (1 if on else 0):
            rec.dirty = True
        y[i] = 1 if on else 0
    elif rec is not None:
        rec.read(AREA_Y, i, y[i])
    return bool(y[i])


def _immutable(state: dict[str, Any]) -> bool:
    """The state compares by value (scalars, tuples of scalars): a list changed in place would not show."""
    for v in state.values():
        t = type(v)
        if t in _SCALARS:
            continue
        if t is tuple and all(type(e) in _SCALARS for e in v):
            continue
        return False
    return True


def _grouped(reads: dict[tuple[int, int], Any]) -> tuple:
    """(area, itemgetter of the area's indices, the values seen) per area read: comparing what the
    getter gathers now with the values is the loop `areas[area][i] != v` over every read."""
    by_area: dict[int, tuple[list[int], list[Any]]] = {}
    for (area, i), v in reads.items():
        idx, vals = by_area.setdefault(area, ([], []))
        idx.append(i)
        vals.append(v)
    return tuple((area, itemgetter(*idx), tuple(vals) if len(idx) > 1 else vals[0])
                 for area, (idx, vals) in by_area.items())


class ScanGate:
    """Decides, cycle by cycle, whether the user scan must run (see the module doc)."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.last: ScanRecord | None = None
        self.scans = 0  # real scans
        self.skipped = 0  # scans carried over

    def quiet(self) -> bool:
        """True when the last scan changed nothing and nothing it read or waits for changed."""
        rec = self.last
        if rec is None or rec.dirty:
            return False
        ctx = self.ctx
        t = ctx.time
        for start, seconds in rec.timers:
            if t - start >= seconds - TIMER_EPS:
                return False
        checks = rec.checks
        if checks is None:
            checks = rec.checks = _grouped(rec.reads)
        mem = ctx.mem
        areas = (mem.m, mem.words, mem.x, mem.y, mem.a, ctx.io.inputs)
        for area, get, want in checks:  # one C-level gather and tuple compare per area, not a loop per device
            if get(areas[area]) != want:
                return False
        self.skipped += 1
        return True

    def run(self, scan: Callable[[Any], None]) -> None:
        """One real scan, recorded."""
        ctx = self.ctx
        self.last = None  # a scan that raises leaves no record: the next one runs
        rec = ScanRecord()
        state, prev, timers = dict(ctx.state), dict(ctx._prev), dict(ctx._timers)
        ctx._rec = ctx.io._rec = rec
        try:
            scan(ctx)
        finally:
            ctx._rec = ctx.io._rec = None
        self.scans += 1
        rec.dirty = (rec.dirty or ctx._prev != prev or ctx._timers != timers or ctx.state != state
                     or not _immutable(ctx.state))
        self.last = rec


def wants_gate(program: Any) -> bool:
    """The program declared its scan a function of what it reads (``SCAN_ON_CHANGE = True``)."""
    return getattr(program, "SCAN_ON_CHANGE", False) is True
