"""The one narrow output interface (LinuxCNC canon): work <-> machine conversion and the
emit_* calls that build every Move/Aux the interpreter, cycles and compensation produce.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from collections.abc import Callable

from nc.interp.state import PLANES
from nc.moves import Aux, Event, Move


class CanonicalMixin:
    def work_position(self) -> dict[str, float]:
        """Current position in the active work system, as a program would write it."""
        return self.to_work(self.position)

    def to_work(self, machine: dict[str, float]) -> dict[str, float]:
        origin = self.frames.origins(self.state.wcs, self.axes)
        position, diameter = self.position, self.profile.diameter_axes
        out = {}
        for a in self.axes:
            v = machine.get(a, position.get(a, 0.0)) - origin[a]
            out[a] = v * 2.0 if a in diameter else v
        return out

    def work_converter(self) -> Callable[[dict[str, float]], dict[str, float]]:
        """`to_work` for the offsets in force now, as one comprehension over precomputed (axis, origin,
        factor): a cycle converts every move it makes while no offset can change (issue 16). x * 1.0 is
        x bit for bit, so the result equals `to_work`'s; an end point lacking an axis goes its way."""
        origin = self.frames.origins(self.state.wcs, self.axes)
        diameter = self.profile.diameter_axes
        spec = tuple((a, origin[a], 2.0 if a in diameter else 1.0) for a in self.axes)
        slow = self.to_work
        if len(spec) == 2:  # a lathe's X and Z: the loop written out
            (a1, o1, f1), (a2, o2, f2) = spec

            def convert2(machine: dict[str, float]) -> dict[str, float]:
                try:
                    return {a1: (machine[a1] - o1) * f1, a2: (machine[a2] - o2) * f2}
                except KeyError:
                    return slow(machine)
            return convert2

        def convert(machine: dict[str, float]) -> dict[str, float]:
            out = {}  # a loop, not a comprehension: no function frame per call (a move each)
            try:
                for a, o, f in spec:
                    out[a] = (machine[a] - o) * f
            except KeyError:
                return slow(machine)
            return out
        return convert

    def to_machine(self, work: dict[str, float]) -> dict[str, float]:
        origin = self.frames.origins(self.state.wcs, self.axes)
        diameter = self.profile.diameter_axes
        out = {}
        for a in self.axes:
            v = work.get(a)
            if v is None:
                out[a] = self.position[a]
                continue
            v = v / 2.0 if a in diameter else v
            out[a] = v + origin[a]
        return out

    # ---- emit helpers for cycles ------------------------------------------------------------------
    def _emit(self, kind: str, work: dict[str, float], tags: tuple[str, ...], **kw) -> Move:
        full = self.work_position()
        full.update(work)
        end = self.to_machine(full)
        b = self.block
        mv = Move(kind, b.line if b else 0, b.text if b else "", dict(self.position), end, full,
                  program=self.program_name, plane=PLANES[self.state.plane], tags=tags, **kw)
        self.position = end
        return self._decorate(mv)

    def emit_rapid(self, work: dict[str, float], tags: tuple[str, ...] = ()) -> Move:
        return self._emit("rapid", work, tags)

    def emit_line(self, work: dict[str, float], feed: float | None = None, tags: tuple[str, ...] = (),
                  per_rev: bool | None = None) -> Move:
        return self._emit("line", work, tags, feed=self.feed() if feed is None else feed,
                          per_rev=self.state.per_rev if per_rev is None else per_rev)

    def emit_arc(self, work: dict[str, float], center_work: dict[str, float], cw: bool,
                 feed: float | None = None, tags: tuple[str, ...] = ()) -> Move:
        c = self.to_machine({**self.work_position(), **center_work})
        return self._emit("arc", work, tags, center=c, dir="cw" if cw else "ccw",
                          feed=self.feed() if feed is None else feed, per_rev=self.state.per_rev)

    def emit_thread(self, work: dict[str, float], lead: float, lead_change: float = 0.0,
                    start_angle: float = 0.0, tags: tuple[str, ...] = ()) -> Move:
        return self._emit("thread", work, tags, lead=lead, lead_change=lead_change, start_angle=start_angle,
                          feed=lead, per_rev=True)

    def emit_dwell(self, seconds: float, tags: tuple[str, ...] = ()) -> Move:
        b = self.block
        here = dict(self.position)
        return Move("dwell", b.line if b else 0, b.text if b else "", here, dict(here), self.work_position(),
                    duration=seconds, program=self.program_name, tags=tags)

    def emit_aux(self, kind: str, value: float) -> Event:
        b = self.block
        return Aux(kind, value, b.line if b else 0, b.text if b else "", program=self.program_name)  # type: ignore[arg-type]
