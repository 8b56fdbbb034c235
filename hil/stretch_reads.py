"""The channel's reads inside a stretch (issue 17, decisions bench B26/B27): its event stream read ahead.

A stretch that runs the NC's steps itself (hil/stretch_pass.py) runs the channel's feed at the cycles stepping
reads the program in (a CAM program's queue refills 8 blocks at a time, 4 a cycle). A feed's push cannot be
taken back, so a feed runs there only when the events it takes are plain moves (`Ahead.peek`: line, arc or
rapid, no G31, feed per revolution or G96, inside the soft limits, generated without a macro statement) and the
channel's state lets it only read and push (`may_read`); otherwise the stretch ends before that cycle. The events
peeked stay in `Ahead`, which the channel reads them from in order, with the statement budget as generating them
left it (the interpreter already runs ahead of the machine: its preview window, nc/interp/preview.py, reads by
events, not cycles).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

from nc.channel import Channel, RunState
from nc.moves import Event, Move
from nc.motion.planner import Planner

PLAIN_KINDS = ("line", "arc", "rapid")


class Ahead:
    """The channel's event stream with events peeked ahead of its feed: handed out first, in order, each with
    the statement budget's count as generating it left it (so the budget reads as in stepping), and a plain
    move with its soft-limit verdict, taken when it was read (`Channel._checked`: the feed does not check it
    again, after the interpreter has been read further).

    What was peeked is plain moves (`plain`), then at most one other event (`tail`): a peek stops at the first
    event that is not a plain move, and the next peek stops there again without reading. A plain move was
    generated without a statement (budget count 0), so handing it out leaves the budget as it is; the channel's
    feed takes them straight from `plain` (`Channel._feed_planner`, issue 17)."""

    def __init__(self, source: Iterator[Event], ch: Channel) -> None:
        self.source = source
        self.ch = ch
        self.plain: deque[Move] = deque()
        # the event after them: (event, the exception reading it raised, budget used and peak after it)
        self.tail: tuple[Event | None, Exception | None, int, int] | None = None
        # (the soft limits' box test, the end of the last move it found inside): `peek`'s test of the next move's end
        self._inside: tuple[object, dict | None] = (None, None)

    def __iter__(self) -> "Ahead":
        return self

    def __next__(self) -> Event:
        if self.plain:
            ev = self.ch._checked = self.plain.popleft()
            return ev
        tail = self.tail
        if tail is None:
            return next(self.source)
        self.tail = None
        ev, exc, used, peak = tail
        budget = self.ch.statement_budget
        if budget is not None and used:
            budget.used = used
            budget.peak = max(budget.peak, peak)
        if exc is not None:
            raise exc
        return ev  # type: ignore[return-value]

    def peek(self, k: int) -> bool:
        """The next k events (the most one feed reads) generated now and kept: True when all are plain moves
        (module doc), so a feed reading any of them only pushes."""
        plain = self.plain
        if len(plain) >= k:
            return True
        if self.tail is not None:
            return False
        ch = self.ch
        budget = ch.statement_budget
        saved = (budget.used, budget.peak) if budget is not None else None
        source = self.source
        # the soft limits' box test, found once for the reads (SoftLimits.line_test: valid while the params keep
        # their length), then one call a line or rapid, of its end alone where its start equals the end of the last
        # move that test found inside (a program's lines: the start is the last end); `check` where it does not
        # answer (B193)
        limits = ch.soft_limits
        box = limits.line_test() if limits is not None else None
        test, end_test, params, n_params = box if box is not None else (None, None, None, -1)
        last_test, last_end = self._inside
        if last_test is not test:
            last_end = None
        ok = True
        if budget is not None:
            budget.used = 0  # a cycle's budget opens before its first read (a plain move leaves it at 0 for the next)
        while len(plain) < k:
            try:
                ev = next(source)
            except Exception as e:  # StopIteration, an alarm: handed out as the feed would meet it
                self.tail = (None, e, budget.used if budget is not None else 0, budget.peak if budget is not None else 0)
                ok = False
                break
            # a move the feed only pushes: no G31, thread, feed per revolution or G96, generated without a statement,
            # inside the soft limits (checked now, right after reading it, where the feed checks it in stepping);
            # inline, a call less an event (B178)
            if type(ev) is Move and (kind := ev.kind) in PLAIN_KINDS and not ev.per_rev and ev.css is None \
                    and "G31" not in ev.tags and (budget is None or not budget.used):
                if limits is None:
                    plain.append(ev)
                    continue
                if test is not None and kind != "arc" and len(params) == n_params:  # type: ignore[arg-type]
                    end = ev.end
                    if end_test(end) if ev.start == last_end else test(ev.start, end):  # type: ignore[misc]
                        last_end = end
                        plain.append(ev)
                        continue
                if limits.check(ev) is None:
                    plain.append(ev)
                    continue
            self.tail = (ev, None, budget.used if budget is not None else 0, budget.peak if budget is not None else 0)
            ok = False
            break
        self._inside = (test, last_end)
        if saved is not None:
            budget.used, budget.peak = saved  # type: ignore[union-attr]
        return ok


def ahead(ch: Channel) -> Ahead:
    """The channel's events as an `Ahead` (put in place once; the channel reads through it from then on)."""
    ev = ch.events
    if type(ev) is Ahead and ev.ch is ch:
        return ev
    ch.events = ch._ahead = a = Ahead(ev, ch)  # type: ignore[arg-type]
    return a


def may_read(ch: Channel, pl: Planner) -> bool:
    """The channel state in which a feed inside a stretch only reads and pushes (Channel._feed_planner)."""
    budget = ch.statement_budget
    return (ch.state is RunState.RUNNING and ch.events is not None and ch.end is None and ch._deferred is None
            and ch._limit_alarm is None and ch._interrupt is None and not ch.single_block and not ch.alarms
            and not ch.skip_armed and ch._skip_move is None and (budget is None or not budget.spent)
            and not pl.held and pl.threads_queued == 0)
