"""Preview (look-ahead) window: the interpreter reads up to ``depth`` motion blocks ahead of the
one the machine executes, so macro statements run early (N§3.2.2, decisions A27).

`PreviewWindow` wraps the event stream.  It pulls from the interpreter until ``depth`` Moves are
buffered; every macro statement run meanwhile is logged (`Interpreter.preview_log`) with the
motion block the machine was executing at that moment (the oldest buffered Move).  A `Sync` (G05,
G10, G11, G31, G53, halt M codes of N1.118/N1.119, writes to live # variables) empties the window
before anything after it is read.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import TYPE_CHECKING

from nc.alarms import NcAlarm, internal_error
from nc.interp.records import PreviewRecord
from nc.moves import Busy, Event, Move, MoveBatch, MoveList, Sync

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.host import InterpHost


class Passing:
    """What the preview window may read past the corner and compensation stages (issue 17, decisions bench B173): the
    lean lane's run the program counter hands out (`stream`, nc.interp.lean_run: plain Moves without ,C/,R or radius
    compensation, each made as the interpreter stands after it), and the compensator of the stream (`comp`, None
    without one). While no corner waits and the compensator holds nothing, both stages would only pass such a Move
    on: the window reads the run itself (three generator frames less a Move), and once the run is done the stages
    read on from where they stand (the program counter's `yield from` of a finished run returns at once)."""

    __slots__ = ("stream", "comp")

    def __init__(self) -> None:
        self.stream: Iterator[Move] | None = None
        self.comp: object = None


class PreviewWindow:
    def __init__(self, interp: "InterpHost", events: Iterator[Event], depth: int, passing: Passing | None = None) -> None:
        self.interp = interp
        self.events = events
        self.passing = passing
        self.depth = max(0, depth)
        self.buf: deque[Event] = deque()
        self.executing: Move | None = None  # the motion block the machine is running now
        if interp.preview_log.maxlen != 0:  # a log that keeps nothing is not worth a call per statement
            interp.on_statement = self._statement

    def _statement(self, block, program: str) -> None:
        first = None
        n_ahead = 0
        for e in self.buf:  # one pass (this runs for every macro statement)
            if isinstance(e, Move):
                n_ahead += 1
                if first is None:
                    first = e
        ahead = first or self.executing
        self.interp.preview_log.append(PreviewRecord(
            block.line, block.text.strip(), program,
            ahead.line if ahead is not None else None,
            ahead.block.strip() if ahead is not None else None, n_ahead))

    def __iter__(self) -> Iterator[Event]:
        done = False
        failure: Exception | None = None
        buf, events, depth = self.buf, self.events, self.depth
        interp, passing = self.interp, self.passing
        # counts of the Moves and Syncs in buf, kept as events enter and leave (hot path: no rescans)
        moves = syncs = 0
        while True:
            # read ahead until the window is full, a Sync arrives, or the program ends. A for loop (the
            # stream's next event without a call of next()) that, once the window is full of Moves, hands
            # out its oldest events until there is room and reads on (hot path: one event in, one out).
            # Nothing is thrown into this generator: the `try` sees only the stream's alarms.
            if not done and moves <= depth and not syncs:
                try:
                    for ev in events:
                        if type(ev) is Move:  # the usual event first (Move has no subclass)
                            buf.append(ev)
                            moves += 1
                            while moves > depth:  # no Sync is in buf while reading
                                out = buf.popleft()
                                if type(out) is Move:
                                    moves -= 1
                                    self.executing = out
                                else:
                                    moves, syncs = self._left(out, moves, syncs)
                                yield out
                            if passing is not None and (run := passing.stream) is not None \
                                    and not interp.corner_pending \
                                    and ((comp := passing.comp) is None or (comp.pending is None and comp.out_pos is None)):
                                # the lean lane's run, read past the stages (`Passing`): the same steps a Move
                                try:
                                    for ev in run:
                                        buf.append(ev)
                                        moves += 1
                                        while moves > depth:
                                            out = buf.popleft()
                                            if type(out) is Move:
                                                moves -= 1
                                                self.executing = out
                                            else:
                                                moves, syncs = self._left(out, moves, syncs)
                                            yield out
                                except Exception as exc:  # a bug: 0x0000 at the block, as the program counter says it
                                    b = interp.block
                                    raise NcAlarm(0x0000, internal_error(exc).message, line=getattr(b, "line", None),
                                                  block=getattr(b, "text", None), program=interp.program_name) from exc
                            continue
                        if isinstance(ev, Busy):  # the statement budget is spent: the channel reads on next cycle
                            yield ev
                            continue
                        buf.append(ev)
                        if isinstance(ev, Move):
                            moves += 1
                        elif type(ev) is MoveBatch or type(ev) is MoveList:  # a run of plain moves (nc.interp.bulk,
                            moves += len(ev)  # a cycle's) counts as its moves
                        elif isinstance(ev, Sync):
                            syncs += 1
                        if moves > depth or syncs:
                            break
                    else:
                        done = True  # the program ended
                except Exception as exc:  # an alarm read ahead is raised when execution reaches it
                    failure = exc
                    done = True
                continue
            if not buf:
                if failure is not None:
                    raise failure
                return
            ev = buf.popleft()
            moves, syncs = self._left(ev, moves, syncs)
            yield ev

    def _left(self, ev: Event, moves: int, syncs: int) -> tuple[int, int]:
        """The counts of Moves and Syncs in the window once `ev` has left it (the machine runs it now)."""
        if isinstance(ev, Move):
            moves -= 1
            self.executing = ev
        elif type(ev) is MoveBatch:
            moves -= len(ev)
            self.executing = ev  # type: ignore[assignment]  # its .line/.block: the last move's
        elif type(ev) is MoveList:
            moves -= len(ev)
            self.executing = ev.items[-1]
        elif isinstance(ev, Sync):
            syncs -= 1
        return moves, syncs
