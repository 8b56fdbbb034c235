"""Modal state changes of one block: G codes by modal group (plane, units, distance, feed mode,
work system, compensation, cycles, CSS), transforms (G50.1/G51/G68) and distance words.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from nc.alarms import NcAlarm
from nc.interp.state import N_EXT_WCS
from nc.moves import Aux
from nc.program.blocks import Block, Word


# group-01 functions -> the motion mode (a constant: every G0/G1 block sets it)
_MOTION = {"G00": 0, "G01": 1, "G02": 2, "G03": 3, "G2.4": 2.4, "G3.4": 3.4, "G32": 32, "G34": 34}


class ModalMixin:
    def _set_modal(self, grp: int, fn: str, w: Word, block: Block) -> None:
        st = self.state
        st.groups[grp] = w.value
        if grp == 1:
            st.motion = _MOTION[fn]
            if st.cycle is not None:  # a group-01 code cancels the cycle as G80 does
                self.cycle_memory.pop("hole", None)
            st.cycle = None
            if self._three_point is not None and fn not in ("G2.4", "G3.4"):
                # N§3.3.4: the middle-point block is followed by the end-point block
                raise NcAlarm(0x0260, f"{fn} after a G2.4/G3.4 middle point: the end point block is missing")
        elif grp == 2:
            if st.comp != 40 and int(w.value) != st.plane:
                raise NcAlarm(0x1203, "plane change while tool radius compensation is active")
            st.plane = int(w.value)
        elif grp == 3:
            st.absolute = fn == "abs"
        elif grp == 5:
            st.per_rev = fn == "perrev"
        elif grp == 6:
            inch = fn == "inch"
            if inch != st.inch and self.unit_locked:
                raise NcAlarm(0x0207, "G20/G21 may not change while the program runs (N§3.7.3)")
            st.inch = inch
        elif grp == 7:
            if fn != "G40" and not self.profile.is_lathe:
                d = block.get("D")
                if d is None and st.d_number == 0:
                    raise NcAlarm(0x0216, f"{fn} needs D")
            st.comp = int(fn[1:])
        elif grp == 8:
            st.length_comp = int(fn[1:])
            if fn != "G49":
                h = block.get("H")
                if h is None and st.h_number == 0:
                    raise NcAlarm(0x0218, f"{fn} needs H")
                if h is not None:
                    if h.value != int(h.value) or not 0 <= h.value <= 512:
                        raise NcAlarm(0x0219, f"H{h.value:g} out of range")
                    st.h_number = int(h.value)
            self._apply_length_comp()
        elif grp == 9:
            if fn == "G80":
                st.cycle = None
                self.cycle_modal = {}
                self.cycle_memory.pop("hole", None)  # the next hole cycle starts afresh (initial level, R, Q, P)
            else:
                st.cycle = fn
                self.cycle_modal = {x.letter: x.value for x in block.words if x.letter != "G"}
        elif grp == 10:
            st.cycle_return = 98 if fn == "ret98" else 99
        elif grp == 11:
            st.scaling = fn == "scale"
            self._transform(fn, block)
        elif grp == 12:
            p = block.get("P")
            if fn == "G54" and p is not None:
                if p.value != int(p.value):
                    raise NcAlarm(0x0236, "G54 P must be an integer")
                if not 1 <= p.value <= N_EXT_WCS:
                    raise NcAlarm(0x0237, f"G54 P{p.value:g}: extended work systems are P1-P{N_EXT_WCS}")
                st.wcs = 5 + int(p.value)
                st.groups[31] = p.value
            else:
                st.wcs = int(fn[1:]) - 54
                st.groups[31] = 0
        elif grp == 13:
            st.exact_stop_modal = fn == "G61"
        elif grp == 15:
            st.rotation = fn == "G68"
            self._transform(fn, block)
        elif grp == 16:
            st.polar = fn == "G16"
        elif grp == 17:
            st.css = fn == "G96"
        elif grp == 18:
            self._transform(fn, block)

    def _css_switch(self, block: Block) -> Aux:
        """The S aux of a `G96` or `G97` without S (motion decisions 31): G96 resumes the last
        surface speed given under G96 (Fanuc; 0 m/min if none) with the work centre as `G96 S_` does;
        G97 keeps the spindle at the rpm CSS had reached, which the channel fills in (`hold`)."""
        st = self.state
        if not st.css:
            return Aux("S", st.spindle_speed, block.line, block.text, args={"hold": 1.0}, program=self.program_name)
        args = {"css": 1.0}
        if "X" in self.axes:
            args["x0"] = self.frames.origins(st.wcs, self.axes)["X"]
        return Aux("S", st.surface_speed, block.line, block.text, args=args, program=self.program_name)

    def _transform(self, fn: str, block: Block) -> None:
        """Scaling, mirror and rotation belong to `nc.transforms` (issue 4); without it they are
        refused rather than silently ignored."""
        try:
            import nc.transforms as tr  # noqa: F401
        except ImportError:
            if fn in ("scale", "mirror", "G68"):
                raise NcAlarm(0x021D, f"{fn} needs nc.transforms, which this build lacks") from None
            return
        hook = getattr(tr, "modal", None)
        if hook is not None:
            hook(self, fn, block)
        elif fn in ("scale", "mirror", "G68"):
            raise NcAlarm(0x021D, f"{fn}: nc.transforms has no modal(host, fn, block) hook")

    # ---- numbers and geometry ------------------------------------------------------------------
    def distance(self, w: Word, axis: str | None = None) -> float:
        """Apply the decimal-point rule (N8.018 Bit10, decisions A4) and inch input; a rotary
        axis word (``axis`` in profile.rotary_axes) stays in degrees under G20."""
        v = w.value
        if not w.has_point and not self.profile.param("N8.018 Bit10"):
            v *= 0.001
        if self.state.inch and (axis is None or axis not in self.profile.rotary_axes):
            v *= 25.4
        return v

    _distance = distance
