"""The motion of one block: target from axis words (units, diameter, incremental U/W, polar,
,A angles), lines, arcs (R, IJK, three-point G2.4/G3.4), threads and the move decoration.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

import math

from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.interp import context
from nc.interp.arcs import center_from_radius, check_center, sweep
from nc.interp.state import PLANES
from nc.moves import Event, Move
from nc.program.blocks import Block, Word
from nc.interp.records import CHORD_TOL_3D, INCREMENTAL, _Geometry, _transforms


_AXIS_LETTERS: dict[tuple, tuple[tuple[str, str | None], ...]] = {}


class MotionMixin:
    def _axis_words(self, block: Block) -> dict[str, tuple[Word, bool]]:
        """axis -> (word, incremental) from X/Y/Z/… and the U/V/W/H incremental addresses (A5)."""
        cached = self.__dict__.get("_axis_pairs")
        if cached is None or cached[0] is not self.axes or cached[1] is not self.profile:
            key = (self.axes, self.profile.is_lathe)
            pairs = _AXIS_LETTERS.get(key)
            if pairs is None:  # (axis, its incremental letter or None) per axes and machine type, found once
                incs = {v: k for k, v in reversed(INCREMENTAL.items())}  # the first letter naming an axis
                pairs = _AXIS_LETTERS[key] = tuple(
                    (a, (incs.get(a) if incs.get(a) not in self.axes else None) if key[1] else None)
                    for a in self.axes)
            letters = frozenset(a for pair in pairs for a in pair if a is not None)
            cached = self._axis_pairs = (self.axes, self.profile, pairs, letters)
        # the block's axis words in one pass, the last of a letter winning as `Block.get` finds it (A9)
        found: dict[str, Word] = {}
        letters = cached[3]
        for w in block.words:
            if w.letter in letters:
                found[w.letter] = w
        out: dict[str, tuple[Word, bool]] = {}
        if not found:
            return out
        for a, inc_letter in cached[2]:
            w_abs = found.get(a)
            w_inc = found.get(inc_letter) if inc_letter else None
            if w_abs is not None and w_inc is not None:
                raise NcAlarm(0x0202, f"{a} and {inc_letter} in one block")
            if w_abs is not None:
                out[a] = (w_abs, not self.state.absolute)
            elif w_inc is not None:
                out[a] = (w_inc, True)
        return out

    def _geometry(self, block: Block, base: dict[str, float] | None = None) -> _Geometry:
        st = self.state
        tr = _transforms(self)
        if tr is None and base is None and not block.comma and (not st.polar or self.profile.is_lathe):
            return self._plain_geometry(block)
        work = dict(base) if base is not None else self.work_position()
        if tr is not None:
            work = tr.inverse(self, work)  # incremental moves count in the programmed frame
        words = self._axis_words(block)
        if st.polar and not self.profile.is_lathe:
            return self._polar_geometry(block, work, words)
        for a, (w, inc) in words.items():
            v = self.distance(w, a)
            work[a] = work[a] + v if inc else v
        axes = set(words)
        if "A" in block.comma and len(axes & set(PLANES[st.plane])) == 1:
            self._linear_angle(block, work, axes)
        machine = self.to_machine(tr.apply(self, work) if tr is not None else work)
        for a in self.axes:
            if not math.isfinite(machine[a]) or abs(machine[a]) > 1e9:
                raise NcAlarm(0x120E, f"{a} target is out of range")
        return _Geometry(work, machine, bool(words), axes)

    def _plain_geometry(self, block: Block) -> _Geometry:
        """`_geometry` without transforms, polar mode or ,A (every block of a usual program, issue 16):
        `work_position`, `to_machine` and the range check in one pass over the axes, the origins
        looked up once (the same dict both would get)."""
        axes = self.axes
        origin = self.frames.origins(self.state.wcs, axes)
        diameter = self.profile.diameter_axes
        position = self.position
        work = {}
        for a in axes:
            v = position.get(a, 0.0) - origin[a]
            work[a] = v * 2.0 if a in diameter else v
        words = self._axis_words(block)
        inch = self.state.inch
        for a, (w, inc) in words.items():
            v = w.value if w.has_point and not inch else self.distance(w, a)  # `distance` keeps such a value
            work[a] = work[a] + v if inc else v
        machine = {}
        for a in axes:
            v = work[a]
            v = (v / 2.0 if a in diameter else v) + origin[a]
            if not math.isfinite(v) or abs(v) > 1e9:
                raise NcAlarm(0x120E, f"{a} target is out of range")
            machine[a] = v
        return _Geometry(work, machine, bool(words), set(words))

    def _polar_geometry(self, block: Block, work: dict[str, float], words) -> _Geometry:
        a1, a2 = PLANES[self.state.plane]
        r0 = math.hypot(work.get(a1, 0.0), work.get(a2, 0.0))
        t0 = math.degrees(math.atan2(work.get(a2, 0.0), work.get(a1, 0.0)))
        r, t = r0, t0
        for a, (w, inc) in words.items():
            if a == a1:
                r = r + self.distance(w) if inc else self.distance(w)
            elif a == a2:
                t = t + w.value if inc else w.value  # angles are degrees as written
            else:
                v = self.distance(w, a)
                work[a] = work[a] + v if inc else v
        if a1 in words or a2 in words:
            work[a1] = r * math.cos(math.radians(t))
            work[a2] = r * math.sin(math.radians(t))
        return _Geometry(work, self.to_machine(work), bool(words), set(words))

    def _linear_angle(self, block: Block, work: dict[str, float], axes: set[str]) -> None:
        """`,A`: the other plane coordinate from the angle measured from the plane's first axis (A32)."""
        a1, a2 = PLANES[self.state.plane]
        start = self.work_position()
        ang = math.radians(block.comma["A"])
        k2 = 0.5 if a2 in self.profile.diameter_axes else 1.0
        k1 = 0.5 if a1 in self.profile.diameter_axes else 1.0
        if a1 in axes:
            d1 = (work[a1] - start[a1]) * k1
            work[a2] = start[a2] + d1 * math.tan(ang) / k2
        else:
            t = math.tan(ang)
            if abs(t) < 1e-12:
                raise NcAlarm(0x0207, ",A parallel to the given axis")
            d2 = (work[a2] - start[a2]) * k2
            work[a1] = start[a1] + d2 / t / k1
        axes.update((a1, a2))

    def target(self, block: Block) -> dict[str, float]:
        """Programmed end point of the block's axis words (work coordinates, after transforms)."""
        g = self._geometry(block)
        return self.to_work(g.target_machine)

    # ---- motion ------------------------------------------------------------------------
    def feed(self, block: Block | None = None) -> float:
        st = self.state
        feed = st.feed
        if feed is None or feed == 0.0:
            default = self.profile.param("N1.042")
            if default > 0 and not st.per_rev:
                return default
            raise NcAlarm(0x1001, "no F programmed for a cutting move")
        return feed * (25.4 if st.inch else 1.0)

    _feed = feed

    def _move_common(self, block: Block, end: dict[str, float], work: dict[str, float]) -> dict:
        st = self.state
        common = dict(line=block.line, block=block.text, start=dict(self.position), end=dict(end), work=dict(work),
                      program=self.program_name, plane=PLANES[st.plane])
        return common

    def _decorate(self, move: Move, exact: bool = False) -> Move:
        st = self.state
        move.exact_stop = exact or st.exact_stop_modal
        if st.comp in (41, 42):
            move.comp = f"G{st.comp}"
            tr = _transforms(self)
            if tr is not None:
                move.comp = tr.comp_code(self, move.plane, move.comp)
            move.comp_radius, move.tip = self._comp_radius()
        if st.css:
            move.css = st.surface_speed
        return move

    def _length_comp_move(self, geo: _Geometry) -> _Geometry:
        """N§3.12.2 note (3), parameter [N1.010]: 0 (default) moves the tool to the compensated position in
        a G43/G44/G49 block without Z (the programmed Z is kept, the machine Z takes the new length); 1 only
        changes the offset internally, the next Z move takes it up."""
        z = "Z" if "Z" in self.axes else self.axes[-1]
        if self.profile.is_lathe or z in geo.axes or self.profile.param("N1.010", 0.0) != 0:
            return geo
        work = dict(geo.target_work)
        work[z] = self.last_target.get(z, work[z])
        machine = self.to_machine(work)
        moved = geo.moved or abs(machine[z] - self.position[z]) > 1e-12
        return _Geometry(work, machine, moved, geo.axes | ({z} if moved else set()))

    def _motion(self, block: Block, funcs: set[str]) -> Iterator[Event]:
        st = self.state
        if "G04" in funcs:
            return
        cyc = st.cycle
        # N§3.3.4 note (1): under G91 the end point of G2.4/G3.4 counts from the middle point
        mid = self._three_point
        geo = self._geometry(block, base=None if mid is None else self.to_work(mid))
        if funcs & {"G43", "G44", "G49"}:
            geo = self._length_comp_move(geo)
        if cyc is not None and not (funcs & {"G00", "G01", "G02", "G03"}):
            if geo.moved or self._cycle_fn(funcs):
                self.unit_locked = True
                yield from context.run_cycle(self, cyc, block)
                self.last_target = self.work_position()
            return
        if st.motion in (32, 34) and geo.moved:
            self.unit_locked = True
            yield from self._thread(block, geo, "G32" if st.motion == 32 else "G34")
            return
        if st.motion == 1 and "A" in block.comma:
            a1, a2 = PLANES[st.plane]
            if not geo.axes & {a1, a2}:  # `,A1` alone: its end is the intersection with the next block
                if geo.axes:  # only axes outside the plane: an angle in the plane cannot apply to them
                    raise NcAlarm(0x0207, f",A needs an end coordinate in the active plane ({a1}/{a2}), "
                                          f"not only {'/'.join(sorted(geo.axes))}")
                if "C" in block.comma or "R" in block.comma:
                    raise NcAlarm(0x021D, "the two-block ,A form with ,C/,R is not supported")
                self._angle_pending = (block, self._move_common(block, geo.target_machine, geo.target_work))
                return
            if self._angle_pending is not None:
                yield from self._angle_intersection(block, geo)
        if self._angle_pending is not None:
            raise NcAlarm(0x0207, ",A without an end point must be followed by G01 with both plane "
                          "coordinates and ,A", line=self._angle_pending[0].line, block=self._angle_pending[0].text)
        if not geo.moved:
            has_centre = block.has("I") or block.has("J") or block.has("K")
            if st.motion in (2, 3) and has_centre and funcs & {"G02", "G03"} | ({"G02", "G03"} if has_centre else set()):
                pass  # full circle with centre words and no end point
            else:
                return
        self.unit_locked = True
        exact = "G09" in funcs
        motion = st.motion
        if motion == 0 or motion == 1:  # `_move_common`'s fields, positionally (no dict per block); the
            # target dicts are this block's own (no stage changes a move's points in place)
            move = Move("rapid" if motion == 0 else "line", block.line, block.text, dict(self.position),
                        geo.target_machine, geo.target_work, None, None,
                        self.feed() if motion == 1 else None, None, st.per_rev if motion == 1 else False,
                        PLANES[st.plane], False, None, 0.0, 0.0, 0.0, self.program_name)
            self.position = dict(geo.target_machine)
            self.last_target = dict(geo.target_work)
            yield self._decorate(move, exact)
            return
        common = self._move_common(block, geo.target_machine, geo.target_work)
        if st.motion in (2.4, 3.4):
            yield from self._three_point_arc(block, geo, common)
            return
        move = self._arc(block, common)
        if move is None:
            return
        self.position = dict(geo.target_machine)
        self.last_target = dict(geo.target_work)
        yield self._decorate(move, exact)

    def _angle_intersection(self, block: Block, geo: _Geometry) -> Iterator[Event]:
        """Two-block `,A` (L l.2449 pattern 2): the held block runs from the start at its angle to the
        intersection with the line into this block's end point at this block's angle (A32)."""
        first, common = self._angle_pending  # type: ignore[misc]
        self._angle_pending = None
        a1, a2 = PLANES[self.state.plane]
        s = (self.position[a1], self.position[a2])  # machine coordinates (lathe X radius)
        e = (geo.target_machine[a1], geo.target_machine[a2])
        t1, t2 = math.radians(first.comma["A"]), math.radians(block.comma["A"])
        d1, d2 = (math.cos(t1), math.sin(t1)), (math.cos(t2), math.sin(t2))
        den = d1[0] * d2[1] - d1[1] * d2[0]
        if abs(den) < 1e-12:
            raise NcAlarm(0x0207, "the two ,A lines are parallel")
        t = ((e[0] - s[0]) * d2[1] - (e[1] - s[1]) * d2[0]) / den
        mid = dict(self.position)
        mid[a1], mid[a2] = s[0] + d1[0] * t, s[1] + d1[1] * t
        common.update(start=dict(self.position), end=dict(mid), work=self.to_work(mid))
        move = Move("line", feed=self.feed(), per_rev=self.state.per_rev, **common)
        self.position = dict(mid)
        yield self._decorate(move)

    def _thread(self, block: Block, geo: _Geometry, fn: str) -> Iterator[Event]:
        if context.cycle_runner() is not None:
            yield from context.run_cycle(self, fn, block)
            return
        f = block.get("F")
        lead = self.distance(f) if f is not None and f.has_point else (f.value if f is not None else self.feed())
        if f is not None:
            self.state.feed = f.value
        q = block.get("Q")
        k = block.get("K")
        common = self._move_common(block, geo.target_machine, geo.target_work)
        move = Move("thread", lead=lead, lead_change=self.distance(k) if (k and fn == "G34") else 0.0,
                    start_angle=(q.value * 0.001 if q is not None and not q.has_point else (q.value if q else 0.0)),
                    per_rev=True, feed=lead, tags=(fn,), **common)
        self.position = dict(geo.target_machine)
        self.last_target = dict(geo.target_work)
        yield self._decorate(move)

    def _arc(self, block: Block, common: dict) -> Move | None:
        st = self.state
        a1, a2 = PLANES[st.plane]
        if a1 not in self.axes or a2 not in self.axes:
            raise NcAlarm(0x025D, f"G{st.plane} plane needs axes {a1} and {a2}")
        cw = st.motion == 2
        tr = _transforms(self)
        if tr is not None:
            cw = tr.arc_cw(self, (a1, a2), cw)
        start, end = common["start"], common["end"]
        s = (start[a1], start[a2])
        e = (end[a1], end[a2])
        tol = self.profile.param("N1.040", 0.01)
        r = block.get("R")
        centre_letter = {"X": "I", "Y": "J", "Z": "K"}
        ci, cj = block.get(centre_letter[a1]), block.get(centre_letter[a2])
        if r is not None:  # R wins over I/J/K (N§3.3.3)
            if math.hypot(e[0] - s[0], e[1] - s[1]) < 1e-9:
                return None  # full circle in R format: the tool does not move (A30)
            # G51 scales the arc with its end points: R too (fuzz21; unequal plane ratios are 0x025F)
            k = tr.radius_scale(self, (a1, a2)) if tr is not None else 1.0
            c = center_from_radius(s, e, self.distance(r) * k, cw, tol)
        elif ci is not None or cj is not None:
            # I/J/K are always radius values from the start point (decisions A6)
            c = (s[0] + (self.distance(ci) if ci else 0.0), s[1] + (self.distance(cj) if cj else 0.0))
            if tr is not None:  # the centre is a programmed point: take it through the transforms
                pw = tr.inverse(self, self.to_work(start))
                k1 = 2.0 if a1 in self.profile.diameter_axes else 1.0
                k2 = 2.0 if a2 in self.profile.diameter_axes else 1.0
                pw[a1] += (self.distance(ci) if ci else 0.0) * k1
                pw[a2] += (self.distance(cj) if cj else 0.0) * k2
                cm = self.to_machine(tr.apply(self, pw))
                c = (cm[a1], cm[a2])
            check_center(s, e, c, tol)
            self.last_arc_ijk = (self.distance(ci) if ci else 0.0, self.distance(cj) if cj else 0.0, 0.0)
        else:
            # no R/I/J/K: the path is a straight line (N§3.3.3)
            return Move("line", feed=self.feed(), per_rev=st.per_rev, **common)
        sweep(s, e, c, cw)  # validates
        centre = {a: end[a] for a in self.axes}
        centre[a1], centre[a2] = c
        p = block.get("P") if any(a not in (a1, a2) and block.has(a) for a in self.axes) else None
        move = Move("arc", center=centre, dir="cw" if cw else "ccw", feed=self.feed(), per_rev=st.per_rev,
                    **common)
        if p is not None:
            move.turns = float(int(p.value))
        return move

    def _three_point_arc(self, block: Block, geo: _Geometry, common: dict) -> Iterator[Event]:
        """G2.4/G3.4: first block = middle point, second = end point (N§3.3.4, A31)."""
        if self._three_point is None:
            self._three_point = dict(geo.target_machine)
            self.last_target = dict(geo.target_work)
            return
        mid = self._three_point
        self._three_point = None
        p0 = [self.position[a] for a in self.axes]
        p1 = [mid[a] for a in self.axes]
        p2 = [geo.target_machine[a] for a in self.axes]
        import numpy as np
        a, b, c = np.array(p0), np.array(p1), np.array(p2)
        u, v = b - a, c - a
        w = np.cross(u, v) if len(a) == 3 else None
        if w is None or np.linalg.norm(w) < 1e-9:
            raise NcAlarm(0x025B, "G2.4/G3.4 points are collinear or the machine has no 3 axes")
        ww = float(np.dot(w, w))
        centre = a + (np.cross(w, u) * float(np.dot(v, v)) + np.cross(v, w) * float(np.dot(u, u))) / (2 * ww)
        radius = float(np.linalg.norm(a - centre))
        n = w / math.sqrt(ww)
        e1 = (a - centre) / radius
        e2 = np.cross(n, e1)
        ang_end = math.atan2(float(np.dot(c - centre, e2)), float(np.dot(c - centre, e1))) % (2 * math.pi)
        # chords whose sagitta stays within CHORD_TOL_3D of the true arc (every vertex is on the circle)
        step = 2.0 * math.acos(max(-1.0, 1.0 - CHORD_TOL_3D / radius)) if radius > CHORD_TOL_3D else math.pi / 2
        segs = max(4, int(math.ceil(ang_end / min(step, math.radians(2.0)))))
        feed = self.feed()
        for i in range(1, segs + 1):
            t = ang_end * i / segs
            pt = centre + radius * (math.cos(t) * e1 + math.sin(t) * e2)
            end = {ax: float(pt[k]) for k, ax in enumerate(self.axes)}
            mv = Move("line", block.line, block.text, dict(self.position), end, self.to_work(end), feed=feed,
                      per_rev=self.state.per_rev, program=self.program_name, plane=PLANES[self.state.plane],
                      tags=("G2.4" if self.state.motion == 2.4 else "G3.4",))
            self.position = end
            yield self._decorate(mv)
        self.last_target = dict(geo.target_work)
