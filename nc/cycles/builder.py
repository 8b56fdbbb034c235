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

    def _same(self, p: Pt) -> bool:
        """A move shorter than float noise is dropped; the position snaps to the exact target."""
        if abs(p[0] - self.here[0]) < 1e-12 and abs(p[1] - self.here[1]) < 1e-12:
            self.position[self.plane[0]], self.position[self.plane[1]] = p
            return True
        return False

    def rapid(self, p: Pt, tags: tuple[str, ...] = ()) -> Move | None:
        if self._same(p):
            return None
        return self._emit(Move("rapid", **self._common(self._end(p), tags)))

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
        if self._same(p):
            return None
        return self._emit(Move("line", feed=feed if feed is not None else self.feed, per_rev=self.per_rev,
                               **self._common(self._end(p), tags)))

    def seg(self, s: Seg, tags: tuple[str, ...] = (), feed: float | None = None, rapid: bool | None = None) -> Move | None:
        """Add a contour element (the builder must already be at its start)."""
        if rapid if rapid is not None else s.rapid:
            return self.rapid(s.p1, tags)
        if not s.is_arc:
            return self.feed_to(s.p1, tags, feed)
        end = self._end(s.p1)
        centre = dict(end)
        centre[self.plane[0]], centre[self.plane[1]] = s.center
        return self._emit(Move("arc", center=centre, dir="cw" if s.cw else "ccw",
                               feed=feed if feed is not None else self.feed, per_rev=self.per_rev,
                               **self._common(end, tags)))

    def thread(self, p: Pt, lead: float, start_angle: float, tags: tuple[str, ...] = (),
               lead_change: float = 0.0) -> Move:
        return self._emit(Move("thread", lead=lead, lead_change=lead_change, start_angle=start_angle,
                               feed=lead, per_rev=True, **self._common(self._end(p), tags)))

    def dwell(self, seconds: float, tags: tuple[str, ...] = ()) -> Move:
        here = dict(self.position)
        return self._emit(Move("dwell", duration=seconds, **self._common(here, tags)))

    def aux(self, kind: str, value: float, **args: float) -> None:
        self.events.append(Aux(kind, value, self.line, self.block, args=dict(args), program=self.program))  # type: ignore[arg-type]
