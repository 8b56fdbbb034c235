"""The channel's feed inside a stretch across a cruise's blocks (issue 17, decision bench B26).

A CAM program's queue refills 8 blocks at a time, 4 a cycle: a stretch across a cruise's blocks (B25) ended
before every cycle whose feed reads the program, and that cycle was stepped. Here the stretch runs those feeds
itself, at the cycle stepping would, in stepping's order: the planner's rows up to that cycle
(`sample_stretch(..., across=True)`, whose chain checks see the queue as that cycle's step sees it), then the
channel's own feed (`Channel._feed_planner`: the interpreter and `Planner.push` of the blocks read), then the
rows after it, checked against the queue with those pushes. A push may change what a later row would be (a
block of the chain that no longer cruises, a filter share λ): the stretch ends before the first row that
differs from what the drives were stepped with (the rows sampled before the reads), as B20 ends a stretch.

A push cannot be taken back, so the reads run only where nothing cuts the stretch after them: the stretch's
length is decided first (the rows as they stand, the drive models, the bench's checks), the stretch runs at once
(bulk, the basic MLC, lock-step), and a read happens only when the events it takes are plain moves
(`Ahead.peek`: no M/S/T code, sync, end, alarm, G31, thread, feed per revolution, G96, soft-limit crossing or
macro statement). Otherwise the stretch ends before that cycle. The events peeked stay in `Ahead`, which the
channel reads them from in order, with the statement budget as generating them left it (the interpreter
already runs ahead of the machine: its preview window, nc/interp/preview.py, reads by events, not cycles).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import Any

import numpy as np

from nc.channel import READS_PER_CYCLE, Channel, RunState
from nc.moves import Event, Move
from nc.motion.planner import Planner
from nc.motion.stretch import Samples, sample_stretch
from hil.stretch_state import _across, _restore_planner, _save_planner

PLAIN_KINDS = ("line", "arc", "rapid")


class Ahead:
    """The channel's event stream with events peeked ahead of its feed: handed out first, in order, each with
    the statement budget's count as generating it left it (so the budget reads as in stepping), and a plain
    move with its soft-limit verdict, taken when it was read (`Channel._checked`: the feed does not check it
    again, after the interpreter has been read further)."""

    def __init__(self, source: Iterator[Event], ch: Channel) -> None:
        self.source = source
        self.ch = ch
        # (event, the exception reading it raised, budget used and peak after it, a plain move)
        self.buf: deque[tuple[Event | None, Exception | None, int, int, bool]] = deque()

    def __iter__(self) -> "Ahead":
        return self

    def __next__(self) -> Event:
        if not self.buf:
            return next(self.source)
        ev, exc, used, peak, plain = self.buf.popleft()
        budget = self.ch.statement_budget
        if budget is not None and used:
            budget.used = used
            budget.peak = max(budget.peak, peak)
        if exc is not None:
            raise exc
        if plain:
            self.ch._checked = ev  # type: ignore[assignment]
        return ev  # type: ignore[return-value]

    def peek(self, k: int) -> bool:
        """The next k events (the most one feed reads) generated now and kept: True when all are plain moves
        (module doc), so a feed reading any of them only pushes."""
        ch = self.ch
        budget = ch.statement_budget
        saved = (budget.used, budget.peak) if budget is not None else None
        plain = True
        for j in range(k):
            if j < len(self.buf):
                plain = self.buf[j][4]
            else:
                if budget is not None:
                    budget.used = 0  # a cycle's budget opens before its first read
                ev: Event | None = None
                exc: Exception | None = None
                try:
                    ev = next(self.source)
                except Exception as e:  # StopIteration, an alarm: handed out as the feed would meet it
                    exc = e
                used = budget.used if budget is not None else 0
                plain = exc is None and not used and _plain(ev, ch)
                self.buf.append((ev, exc, used, budget.peak if budget is not None else 0, plain))
            if not plain:
                break
        if budget is not None and saved is not None:
            budget.used, budget.peak = saved
        return plain


def _plain(ev: Event | None, ch: Channel) -> bool:
    """A move the feed only pushes: no G31, thread, feed per revolution or G96, inside the soft limits (checked
    now, right after reading it, where the feed checks it in stepping)."""
    if type(ev) is not Move or ev.kind not in PLAIN_KINDS or ev.per_rev or ev.css is not None or "G31" in ev.tags:
        return False
    return ch.soft_limits is None or ch.soft_limits.check(ev) is None


def ahead(ch: Channel) -> Ahead:
    """The channel's events as an `Ahead` (put in place once; the channel reads through it from then on)."""
    ev = ch.events
    if type(ev) is Ahead and ev.ch is ch:
        return ev
    ch.events = a = Ahead(ev, ch)  # type: ignore[arg-type]
    return a


def may_read(ch: Channel, pl: Planner) -> bool:
    """The channel state in which a feed inside a stretch only reads and pushes (Channel._feed_planner)."""
    budget = ch.statement_budget
    return (ch.state is RunState.RUNNING and ch.events is not None and ch.end is None and ch._deferred is None
            and ch._limit_alarm is None and ch._interrupt is None and not ch.single_block and not ch.alarms
            and not ch.skip_armed and ch._skip_move is None and (budget is None or not budget.spent)
            and not pl.held and pl.threads_queued == 0)


def sample_reading(ch: Channel, pl: Planner, n: int, expect: np.ndarray) -> tuple[Samples | None, int]:
    """Up to n rows of a cruise across its blocks from where the planner stands, with the feeds of the cycles
    that read (module doc), each row equal to `expect` (what the drives were stepped with); fewer where a row
    would differ, a block stops cruising, or a feed would read something else than plain moves. Also how many
    feeds ran; where the stretch ends right after one, the channel's next step skips its feed (`Channel._fed`)."""
    parts: list[Samples] = []
    rows, feeds, fed_at = 0, 0, -1
    src = ahead(ch)
    while rows < n:
        seg = _across(ch, pl, n - rows) if pl.full else 0
        if seg == 0:  # this cycle's feed reads
            if not rows or not may_read(ch, pl) or not src.peek(READS_PER_CYCLE):
                break  # (the first cycle's feed reads nothing: Stretcher._quiet)
            ch._feed_planner()  # plain moves only: it pushes them, nothing else changes
            feeds, fed_at = feeds + 1, rows
            seg = _across(ch, pl, n - rows) if pl.full else 1  # still filling: the next cycle reads again
        saved = _save_planner(pl)
        smp = sample_stretch(pl, seg, across=True)
        if smp is None:
            break
        got = len(smp.positions)
        want = expect[rows:rows + got]
        if not np.array_equal(smp.positions, want):
            bad = int(np.flatnonzero(np.any(smp.positions != want, axis=1))[0])
            _restore_planner(pl, saved)
            if bad:
                parts.append(sample_stretch(pl, bad, across=True))  # type: ignore[arg-type]
                rows += bad
            break
        parts.append(smp)
        rows += got
        if got < seg:
            break
    if fed_at == rows:  # the stretch ends before the cycle whose feed it ran: that cycle's step must not read again
        ch._fed = True
    return (_joined(parts) if parts else None), feeds


def _joined(parts: list[Samples]) -> Samples:
    if len(parts) == 1:
        return parts[0]
    moves: list[Any] = []
    for p in parts:
        moves += p.moves if p.moves is not None else [p.move] * len(p.positions)
    return Samples(np.concatenate([p.positions for p in parts]), [ln for p in parts for ln in p.lines],
                   np.concatenate([p.path_velocity for p in parts]), parts[0].move, moves)
