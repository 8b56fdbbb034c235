"""Builds the canonical Moves of a cycle from plane points, keeping the current position.

A cycle computes its path in a 2-D plane (Z, X radius on a lathe) and hands each element to a
`PathBuilder`, which turns it into a `nc.moves.Move` in machine coordinates with the block's line,
text and program, the work position as programmed, and tags naming the cycle and the pass.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from nc.cycles.geometry import Pt, Seg
from nc.moves import Aux, Event, Move


@dataclass
class PathBuilder:
    position: dict[str, float]  # machine coordinates, updated as moves are added
    plane: tuple[str, str]  # (first, second) axis names of the cycle plane
    line: int
    block: str
    to_work: Callable[[dict[str, float]], dict[str, float]]
    program: str | None = None
    feed: float | None = None
    per_rev: bool = True
    events: list[Event] = field(default_factory=list)
    css: float | None = None

    @property
    def here(self) -> Pt:
        return (self.position[self.plane[0]], self.position[self.plane[1]])

    def _end(self, p: Pt) -> dict[str, float]:
        end = dict(self.position)
        end[self.plane[0]], end[self.plane[1]] = p
        return end

    def _emit(self, move: Move) -> Move:
        self.events.append(move)
        self.position = dict(move.end)
        return move

    def _common(self, end: dict[str, float], tags: tuple[str, ...]) -> dict:
        return dict(line=self.line, block=self.block, start=dict(self.position), end=end,
                    work=self.to_work(end), program=self.program, plane=self.plane, tags=tags, css=self.css)

    def _to(self, kind: str, p: Pt, tags: tuple[str, ...], feed: float | None, per_rev: bool,
            center: dict[str, float] | None = None, dir: str | None = None, lead: float | None = None,
            lead_change: float = 0.0, start_angle: float = 0.0) -> Move | None:
        """The lean path of every plane move (issue 16: a lathe cycle emits thousands): the Move built
        positionally; its end is the new position and the next move's start (one dict for both: no
        stage changes a move's points in place, `hil path` writes the shared point once).
        A line or rapid shorter than float noise is dropped; the position snaps to the exact target."""
        pos = self.position
        a1, a2 = self.plane
        if center is None and kind != "thread" and -1e-12 < p[0] - pos[a1] < 1e-12 and -1e-12 < p[1] - pos[a2] < 1e-12:
            pos = self.position = pos.copy()  # the last move's end: snap a copy
            pos[a1], pos[a2] = p
            return None
        end = pos.copy()
        end[a1], end[a2] = p
        mv = Move(kind, self.line, self.block, pos, end, self.to_work(end), center, dir, feed,  # type: ignore[arg-type]
                  None, per_rev, self.plane, False, lead, lead_change, start_angle, 0.0, self.program, tags,
                  None, 0.0, 0, self.css)
        self.events.append(mv)
        self.position = end
        return mv

    def rapid(self, p: Pt, tags: tuple[str, ...] = ()) -> Move | None:
        return self._to("rapid", p, tags, None, False)

    def rapid_axes(self, target: dict[str, float], tags: tuple[str, ...] = ()) -> Move | None:
        end = dict(self.position)
        end.update(target)
        if all(abs(end[a] - self.position[a]) < 1e-12 for a in end):
            return None
        return self._emit(Move("rapid", **self._common(end, tags)))

    def line_axes(self, target: dict[str, float], tags: tuple[str, ...] = (), feed: float | None = None) -> Move | None:
        end = dict(self.position)
        end.update(target)
        if all(abs(end[a] - self.position[a]) < 1e-12 for a in end):
            return None
        return self._emit(Move("line", feed=feed if feed is not None else self.feed, per_rev=self.per_rev,
                               **self._common(end, tags)))

    def feed_to(self, p: Pt, tags: tuple[str, ...] = (), feed: float | None = None) -> Move | None:
        return self._to("line", p, tags, feed if feed is not None else self.feed, self.per_rev)

    def seg(self, s: Seg, tags: tuple[str, ...] = (), feed: float | None = None, rapid: bool | None = None) -> Move | None:
        """Add a contour element (the builder must already be at its start)."""
        if rapid if rapid is not None else s.rapid:
            return self.rapid(s.p1, tags)
        if not s.is_arc:
            return self.feed_to(s.p1, tags, feed)
        centre = self._end(s.p1)
        centre[self.plane[0]], centre[self.plane[1]] = s.center
        return self._to("arc", s.p1, tags, feed if feed is not None else self.feed, self.per_rev, centre,
                        "cw" if s.cw else "ccw")

    def thread(self, p: Pt, lead: float, start_angle: float, tags: tuple[str, ...] = (),
               lead_change: float = 0.0) -> Move:
        return self._to("thread", p, tags, lead, True, None, None, lead, lead_change, start_angle)  # type: ignore[return-value]

    def dwell(self, seconds: float, tags: tuple[str, ...] = ()) -> Move:
        here = dict(self.position)
        return self._emit(Move("dwell", duration=seconds, **self._common(here, tags)))

    def aux(self, kind: str, value: float, **args: float) -> None:
        self.events.append(Aux(kind, value, self.line, self.block, args=dict(args), program=self.program))  # type: ignore[arg-type]
