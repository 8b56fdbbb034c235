"""Non-modal G codes of group 0 (G04 G05 G09 G10 G11 G52 G53 G28 G29 G30 G31, G92-style set),
and the tool words: T, tool and length offsets, radius of the D number.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.interp.state import PLANES
from nc.moves import Aux, Event, Move, Sync
from nc.program.blocks import Block, Word


class NonModalMixin:
    # ---- non-modal G codes ---------------------------------------------------------------------
    def _g_G04(self, block: Block) -> Iterator[Event]:
        p = block.get("P")
        x = block.get("X") or (block.get("U") if self.profile.is_lathe else None)
        if p is not None:
            if p.has_point and block.words[block.words.index(p)].has_point and not self._computed(p):
                raise NcAlarm(0x0258, "G04 P takes an integer number of milliseconds")
            seconds = p.value / 1000.0
        elif x is not None:
            scale = 1.0 if (x.has_point or self.profile.param("N1.11 Bit4")) else 0.001
            seconds = x.value * scale
        else:
            raise NcAlarm(0x0222, "G04 needs X (s) or P (ms)")
        if seconds < 0:
            raise NcAlarm(0x0223, "negative dwell time")
        here = dict(self.position)
        dwell = Move("dwell", block.line, block.text, here, dict(here), self.work_position(), duration=seconds,
                     program=self.program_name)
        if self.state.css:  # G96 holds during the dwell: rpm from the surface speed at the current X
            dwell.css = self.state.surface_speed
        yield dwell

    def _computed(self, w: Word) -> bool:
        return not any(ch == "." for ch in w.text) and w.text[1:2] in ("#", "[", "-", "=")

    def _g05_group(self, block: Block) -> int:
        """G05 P: the parameter group 1-20, 0 the original settings (N§3.8.2); its Sync carries it to the
        channel, which switches the planner's settings at rest or raises 0x120D (decision language L25-1)."""
        p = block.get("P")
        if p is None or p.value != int(p.value) or not 0 <= p.value <= 20:
            raise NcAlarm(0x0243, "G05 P must be 0-20")
        return int(p.value)

    def _g_G05(self, block: Block) -> None:
        self.state.groups[0] = 5
        self.param_group = self._g05_group(block)

    def _g_G09(self, block: Block) -> None:
        return None

    def _g_G84_48(self, block: Block) -> Iterator[Event]:
        """G84.48 (N§3.13.2 G84 note (6)): the channel retracts an interrupted tap to its R point at rest, the
        spindle reversed and locked to the pitch, and ends the tapping interrupt status; without the status it does
        nothing (decision mlc M26-3). A preview stop: the blocks after it start from where the retraction ends
        (`Channel.on_retracted` updates `position`)."""
        yield Sync(block.line, block.text, "G84.48", None, self.program_name)

    def _g_G10(self, block: Block) -> Iterator[Event]:
        from nc.interp.datasetting import g10
        yield from g10(self, block)

    def _g_G11(self, block: Block) -> Iterator[Event]:
        from nc.interp.datasetting import g11
        yield from g11(self, block)

    def _g_G900(self, block: Block) -> Iterator[Event]:
        p, q = block.get("P"), block.get("Q")
        if p is None or q is None or not 30200 <= p.value <= 30399 or p.value != int(p.value):
            return  # N§3.8.5: missing or out-of-range P/Q -> the block is ignored
        on = 0.0 if q.value == 0 else 1.0
        yield Aux("G900", p.value, block.line, block.text, args={"Q": on}, wait=False, program=self.program_name)

    def _g_G52(self, block: Block) -> None:
        words = self._axis_words(block)
        # N§3.6.2: "only valid in G90 absolute mode and cannot be used in G91"; L§G52: "valid only when set with
        # absolute values": a shift given incrementally (G91 or U/W) is refused, not taken as absolute (language.md)
        inc = [w.text for w, i in words.values() if i or not self.state.absolute]
        if inc:
            raise NcAlarm(0x0207, f"G52 takes absolute values only (G90); {' '.join(inc)} is incremental")
        for a, (w, _inc) in words.items():
            v = self.distance(w, a)
            self.frames.local_shift[a] = v / 2.0 if a in self.profile.diameter_axes else v

    def _g_set(self, block: Block) -> Iterator[Event]:
        """G92 (mill, lathe B/C) / G50 (lathe A): coordinate setting, and S = max spindle speed."""
        s = block.get("S")
        if s is not None:
            self.state.spindle_max = s.value
            yield Aux("S", s.value, block.line, block.text, args={"max": 1.0}, program=self.program_name)
        words = self._axis_words(block)
        for a, (w, inc) in words.items():
            v = self.distance(w, a)
            cur = self.work_position()[a]
            want = cur + v if inc else v
            m = want / 2.0 if a in self.profile.diameter_axes else want
            base = self.frames.origin(self.state.wcs, a) - self.frames.set_shift.get(a, 0.0)
            self.frames.set_shift[a] = self.position[a] - m - base
        self.last_target = self.work_position()

    def _g_G53(self, block: Block) -> Iterator[Event]:
        """Machine-coordinate rapid; ignored in incremental mode but its modal codes apply (7.3.7).

        Executed (G90), it ends length compensation / the lathe tool offset for good, also without a move,
        so its work point is without them; radius compensation sits out this move only (N§3.6.3 note 4)."""
        if not self.state.absolute:
            return
        words = self._axis_words(block)
        if any(inc for _, inc in words.values()):
            return
        self._need_origin(words, "G53")
        self._end_length_offsets()
        self.last_target = self.work_position()
        end = dict(self.position)
        for a, (w, _inc) in words.items():
            v = self.distance(w, a)
            end[a] = v / 2.0 if a in self.profile.diameter_axes else v
        if end == self.position:
            return
        mv = Move("rapid", block.line, block.text, dict(self.position), end, self.to_work(end),
                  program=self.program_name, plane=PLANES[self.state.plane], tags=("G53",))
        self.position = end
        self.last_target = self.work_position()
        self.unit_locked = True
        mv = self._decorate(mv, exact=True)
        mv.comp, mv.comp_radius, mv.tip = None, 0.0, 0  # state.comp stays: the next motion block restarts it
        yield mv

    def _end_length_offsets(self) -> None:
        """G28/G30/G53: mill G43/G44 back to G49, lathe tool offset number cleared (tool number kept)."""
        if self.profile.is_lathe:
            self.state.tool_offset = 0  # N§3.10.1
            self._apply_tool_offset()
        elif self.state.length_comp != 49:
            self.state.length_comp = 49
            self.state.groups[8] = 49
            self._apply_length_comp()

    def _reference(self, n: int) -> dict[str, float]:
        key = {1: "N2.060", 2: "N2.061", 3: "N2.062", 4: "N2.063"}[n]
        return {a: self.profile.param(f"{key} {a}", 0.0) for a in self.axes}

    def _g_G28(self, block: Block, ref: int = 1) -> Iterator[Event]:
        words = self._axis_words(block)
        if not words:
            raise NcAlarm(0x0253, "G28/G30 needs the intermediate point of at least one axis")
        self._need_origin(words, "G28" if ref == 1 else f"G30 P{ref}")
        g = self._geometry(block)
        via = {a: g.target_machine[a] for a in words}
        self.reference_via = dict(via)
        refpt = self._reference(ref)
        tag = "G28" if ref == 1 else f"G30P{ref}"
        mid = dict(self.position)
        mid.update(via)
        # Radius compensation sits out the return (its moves carry none) and the next motion block
        # restarts it (N§3.5.1, N§3.9 note 4; L§2.1 G28): state.comp stays.
        if mid != self.position:
            mv = Move("rapid", block.line, block.text, dict(self.position), dict(mid), self.to_work(mid),
                      program=self.program_name, plane=PLANES[self.state.plane], tags=(tag, "intermediate"))
            self.position = mid
            yield mv
        end = dict(self.position)
        for a in words:
            end[a] = refpt[a]
        self.unit_locked = True
        # the offsets end at the intermediate point (N§3.5.1), also when the axes already stand at the
        # reference point; the reference move's work point is therefore without them
        self._end_length_offsets()  # G28/G30 clear the tool offset number too (N§3.10.1)
        self.last_target = self.work_position()
        if end == self.position:
            return
        mv = Move("rapid", block.line, block.text, dict(self.position), end, self.to_work(end),
                  program=self.program_name, plane=PLANES[self.state.plane], tags=(tag, "reference"),
                  exact_stop=True)
        self.position = end
        self.last_target = self.work_position()
        yield mv

    def _need_origin(self, words: dict, what: str) -> None:
        """App. A 0x0A08 "Origin status of the axis is missing. Please execute the homing operation.": a move
        to machine coordinates (the reference point N2.060-N2.063, G53's machine position) needs the axis's
        origin; L§G53: "before using G53 ... please complete the homing procedure"."""
        missing = [a for a in self.axes if a in words and a in self.unreferenced]
        if missing:
            raise NcAlarm(0x0A08, f"{what}: axis {', '.join(missing)} has no origin (not homed: run without "
                                  f"--no-home, or home it first)", axis=missing[0])

    def _g_G30(self, block: Block) -> Iterator[Event]:
        p = block.get("P")
        n = 2 if p is None else int(p.value)
        if n not in (2, 3, 4) or (p is not None and p.value != int(p.value)):
            raise NcAlarm(0x0243, "G30 P must be 2, 3 or 4")
        yield from self._g_G28(block, n)

    def _g_G29(self, block: Block) -> Iterator[Event]:
        if self.reference_via is None:
            raise NcAlarm(0x0253, "G29 without a previous G28/G30")
        words = self._axis_words(block)
        via = dict(self.position)
        via.update({a: self.reference_via.get(a, self.position[a]) for a in words})
        if via != self.position:
            mv = Move("rapid", block.line, block.text, dict(self.position), dict(via), self.to_work(via),
                      program=self.program_name, plane=PLANES[self.state.plane], tags=("G29", "intermediate"))
            self.position = via
            yield mv
        # in G91 the increments count from the intermediate point (E-N13)
        g = self._geometry(block, base=self.to_work(via))
        mv = Move("rapid", block.line, block.text, dict(self.position), dict(g.target_machine),
                  dict(g.target_work), program=self.program_name, plane=PLANES[self.state.plane], tags=("G29",))
        self.position = dict(g.target_machine)
        self.last_target = dict(g.target_work)
        yield mv

    def _g_G31(self, block: Block) -> Iterator[Event]:
        if self.state.comp in (41, 42):
            raise NcAlarm(0x0207, "G31 is not allowed while G41/G42 is active")
        p = block.get("P")
        mask = 0 if p is None else int(p.value)
        if p is not None and not 0 <= mask <= 255:
            raise NcAlarm(0x024E, f"G31 P{mask}: HSI mask is 0-255")
        g = self._geometry(block)
        if not g.moved:
            return
        f = block.get("F")
        feed = f.value * (25.4 if self.state.inch else 1.0) if f is not None else (
            self.profile.param("N1.027", 0.0) or self.feed())
        common = self._move_common(block, g.target_machine, g.target_work)
        mv = Move("line", feed=feed, per_rev=False, tags=("G31", f"P{mask}"), exact_stop=True, **common)
        self.skip_position = None
        self.position = dict(g.target_machine)
        self.last_target = dict(g.target_work)
        yield mv
        yield Sync(block.line, block.text, "G31 skip position")

    # ---- S / T / tools ----------------------------------------------------------------------
    def _tool(self, block: Block, t: Word) -> Iterator[Event]:
        st = self.state
        if t.value < 0 or t.value != int(t.value) or t.value > 9999_9999:
            raise NcAlarm(0x021C, f"T{t.value:g} out of range")
        v = int(t.value)
        st.tool = v
        if self.profile.is_lathe:
            if v >= 100:
                st.tool_offset = v % 100
                tool_no = v // 100
            else:
                st.tool_offset = v  # decisions: T3 = tool 3 with offset 3
                tool_no = v
            if st.tool_offset > 64 and self.profile.legacy:
                raise NcAlarm(0x021A, f"T{v}: offset number above 64")
            self._apply_tool_offset()
        else:
            tool_no = v
        yield Aux("T", t.value, block.line, block.text, args={"tool": float(tool_no)}, program=self.program_name)

    def _apply_tool_offset(self) -> None:
        k = self.state.tool_offset
        shift = {}
        for a in self.axes:
            v = self.tools.length(a, k) + self.tools.wear(a, k) if k else 0.0
            shift[a] = v / 2.0 if a in self.profile.diameter_axes else v
        self.frames.tool_shift = shift

    def _apply_length_comp(self) -> None:
        st = self.state
        if self.profile.is_lathe:
            return
        z = "Z" if "Z" in self.axes else self.axes[-1]
        if st.length_comp == 49 or st.h_number == 0:
            self.frames.tool_shift = {}
            return
        h = self.tools.length(z, st.h_number) + self.tools.wear(z, st.h_number)
        self.frames.tool_shift = {z: h if st.length_comp == 43 else -h}

    def _comp_radius(self) -> tuple[float, int]:
        st = self.state
        if self.profile.is_lathe:
            k = st.tool_offset
            return self.tools.radius.get(k, 0.0) + self.tools.radius_wear.get(k, 0.0), int(self.tools.tip.get(k, 0))
        d = st.d_number
        return self.tools.radius.get(d, 0.0) + self.tools.radius_wear.get(d, 0.0), 0
