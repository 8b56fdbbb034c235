"""Tool radius / nose radius compensation as a transform of the interpreter's event stream.

The interpreter marks each Move with `comp` ("G41"/"G42"/None), `comp_radius` and `tip`; this
stage replaces the programmed path by the compensated one (decisions A52–A54):

* start-up (first compensated move, a line or rapid): Fanuc type A — its end point is offset
  normal to the start of the next programmed element; an arc cannot start compensation (0x1201);
* between two compensated elements: inner corners are trimmed to the intersection of the offset
  elements, outer corners get an arc of the tool radius around the programmed corner;
* cancel (first move with comp None): the last compensated element ends offset normal to itself,
  the cancel move runs from there to its programmed end; an arc cannot cancel (0x1201);
* moves that do not move in the plane (a Z move under G17, a dwell) and non-motion events are held
  in order while the look-ahead waits for the next element in the plane (unbounded, ≥ 3 blocks);
* lathe: the programmed path is the imaginary tool tip; the output is nose centre + the tip vector
  of the imaginary tip number (0/9 = centre, the output is the nose-centre path).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from nc.alarms import NcAlarm
from nc.compensation import offset as geo
from nc.compensation.nose import tip_vector
from nc.cycles.geometry import Pt, Seg, dist
from nc.moves import Busy, Event, Move, MoveBatch, MoveList, ProgramEnd

PLANE_MOVES = ("rapid", "line", "arc", "thread")


def _plane_pt(m: Move, key: str) -> Pt:
    d = getattr(m, key)
    a1, a2 = m.plane
    return (d[a1], d[a2])


def _seg(m: Move) -> Seg:
    a1, a2 = m.plane
    s, e, c = m.start, m.end, m.center
    if m.kind == "arc" and c is not None:
        return Seg((s[a1], s[a2]), (e[a1], e[a2]), (c[a1], c[a2]), m.dir == "cw", False, m)
    return Seg((s[a1], s[a2]), (e[a1], e[a2]), None, False, m.kind == "rapid", m)


def _moves_in_plane(m: Move) -> bool:
    kind = m.kind
    if kind not in PLANE_MOVES:
        return False
    if kind == "arc":
        return True
    a1, a2 = m.plane
    s, e = m.start, m.end
    return dist((s[a1], s[a2]), (e[a1], e[a2])) > 1e-9


@dataclass(slots=True)
class _Pending:
    move: Move
    seg: Seg
    off: Seg  # whole element offset
    start: Pt  # compensated start (centre)
    startup: bool
    held: list[Event] = field(default_factory=list)  # events after this move, waiting for the next element


class Compensator:
    def __init__(self) -> None:
        self.pending: _Pending | None = None
        self.side = 0.0
        self.radius = 0.0
        self.tip = 0
        self.plane: tuple[str, str] | None = None
        self.out_pos: Pt | None = None  # last emitted centre position (plane)

    # ---- helpers --------------------------------------------------------------------------------
    def _tipv(self) -> Pt:
        return tip_vector(self.tip, self.radius)

    def _with_plane(self, m: Move, start: Pt, end: Pt, center: Pt | None, tip: bool = True,
                    tip_start: bool | None = None) -> Move:
        a1, a2 = m.plane
        tv = self._tipv()
        ts = tv if (tip if tip_start is None else tip_start) else (0.0, 0.0)
        te = tv if tip else (0.0, 0.0)
        s = dict(m.start)
        e = dict(m.end)
        s[a1], s[a2] = start[0] + ts[0], start[1] + ts[1]
        e[a1], e[a2] = end[0] + te[0], end[1] + te[1]
        c = None
        if m.center is not None:
            c = dict(m.center)
            if center is not None:
                c[a1], c[a2] = center[0] + te[0], center[1] + te[1]
        return m.replaced(start=s, end=e, center=c, tags=tuple(m.tags) + ("comp",))

    def _corner_move(self, m: Move, arc: Seg) -> Move:
        a1, a2 = m.plane
        tv = self._tipv()
        s, e, c = dict(m.end), dict(m.end), dict(m.end)
        s[a1], s[a2] = arc.p0[0] + tv[0], arc.p0[1] + tv[1]
        e[a1], e[a2] = arc.p1[0] + tv[0], arc.p1[1] + tv[1]
        c[a1], c[a2] = arc.center[0] + tv[0], arc.center[1] + tv[1]
        kind = "arc"
        return Move(kind, m.line, m.block, s, e, dict(m.work), center=c, dir="cw" if arc.cw else "ccw",
                    feed=m.feed, per_rev=m.per_rev, plane=m.plane, program=m.program,
                    tags=tuple(m.tags) + ("comp", "corner"), comp=m.comp, comp_radius=m.comp_radius, tip=m.tip,
                    css=m.css)

    def _fix_held(self, held: list[Event], at: Pt, tip: bool) -> list[Event]:
        """Moves out of the plane held during look-ahead keep the plane offset."""
        out: list[Event] = []
        tv = self._tipv() if tip else (0.0, 0.0)
        for ev in held:
            if isinstance(ev, Move) and self.plane is not None:
                a1, a2 = self.plane  # a dwell carries a default plane; the compensation plane counts
                s, e = dict(ev.start), dict(ev.end)
                for d in (s, e):
                    if a1 in d and a2 in d:
                        d[a1], d[a2] = at[0] + tv[0], at[1] + tv[1]
                ev = ev.replaced(start=s, end=e)
            out.append(ev)
        return out

    def _flush(self, end: Pt, extra: list[Move] | None = None) -> list[Event]:
        """Emit the pending element ending at `end` (centre), then what it held."""
        p = self.pending
        assert p is not None
        try:
            geo.check_trimmed(p.seg, p.start, end, p.off)
        except NcAlarm as alarm:  # the element that runs backwards is this block's (fuzz21: it had no line)
            raise alarm.at(p.move.line, p.move.block, p.move.program)
        if p.startup:
            out_move = self._with_plane(p.move, p.seg.p0, end, None, tip=True, tip_start=False)
        else:
            out_move = self._with_plane(p.move, p.start, end, p.seg.center)
        res: list[Event] = [out_move]
        res.extend(extra or [])
        last = end
        if extra:
            m_last = extra[-1]
            last = _plane_pt(m_last, "end")
            tv = self._tipv()
            last = (last[0] - tv[0], last[1] - tv[1])
        if p.held:
            res.extend(self._fix_held(p.held, last, True))
        self.pending = None
        self.out_pos = last
        return res

    # ---- the stream -------------------------------------------------------------------------------
    def push(self, ev: Event) -> list[Event]:
        if not isinstance(ev, Move):
            if isinstance(ev, ProgramEnd):
                return self.finish() + [ev]
            if self.pending is not None and not isinstance(ev, Busy):  # a Busy mark passes at once
                self.pending.held.append(ev)
                return []
            return [ev]
        m = ev
        if m.comp not in ("G41", "G42") or m.comp_radius == 0.0:
            return self._uncompensated(m)
        side = 1.0 if m.comp == "G41" else -1.0
        r = m.comp_radius
        if r < 0:  # a negative offset swaps the side (both manuals)
            side, r = -side, -r
        if not _moves_in_plane(m):
            if self.pending is not None:
                self.pending.held.append(m)
                return []
            if self.out_pos is not None and self.plane == m.plane:
                return self._fix_held([m], self.out_pos, True)
            return [m]
        seg = _seg(m)
        if self.pending is None and self.out_pos is None:
            # start-up
            if m.kind == "arc":
                raise NcAlarm(0x1201, "tool radius compensation cannot start on an arc (G02/G03)",
                              line=m.line, block=m.block)
            self.side, self.radius, self.tip, self.plane = side, r, m.tip, m.plane
            self.pending = _Pending(m, seg, seg, seg.p0, True)
            return []
        if self.plane is not None and m.plane != self.plane:
            raise NcAlarm(0x1203, "plane changed while tool radius compensation is active", line=m.line, block=m.block)
        if self.pending is None:
            # compensation continues after a flush at a non-plane block: start from the last centre
            off = geo.offset_seg(seg, side, r)
            self.side, self.radius, self.tip = side, r, m.tip
            self.pending = _Pending(m, seg, off, self.out_pos, False)
            return []
        if (side, r) != (self.side, self.radius):
            if m.kind == "arc" and r != self.radius:
                raise NcAlarm(0x1206, "tool radius changed on an arc block", line=m.line, block=m.block)
            # change of side or radius: end the old offset normal to itself, start the new one normally
            p = self.pending
            end = geo.offset_point(p.seg.p1, p.seg.tangent(1.0), self.side, self.radius) if not p.startup else \
                geo.offset_point(p.seg.p1, seg.tangent(0.0), side, r)
            out = self._flush(end)
            self.side, self.radius, self.tip = side, r, m.tip
            off = geo.offset_seg(seg, side, r)
            self.pending = _Pending(m, seg, off, self.out_pos, False)
            if dist(self.out_pos, off.p0) > 1e-9:
                self.pending.start = self.out_pos
                # a straight move to the new offset start is part of this element's start
                self.pending = _Pending(m, seg, Seg(self.out_pos, off.p1, off.center, off.cw, off.rapid, off.src)
                                        if not seg.is_arc else off,
                                        self.out_pos, False)
            return out
        off = geo.offset_seg(seg, side, r)
        p = self.pending
        try:
            if p.startup:
                end = geo.offset_point(p.seg.p1, seg.tangent(0.0), side, r)
                out = self._flush(end)
                self.pending = _Pending(m, seg, off, end, False)
                return out
            a, b, arc = geo.corner(p.seg, seg, p.off, off, side, r)
        except NcAlarm as alarm:
            raise alarm.at(m.line, m.block, m.program)
        extra = [self._corner_move(p.move, arc)] if arc is not None else None
        out = self._flush(a, extra)
        self.pending = _Pending(m, seg, off, b, False)
        return out

    def _uncompensated(self, m: Move) -> list[Event]:
        if self.pending is None:
            if self.out_pos is not None and _moves_in_plane(m) and self.plane == m.plane:
                # cancel after a flushed element: from the last compensated point
                start = self.out_pos
                tv = self._tipv()
                self.out_pos = None
                a1, a2 = m.plane
                s = dict(m.start)
                s[a1], s[a2] = start[0] + tv[0], start[1] + tv[1]
                return [m.replaced(start=s, tags=tuple(m.tags) + ("comp", "cancel"))]
            if self.out_pos is not None and not _moves_in_plane(m) and m.kind != "dwell":
                return self._fix_held([m], self.out_pos, True)
            return [m]
        if not _moves_in_plane(m):
            self.pending.held.append(m)
            return []
        if m.kind == "arc":
            raise NcAlarm(0x1201, "tool radius compensation cannot be cancelled on an arc (G02/G03)",
                          line=m.line, block=m.block)
        p = self.pending
        if p.startup:
            end = geo.offset_point(p.seg.p1, p.seg.tangent(1.0), self.side, self.radius)
        else:
            end = geo.offset_point(p.seg.p1, p.seg.tangent(1.0), self.side, self.radius)
        cancel_len = dist(_plane_pt(m, "start"), _plane_pt(m, "end"))
        if cancel_len < self.radius - 1e-9:
            raise NcAlarm(0x120B, f"the G40 cancel move ({cancel_len:g}) is shorter than the tool radius "
                                  f"({self.radius:g})", line=m.line, block=m.block)
        out = self._flush(end)
        tv = self._tipv()
        a1, a2 = m.plane
        s = dict(m.start)
        s[a1], s[a2] = end[0] + tv[0], end[1] + tv[1]
        out.append(m.replaced(start=s, tags=tuple(m.tags) + ("comp", "cancel")))
        self.out_pos = None
        return out

    def finish(self) -> list[Event]:
        """End of the stream with compensation still on: the last element ends normal to itself."""
        if self.pending is None:
            self.out_pos = None
            return []
        p = self.pending
        end = geo.offset_point(p.seg.p1, p.seg.tangent(1.0), self.side, self.radius)
        out = self._flush(end)
        return out


_ENABLED = [True]


@contextmanager
def disabled() -> Iterator[None]:
    """Interpret the programmed (uncompensated) path, e.g. to draw it next to the compensated one."""
    _ENABLED.append(False)
    try:
        yield
    finally:
        _ENABLED.pop()


def compensate(events: Iterable[Event], profile: object | None = None, passing: object | None = None) -> Iterator[Event]:
    """Wrap an event stream; moves without `comp` pass through unchanged and in order. `passing` (nc.interp.preview's
    `Passing`) is given the Compensator: the preview window reads the lean lane's runs past this stage while it is
    idle."""
    if not _ENABLED[-1]:
        yield from events
        return
    comp = Compensator()
    if passing is not None:
        passing.comp = comp  # type: ignore[attr-defined]
    for ev in events:
        # idle and not compensated: push would hand the event back as it is (issue 16: a lathe cycle's
        # thousands of moves pass here)
        if comp.pending is None and comp.out_pos is None and (not isinstance(ev, Move) or ev.comp is None):
            yield ev
            continue
        if type(ev) is MoveBatch or type(ev) is MoveList:  # plain uncompensated moves (nc.interp.bulk, a
            # cycle's): through whole when idle
            if comp.pending is None and comp.out_pos is None:
                yield ev
                continue
            for m in ev.moves():
                yield from comp.push(m)
            continue
        yield from comp.push(ev)
    yield from comp.finish()
