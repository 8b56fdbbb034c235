"""The block executor: turns parsed blocks into canonical events in machine coordinates.

The interpreter is a generator so the channel can pull it block by block and stop reading
ahead where the controller would (a `Sync` event).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.interp.arcs import center_from_radius, check_center, sweep
from nc.interp.state import PLANES, Frames, ModalState
from nc.interp.variables import Variables
from nc.moves import Aux, Event, Move, ProgramEnd
from nc.profiles import Profile
from nc.program.blocks import Block, Program, Word

MOTION_G = {0, 1, 2, 3}
# G codes of the skeleton subset with their modal group (0 = one-shot)
G_GROUP: dict[int, int] = {0: 1, 1: 1, 2: 1, 3: 1, 4: 0, 17: 2, 18: 2, 19: 2, 20: 6, 21: 6, 98: 5, 99: 5}
M_BEFORE_MOTION = {3, 4, 8, 19}  # issued to the MLC before the block's motion starts
M_END = {2, 30}
MAX_M_PER_BLOCK = 4
DISTANCE_LETTERS = set("XYZUVWIJKRABCH")
INCREMENTAL = {"U": "X", "V": "Y", "W": "Z", "H": "C"}


@dataclass
class _Geometry:
    """Per-block numbers after unit, diameter and decimal-point rules."""

    target_work: dict[str, float]
    target_machine: dict[str, float]
    moved: bool


class Interpreter:
    def __init__(self, profile: Profile, start: dict[str, float] | None = None) -> None:
        self.profile = profile
        self.axes = profile.axes
        self.state = ModalState.power_on(profile)
        self.frames = Frames(self.axes)
        self.position: dict[str, float] = {a: 0.0 for a in self.axes}  # machine, as the axis travels
        if start:
            self.position.update(start)
        self.program_name = ""
        self.vars = Variables()

    def variable(self, number: int) -> float | None:
        return self.vars.get(number)

    # ---- public ---------------------------------------------------------------------------
    def run(self, program: Program) -> Iterator[Event]:
        self.program_name = program.name
        for block in program.blocks:
            if block.skip:
                continue  # block skip switch M2x010 is off by default (decisions A8); see channel
            try:
                for ev in self.execute(block):
                    yield ev
                    if isinstance(ev, ProgramEnd):
                        return
            except NcAlarm as alarm:
                raise alarm.at(block.line, block.text, program.name) from None
            except (ValueError, ArithmeticError, OverflowError) as exc:
                raise NcAlarm(0x0257, f"numerical error: {exc}", line=block.line, block=block.text,
                              program=program.name) from None
        last = program.blocks[-1] if program.blocks else None
        yield ProgramEnd(last.line if last else 0, last.text if last else "", 0)

    def work_position(self) -> dict[str, float]:
        """Current position in the active work system, as a program would write it."""
        out = {}
        for a in self.axes:
            v = self.position[a] - self.frames.origin(self.state.wcs, a)
            out[a] = v * 2.0 if a in self.profile.diameter_axes else v
        return out

    # ---- block execution --------------------------------------------------------------------
    def execute(self, block: Block) -> Iterator[Event]:
        st = self.state
        gcodes = self._gcodes(block)
        self._check_letters(block)
        one_shot: set[int] = set()
        for g in gcodes:
            grp = G_GROUP[g]
            if grp == 0:
                one_shot.add(g)
            elif grp == 1:
                st.motion = g
            elif grp == 2:
                st.plane = g
            elif grp == 6:
                st.inch = g == 20
            elif grp == 5:
                st.per_rev = g == 99

        f = block.get("F")
        if f is not None:
            if f.value < 0:
                raise NcAlarm(0x0223, "F must not be negative")
            st.feed = f.value
        s = block.get("S")
        t = block.get("T")
        mcodes = [int(w.value) for w in block.all("M")]
        if len(mcodes) > MAX_M_PER_BLOCK:
            raise NcAlarm(0x0248, f"{len(mcodes)} M codes in one block (at most {MAX_M_PER_BLOCK})")

        if s is not None:
            st.spindle_speed = s.value
            yield Aux("S", s.value, block.line, block.text, program=self.program_name)
        if t is not None:
            st.tool = int(t.value)
            yield Aux("T", t.value, block.line, block.text, program=self.program_name)
        for m in mcodes:
            if m in M_BEFORE_MOTION:
                if m in (3, 4):
                    st.spindle_dir = 1 if m == 3 else -1
                yield Aux("M", m, block.line, block.text, program=self.program_name)

        if 4 in one_shot:
            yield self._dwell(block)
        else:
            yield from self._motion(block)

        for m in mcodes:
            if m in M_BEFORE_MOTION:
                continue
            if m == 5:
                st.spindle_dir = 0
            if m in M_END:
                yield Aux("M", m, block.line, block.text, program=self.program_name)
                yield ProgramEnd(block.line, block.text, m)
                return
            yield Aux("M", m, block.line, block.text, program=self.program_name)

    def _gcodes(self, block: Block) -> list[int]:
        seen: dict[int, int] = {}
        out = []
        for w in block.all("G"):
            g = int(round(w.value))
            if abs(w.value - g) > 1e-9 or g not in G_GROUP:
                raise NcAlarm(0x021D, f"G code {w.text} is not supported")
            grp = G_GROUP[g]
            if grp and grp in seen and seen[grp] != g:
                raise NcAlarm(0x0202, f"G{seen[grp]:02d} and G{g:02d} of the same group in one block")
            seen[grp] = g
            out.append(g)
        return out

    def _check_letters(self, block: Block) -> None:
        allowed = set(self.axes) | {"G", "M", "S", "T", "F", "P", "I", "J", "K", "R"}
        if self.profile.is_lathe and self.profile.lathe_type == "A":
            allowed |= {INC for INC, ax in INCREMENTAL.items() if ax in self.axes}
        for w in block.words:
            if w.letter == "O":
                raise NcAlarm(0x0201, "'O' is only allowed at the start of a program")
            if w.letter not in allowed:
                raise NcAlarm(0x0201, f"address {w.letter} is not defined on this machine ({w.text})")

    # ---- numbers ---------------------------------------------------------------------------
    def _distance(self, w: Word) -> float:
        """Apply the decimal-point rule (N8.018 Bit10, decisions A4) and inch input."""
        v = w.value
        if not w.has_point and not self.profile.param("N8.018 Bit10"):
            v *= 0.001
        if self.state.inch:
            v *= 25.4
        return v

    def _geometry(self, block: Block) -> _Geometry:
        st = self.state
        work = self.work_position()
        moved = False
        incremental_letters = INCREMENTAL if self.profile.lathe_type == "A" else {}
        for a in self.axes:
            w_abs = block.get(a)
            inc_letter = next((k for k, v in incremental_letters.items() if v == a), None)
            w_inc = block.get(inc_letter) if inc_letter else None
            if w_abs is not None and w_inc is not None:
                raise NcAlarm(0x0202, f"{a} and {inc_letter} in one block")
            if w_abs is not None:
                v = self._distance(w_abs)
                work[a] = v if st.absolute else work[a] + v
                moved = True
            elif w_inc is not None:
                work[a] += self._distance(w_inc)
                moved = True
        machine = {}
        for a in self.axes:
            v = work[a] / 2.0 if a in self.profile.diameter_axes else work[a]
            machine[a] = v + self.frames.origin(st.wcs, a)
            if not math.isfinite(machine[a]):
                raise NcAlarm(0x0223, f"{a} target is not a finite number")
        return _Geometry(work, machine, moved)

    # ---- motion ------------------------------------------------------------------------
    def _feed(self) -> float:
        st = self.state
        feed = st.feed
        if feed is None or feed == 0.0:
            default = self.profile.param("N1.042")
            if default > 0 and not st.per_rev:
                return default
            raise NcAlarm(0x1001, "no F programmed for a cutting move")
        return feed * (25.4 if st.inch else 1.0)

    def _motion(self, block: Block) -> Iterator[Event]:
        st = self.state
        geo = self._geometry(block)
        has_motion_g = any(int(w.value) in MOTION_G for w in block.all("G"))
        if not geo.moved:
            if has_motion_g and st.motion in (2, 3) and (block.has("I") or block.has("J") or block.has("K")):
                pass  # full circle with centre words and no end point
            else:
                return
        start = dict(self.position)
        end = geo.target_machine
        common = dict(line=block.line, block=block.text, start=start, end=end, work=dict(geo.target_work),
                      program=self.program_name, plane=PLANES[st.plane])
        if st.motion == 0:
            move = Move("rapid", **common)
        elif st.motion == 1:
            move = Move("line", feed=self._feed(), per_rev=st.per_rev, **common)
        else:
            move = self._arc(block, common)
        self.position = dict(end)
        yield move

    def _arc(self, block: Block, common: dict) -> Move:
        st = self.state
        a1, a2 = PLANES[st.plane]
        if a1 not in self.axes or a2 not in self.axes:
            raise NcAlarm(0x021D, f"G{st.plane} plane needs axes {a1} and {a2}")
        cw = st.motion == 2
        start, end = common["start"], common["end"]
        s = (start[a1], start[a2])
        e = (end[a1], end[a2])
        tol = self.profile.param("N1.040", 0.01)
        r = block.get("R")
        centre_letter = {"X": "I", "Y": "J", "Z": "K"}
        ci, cj = block.get(centre_letter[a1]), block.get(centre_letter[a2])
        if r is not None:
            if ci is not None or cj is not None:
                raise NcAlarm(0x0202, "arc with both R and I/J/K")
            c = center_from_radius(s, e, self._distance(r), cw, tol)
        elif ci is not None or cj is not None:
            # I/J/K are always radius values from the start point (decisions A6)
            c = (s[0] + (self._distance(ci) if ci else 0.0), s[1] + (self._distance(cj) if cj else 0.0))
            check_center(s, e, c, tol)
        else:
            raise NcAlarm(0x0259, "arc without R or I/J/K")
        sweep(s, e, c, cw)  # validates
        centre = {a: end[a] for a in self.axes}
        centre[a1], centre[a2] = c
        return Move("arc", center=centre, dir="cw" if cw else "ccw", feed=self._feed(), per_rev=st.per_rev,
                    **common)

    def _dwell(self, block: Block) -> Move:
        p = block.get("P")
        x = block.get("X") or block.get("U")
        if p is not None:
            if p.has_point:
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
        return Move("dwell", block.line, block.text, here, dict(here), self.work_position(), duration=seconds,
                    program=self.program_name)
