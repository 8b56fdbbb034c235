"""The block executor: turns parsed blocks into canonical events in machine coordinates.

The interpreter is a generator so the channel can pull it block by block and stop reading ahead
where the controller would (a `Sync` event).  Execution is a program counter over the block list
of the current program with a call stack (M98, G65, G66, G/M/T-code macros, M96 interrupts);
macro statements (assignments, IF, WHILE, GOTO) run when the block is read.
"""

from __future__ import annotations

import copy
import math
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field

from nc.alarm_table import ENDLESS_LOOP
from nc.alarms import NcAlarm
from nc.budget import StatementBudget
from nc.interp import context
from nc.interp.arcs import center_from_radius, check_center, sweep
from nc.interp.corners import expand_corners
from nc.interp.gcodes import STOP_PREVIEW, lookup
from nc.interp.servo import ServoPort
from nc.interp.state import N_EXT_WCS, PLANES, Frames, ModalState
from nc.interp.sysvars import SystemVariables
from nc.interp.tools import ToolTable
from nc.interp.variables import Variables
from nc.moves import BUSY, Aux, Event, Move, ProgramEnd, Sync
from nc.profiles import Profile
from nc.program.blocks import (Assign, Block, Else, ElseIf, End, EndIf, ExitW, Goto, IfGoto, IfThen,
                               Program, While, Word)
from nc.program.expr import evaluate, var_index
from nc.store import ProgramStore

try:  # imported once here: `_transforms` asks it on every block
    import nc.transforms as _transforms_module
except ImportError:  # a build without issue 4's transforms
    _transforms_module = None

M_BEFORE_MOTION = {3, 4, 8, 19, 29}  # issued to the MLC before the block's motion starts
M_END = {2, 30}
# Codes whose axis words name a centre or the axes concerned, never a target: no motion in their block.
TRANSFORM_ARG_FUNCS = frozenset({"scale", "mirror", "mirror_off", "G68"})
CHORD_TOL_3D = 0.0005  # mm: G2.4/G3.4 chords deviate from the arc by at most 0.5 µm
# App. A 0x025F, N§3.12.5: refused while G68 rotation is on, until G69
REFUSED_UNDER_G68 = frozenset({"G54", "G55", "G56", "G57", "G58", "G59", "G28", "G29", "G30", "G2.4", "G3.4"})
# Non-modal codes whose block runs no motion of the current motion mode (the code itself moves or not).
NO_MOTION_FUNCS = frozenset({"G04", "G10", "G11", "G28", "G29", "G30", "G31", "G52", "G53", "set", "G05",
                             "G70", "G71", "G72", "G73", "G74", "G75", "G76", "G900"})
MAX_M_PER_BLOCK = 4
MAX_MACRO_DEPTH = 8  # G65/G66/G-M-T calls (0x0212)
MAX_SUB_DEPTH = 8  # M98 (0x022D)
MAX_IF_DEPTH = 5
MAX_WHILE_DEPTH = 3
INCREMENTAL = {"U": "X", "V": "Y", "W": "Z", "H": "C"}
ARG_LETTERS = {"A": 1, "B": 2, "C": 3, "D": 4, "E": 5, "F": 6, "H": 8, "I": 9, "J": 10, "K": 11, "M": 13,
               "Q": 17, "R": 18, "S": 19, "T": 20, "U": 21, "V": 22, "W": 23, "X": 24, "Y": 25, "Z": 26}
LETTERS = set("ABCDEFGHIJKLMNPQRSTUVWXYZ")


@dataclass
class _Geometry:
    """Per-block numbers after unit, diameter and decimal-point rules."""

    target_work: dict[str, float]
    target_machine: dict[str, float]
    moved: bool
    axes: set[str] = field(default_factory=set)


@dataclass
class Frame:
    program: Program
    pc: int = 0
    kind: str = "main"  # main | m98 | g65 | g66 | gcall | mcall | tcall | m96
    locals_pushed: bool = False
    repeat: int = 1
    loops: list[tuple[int, int, int | None]] = field(default_factory=list)  # (while pc, end pc, id)
    ifs: list[int] = field(default_factory=list)  # ENDIF pcs of the open IF-THEN blocks
    call_code: str | None = None  # "G100" / "M100" / "T" while executing a code-called macro
    restarts: int = 0
    args: dict[int, float] | None = None  # the call's arguments: every L repetition starts from them
    entry: int = 0  # where each repetition starts (M98 H/Q enter mid-program)


@dataclass
class PreviewRecord:
    """A macro statement and the motion block the machine was executing when it ran (preview)."""

    line: int
    block: str
    program: str
    ahead_of_line: int | None = None
    ahead_of_block: str | None = None
    blocks_ahead: int = 0


class Interpreter:
    def __init__(self, profile: Profile, start: dict[str, float] | None = None,
                 store: ProgramStore | None = None) -> None:
        self.profile = profile
        self.axes = profile.axes
        self.state = ModalState.power_on(profile)
        self.frames = Frames(self.axes)
        self.position: dict[str, float] = {a: 0.0 for a in self.axes}  # machine, as the axis travels
        self.take_position(start or {})
        self.program_name = ""
        self.store = store or ProgramStore()
        self._own_store = store is not None  # else the program's own store (Program.store) is searched
        self.tools = ToolTable()
        self.sys = SystemVariables(self)
        self.vars = Variables(legacy=profile.legacy, system_read=self.sys.read, system_write=self.sys.write)
        self.stack: list[Frame] = []
        self.block: Block | None = None
        self.cycle_modal: dict[str, float] = {}
        self.cycle_memory: dict = {}
        self.macro_modal: tuple[int, int, dict[int, float]] | None = None  # G66 (program, L, args)
        self.interrupt_program: int | None = None  # M96 P
        self._interrupt_pending = False
        self._interrupt_stop: dict[str, float] | None = None  # where the motion suspended the block (M2x019)
        self._interrupt_resume: Move | None = None  # the way to the suspended block's end, due at M99
        self._angle_pending: tuple[Block, dict] | None = None  # two-block ,A form: first block held (A32)
        self.reference_via: dict[str, float] | None = None  # G28/G30 intermediate point (machine)
        self.skip_position: dict[str, float] | None = None  # G31 trigger (machine), set by motion
        self.last_target: dict[str, float] = self.work_position()
        self.last_arc_ijk: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.unit_locked = False
        self.block_skip = bool(profile.param("M2x010"))
        # the last statements only: a long run would otherwise grow ~2 MB/min (decisions B3)
        self.preview_log: deque[PreviewRecord] = deque(maxlen=_log_length(profile))
        self.servo = ServoPort(alarm_on_error=bool(profile.param("servo param alarm", 1.0)))  # G10 L40-L46
        self.on_statement = None  # callable(block, program) set by the preview window
        self.budget: StatementBudget | None = None  # per-cycle statements; set by a channel (decisions B2)
        self.p_scale = 1.0
        self._executed = 0
        self._gcall_depth = 0
        self._three_point: dict[str, float] | None = None  # G2.4/G3.4 middle point
        self._plain_axes = frozenset(self.axes) - {"G", "M", "T", "F", "S", "D"}  # `_axis_block` letters

    # ---- public ---------------------------------------------------------------------------

    def take_position(self, start: dict[str, float]) -> None:
        """Start from where the axes stand (machine coordinates), before the program runs."""
        self.position.update({a: v for a, v in start.items() if a in self.position})
    def variable(self, number: int) -> float | None:
        return self.vars.get(number)

    def request_interrupt(self, stopped_at: dict[str, float] | None = None) -> None:
        """The MLC's M2x019 trigger: run the M96 program at the next block boundary.

        ``stopped_at`` is the machine position where the motion suspended the block it was running
        (N§3.11.4.6: "suspended immediately"); M99 of the interrupt program then goes on to that
        block's end point in a straight line (note 2, also for G02/G03).  None: the block had ended."""
        if self.interrupt_program is not None:
            self._interrupt_pending = True
            self._interrupt_stop = dict(stopped_at) if stopped_at is not None else None

    def interrupt_events(self, stopped_at: dict[str, float]) -> Iterator[Event]:
        """The M96 program run at once from `stopped_at`, up to its M99 (the channel's M2x019 while
        the interpreter has read blocks ahead of the motion). Its moves start where the axes
        stopped; afterwards the reading position (position, last point, block) is back where the
        read-ahead left it, so the main program reads on unchanged. Modal changes it makes stay."""
        st = self.state
        if st.comp in (41, 42) or st.scaling:
            raise NcAlarm(0x0005, "M96 interrupt while G41/G42 or G51 is active")
        prog = self.store.find(self.interrupt_program or 0)
        saved = dict(self.position), dict(self.last_target), self.block, self.program_name
        base = len(self.stack)
        self.stack.append(Frame(prog, 0, "m96", False, 1))
        self.position.update({a: v for a, v in stopped_at.items() if a in self.position})
        self.last_target = self.work_position()
        limit = int(self.profile.param("max blocks", 1_000_000))
        try:
            while len(self.stack) > base:
                fr = self.stack[-1]
                if fr.pc >= len(fr.program.blocks):
                    self._return(None)  # the end of the interrupt program returns like M99
                    continue
                block = self._take_block(fr, limit)
                if block is None:
                    continue
                try:
                    for ev in self._execute(block):
                        yield ev
                        if isinstance(ev, ProgramEnd):  # M02/M30 in the interrupt program ends it all
                            return
                except NcAlarm as alarm:
                    raise alarm.at(block.line, block.text, fr.program.name) from None
        finally:
            del self.stack[base:]
            self.position, self.last_target, self.block, self.program_name = saved

    def record_skip(self, machine: dict[str, float]) -> None:
        """Issue 5 reports where a G31 move stopped; #21048…/#21064… read it back."""
        self.skip_position = dict(machine)
        self.position.update(machine)

    def run(self, program: Program, *, preview: bool = True) -> Iterator[Event]:
        events: Iterator[Event] = expand_corners(self, self._run(program))
        comp = _compensation()
        if comp is not None:
            events = comp(events, self.profile)
        if preview:
            from nc.interp.preview import PreviewWindow
            events = iter(PreviewWindow(self, events, int(self.profile.param("preview depth", 8))))
        return events

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

    # ---- the program counter -----------------------------------------------------------------
    def _run(self, program: Program) -> Iterator[Event]:
        self.program_name = program.name
        self.stack = [Frame(program)]
        if not self._own_store and program.store is not None:
            self.store = program.store
        if program.number is not None:
            self.store.loaded.setdefault(program.number, program)
        limit = int(self.profile.param("max blocks", 1_000_000))
        last: Block | None = None
        budget = self.budget
        while self.stack:
            if budget is not None and budget.spent:
                yield BUSY  # the rest of the macro next cycle; the cycle never stalls (decisions B2)
                continue
            fr = self.stack[-1]
            if self._interrupt_pending:
                self._interrupt_pending = False
                yield from self._start_interrupt()
                continue
            if fr.pc >= len(fr.program.blocks):
                if len(self.stack) == 1:
                    break
                self._return(None)  # end of a subprogram without M99 returns like M99
                continue
            last = fr.program.blocks[fr.pc]
            block = self._take_block(fr, limit)
            if block is None:
                continue
            try:
                end = False
                for ev in self._execute(block):
                    yield ev
                    if isinstance(ev, ProgramEnd):
                        end = True
                if end:
                    return
            except NcAlarm as alarm:
                raise alarm.at(block.line, block.text, fr.program.name) from None
            except (ValueError, ArithmeticError, OverflowError) as exc:
                raise NcAlarm(0x0257, f"numerical error: {exc}", line=block.line, block=block.text,
                              program=fr.program.name) from None
        self._check_no_pending_angle()
        yield ProgramEnd(last.line if last else 0, last.text if last else "", 0)

    def _take_block(self, fr: Frame, limit: int) -> Block | None:
        """Advance `fr` by one block and count it; None for a skipped '/' block."""
        block = fr.program.blocks[fr.pc]
        fr.pc += 1
        self._executed += 1
        if self._executed > limit:
            raise NcAlarm(ENDLESS_LOOP, f"more than {limit} blocks executed (endless loop?; parameter 'max blocks')",
                          line=block.line, block=block.text, program=fr.program.name)
        if block.skip and self.block_skip:
            return None
        self.program_name = fr.program.name
        return block

    def _check_no_pending_angle(self) -> None:
        """A held two-block `,A` block never gets its partner at the end of the program."""
        if self._angle_pending is not None:
            blk = self._angle_pending[0]
            self._angle_pending = None
            raise NcAlarm(0x0207, ",A without an end point must be followed by G01 with both plane coordinates "
                          "and ,A", line=blk.line, block=blk.text, program=self.program_name)

    @property
    def frame(self) -> Frame:
        return self.stack[-1]

    def _jump_label(self, n: int, fr: Frame | None = None, code: int = 0x022A) -> None:
        """GOTO n / M99 Pn: nc5 searches forward from the current block and wraps; lathe-2018
        searches from the program start (decisions A16)."""
        fr = fr or self.frame
        hits = fr.program.labels.get(int(n))
        if not hits:
            raise NcAlarm(code, f"N{int(n)} not found in {fr.program.name}")
        if self.profile.legacy:
            target = hits[0]
        else:
            cur = fr.pc - 1
            after = [h for h in hits if h > cur]
            target = after[0] if after else hits[0]
        # a jump may not leave or enter a WHILE body (N§3.11.3.1); lathe-2018 just drops the loop
        for (wpc, epc, _id) in list(fr.loops):
            if not (wpc <= target <= epc):
                if not self.profile.legacy:
                    raise NcAlarm(0x0224, "GOTO cannot leave a WHILE loop (use EXITW)")
                fr.loops.remove((wpc, epc, _id))
        fr.ifs = [e for e in fr.ifs if target <= e]
        fr.pc = target

    # ---- expressions -------------------------------------------------------------------------
    def eval(self, e) -> float | None:
        return evaluate(e, self.vars.get)

    def _resolve(self, block: Block) -> Block:
        """Evaluate the expressions of a block's words; vacant values drop the word (B.3.1.1)."""
        if not block.has_expr:
            return block
        b = block.copy()
        words = []
        for w in block.words:
            if w.expr is None:
                words.append(w)
                continue
            v = self.eval(w.expr)
            if v is None:
                continue
            if not math.isfinite(v):
                raise NcAlarm(0x0223, f"{w.text} is not a finite number")
            words.append(Word(w.letter, v, w.text, True))
        b.words = words
        for k, e in block.comma_expr.items():
            v = self.eval(e)
            if v is not None:
                b.comma[k] = v
        b.comma_expr = {}
        return b

    # ---- one block -----------------------------------------------------------------------------
    def _execute(self, raw: Block) -> Iterator[Event]:
        if raw.stmt is not None:
            yield from self._statement(raw)
            return
        block = self._resolve(raw)
        self.block = block
        st = self.state
        if self._axis_block(block):  # fast path: the steps skipped here are no-ops for such a block
            yield from self._motion(block, set())
            return
        # code-called macros: the calling code must be first in the block (N§3.2.1)
        called = self._code_call(block)
        if called is not None:
            yield from called
            return
        gcodes = self._gcodes(block)
        funcs = {fn for _, fn, _ in gcodes}
        self._check_letters(block, funcs)
        if (self.state.rotation or "G68" in funcs) and "G69" not in funcs and funcs & REFUSED_UNDER_G68:
            raise NcAlarm(0x025F, f"{' '.join(sorted(funcs & REFUSED_UNDER_G68))} while G68 rotation is on: "
                                  "cancel it with G69 first")
        mcodes = block.all("M")
        for w in mcodes:
            if w.value != int(w.value) or not 0 <= w.value <= 65534:
                raise NcAlarm(0x0249, f"M code {w.text} out of range")
        mvals = [int(w.value) for w in mcodes]
        if len(mvals) > MAX_M_PER_BLOCK:
            raise NcAlarm(0x0248, f"{len(mvals)} M codes in one block (at most {MAX_M_PER_BLOCK})")
        calls = [c for c in ("G65", "G66") if c in funcs] + [f"M{m}" for m in mvals if m in (98, 96)]
        if len(calls) > 1:
            raise NcAlarm(0x024B, f"one block can only hold one call command ({' '.join(calls)})")
        if 98 in mvals and len(mvals) > 1:
            raise NcAlarm(0x0249, "M98 must be the only M code of its block")

        if "G65" in funcs:
            self._macro_call(block, modal=False)
            return
        if not funcs.isdisjoint(STOP_PREVIEW):
            yield Sync(block.line, block.text, next(fn for fn in funcs if fn in STOP_PREVIEW))
        halt_m = self._halt_m(mvals) if mvals else None
        if halt_m is not None:
            yield Sync(block.line, block.text, f"M{halt_m}")

        # modal updates
        was_css = st.css
        for grp, fn, w in gcodes:
            if grp:
                self._set_modal(grp, fn, w, block)
        if "G66" in funcs:
            self._macro_call(block, modal=True)
            return
        if "G67" in funcs:
            self.macro_modal = None
            st.macro_modal = False

        f = block.get("F")
        if f is not None and "G31" not in funcs and not (st.cycle or self._cycle_fn(funcs)):
            if f.value < 0:
                raise NcAlarm(0x0223, "F must not be negative")
            st.feed = f.value
        elif f is not None and f.value >= 0 and "G31" not in funcs and not self._is_thread(funcs):
            st.feed = f.value
        if block.has("D") and not self._cycle_fn(funcs) and not st.cycle:
            d = block.get("D").value
            if d != int(d) or d < 0 or d > 512:
                raise NcAlarm(0x0217, f"D{d:g} is out of range")
            st.d_number = int(d)

        # S, T, and M codes issued before motion
        s = block.get("S")
        if s is not None and not ("set" in funcs) and not self._cycle_fn(funcs):
            if s.value < 0 or s.value > 600000:
                raise NcAlarm(0x0223, f"S{s.value:g} out of range 0-600000")
            st.spindle_speed = s.value
            if st.css:
                st.surface_speed = s.value
            spindle = block.get("P")
            args = {"P": spindle.value} if spindle is not None and not funcs & {"G04", "G10", "G30", "G31", "G900", "G05"} and 98 not in mvals else {}
            if st.css:  # G96: S is a surface speed (m/min); the channel turns it into rpm (issue 5)
                args = {**args, "css": 1.0}
                if "X" in self.axes:  # machine X of the work centre: the diameter before any move
                    args["x0"] = self.frames.origins(st.wcs, self.axes)["X"]
            yield Aux("S", s.value, block.line, block.text, args=args, program=self.program_name)
        elif st.css != was_css and s is None:
            yield self._css_switch(block)  # G96 / G97 alone switch when read, not at the next move
        t = block.get("T")
        if t is not None and not self._cycle_fn(funcs):
            yield from self._tool(block, t)
        for m in mvals:
            if m in M_BEFORE_MOTION:
                if m in (3, 4):
                    st.spindle_dir = 1 if m == 3 else -1
                yield Aux("M", m, block.line, block.text, program=self.program_name)

        moved = False
        nonmodal = [fn for grp, fn, _ in gcodes if grp == 0]
        if "G53" in funcs and funcs & {"G28", "G30"}:
            raise NcAlarm(0x0265, "G53 and G28/G30 cannot be programmed together")
        for fn in nonmodal:
            handler = getattr(self, "_g_" + fn.replace(".", "_"), None)
            if handler is not None:
                r = handler(block)
                if r is not None:
                    for ev in r:
                        if isinstance(ev, Move) and ev.kind != "dwell":
                            moved = True
                        yield ev
            elif fn in ("G70", "G71", "G72", "G73", "G74", "G75", "G76"):
                yield from context.run_cycle(self, fn, block)
                moved = True
                self._skip_contour(fn, block)
        if NO_MOTION_FUNCS.isdisjoint(nonmodal) and TRANSFORM_ARG_FUNCS.isdisjoint(funcs):
            for ev in self._motion(block, funcs):
                if isinstance(ev, Move) and ev.kind != "dwell":
                    moved = True
                yield ev

        for m in mvals:
            if m in M_BEFORE_MOTION:
                continue
            if m == 5:
                st.spindle_dir = 0
            if m in M_END:
                yield Aux("M", m, block.line, block.text, program=self.program_name)
                self._check_no_pending_angle()
                self._reset_at_end()
                yield ProgramEnd(block.line, block.text, m)
                return
            if m == 98:
                self._sub_call(block)
                return
            if m == 99:
                self._m99(block)
                if self._interrupt_resume is not None and not any(f.kind == "m96" for f in self.stack):
                    yield self._resume_after_interrupt()
                return
            if m == 96:
                # a preview stop: M2x019 is honoured from this block's execution on, not from its reading
                yield Sync(block.line, block.text, "M96")
                self._m96(block)
                continue
            if m == 97:
                yield Sync(block.line, block.text, "M97")
                self.interrupt_program = None
                continue
            yield Aux("M", m, block.line, block.text, program=self.program_name)

        # G66: call the macro after every block that moved an axis, never inside the macro (A18)
        if moved and self.macro_modal is not None and not any(f.kind == "g66" for f in self.stack):
            prog, count, args = self.macro_modal
            self._push_macro(prog, count, dict(args), "g66")

    def _axis_block(self, block: Block) -> bool:
        """A block of absolute axis words only (``X1.5 Y2``: most CAM output) while no G66 is modal.
        Without G/M/F/S/T/D words or ,C/,R/,A, `_execute` finds no code call, no G or M code, no
        modal change and no letter to refuse; all that runs is `_motion` (tests/test_lang_fastpath.py)."""
        if not block.words or block.comma or self.macro_modal is not None:
            return False
        plain = self._plain_axes
        for w in block.words:
            if w.letter not in plain:
                return False
        return True

    # ---- statements --------------------------------------------------------------------------
    def _statement(self, block: Block) -> Iterator[Event]:
        s = block.stmt
        fr = self.frame
        if self.on_statement is not None:
            self.on_statement(block, fr.program.name)
        if self.budget is not None:
            self.budget.spend()
        if isinstance(s, Assign):
            n = var_index(s.target, self.vars.get)
            v = self.eval(s.value)
            if v is not None and not math.isfinite(v):
                raise NcAlarm(0x0257, "assignment of a non-finite value")
            self.vars.set(n, v)
            if self.sys.live(n):
                yield Sync(block.line, block.text, f"#{n}")
            return
        if isinstance(s, Goto):
            self._jump_label(self._label(s.target))
            return
        if isinstance(s, IfGoto):
            if self._truth(s.cond):
                self._jump_label(self._label(s.target))
            return
        if isinstance(s, IfThen):
            endif, branches = self._scan_if(fr, fr.pc - 1)
            if len(fr.ifs) >= MAX_IF_DEPTH:
                raise NcAlarm(0x023E, f"more than {MAX_IF_DEPTH} nested IF")
            fr.ifs.append(endif)
            if self._truth(s.cond):
                return
            for bpc in branches:
                b = fr.program.blocks[bpc].stmt
                if isinstance(b, ElseIf):
                    if self._truth(b.cond):
                        fr.pc = bpc + 1
                        return
                else:
                    fr.pc = bpc + 1
                    return
            fr.pc = endif + 1
            fr.ifs.pop()
            return
        if isinstance(s, (ElseIf, Else)):
            if not fr.ifs:
                raise NcAlarm(0x023A if isinstance(s, ElseIf) else 0x023B, "ELSE/ELSEIF without IF...THEN")
            fr.pc = fr.ifs.pop() + 1  # the branch before it ran: skip to after ENDIF
            return
        if isinstance(s, EndIf):
            if not fr.ifs:
                raise NcAlarm(0x023C, "ENDIF without IF...THEN")
            fr.ifs.pop()
            return
        if isinstance(s, While):
            wpc = fr.pc - 1
            if s.do is not None and s.do not in (1, 2, 3):
                raise NcAlarm(0x0214, f"DO{s.do}: loop numbers are 1, 2 and 3")
            if s.do is None and not self.profile.legacy:
                raise NcAlarm(0x0215, "WHILE without DO")
            if s.do is not None and self.profile.legacy:
                raise NcAlarm(0x0207, "lathe-2018 loops are WHILE [..] ... ENDW")
            epc = self._scan_end(fr, wpc, s.do)
            active = fr.loops and fr.loops[-1][0] == wpc
            if self._truth(s.cond):
                if not active:
                    if len(fr.loops) >= MAX_WHILE_DEPTH and not self.profile.legacy:
                        raise NcAlarm(0x0226, f"more than {MAX_WHILE_DEPTH} nested WHILE")
                    fr.loops.append((wpc, epc, s.do))
            else:
                if active:
                    fr.loops.pop()
                fr.pc = epc + 1
            return
        if isinstance(s, End):
            if s.do is not None and s.do not in (1, 2, 3):
                raise NcAlarm(0x0225, f"END{s.do}: loop numbers are 1, 2 and 3")
            if not fr.loops or fr.loops[-1][2] != s.do or fr.loops[-1][1] != fr.pc - 1:
                raise NcAlarm(0x022B, f"END{'' if s.do is None else s.do} has no matching WHILE")
            fr.pc = fr.loops[-1][0]
            return
        if isinstance(s, ExitW):
            if s.cond is not None and not self._truth(s.cond):
                return
            if not fr.loops:
                raise NcAlarm(0x022B, "EXITW outside a WHILE loop")
            _, epc, _ = fr.loops.pop()
            fr.ifs = [e for e in fr.ifs if e > epc]
            fr.pc = epc + 1
            return

    def _truth(self, cond) -> bool:
        v = self.eval(cond)
        return bool(v) and v is not None

    def _label(self, e) -> int:
        v = self.eval(e)
        if v is None or v < 0 or v != int(v):
            raise NcAlarm(0x0224, f"GOTO target {v} is not a sequence number")
        return int(v)

    def _scan_if(self, fr: Frame, start: int) -> tuple[int, list[int]]:
        depth = 0
        branches: list[int] = []
        blocks = fr.program.blocks
        for j in range(start + 1, len(blocks)):
            s = blocks[j].stmt
            if isinstance(s, IfThen):
                depth += 1
            elif isinstance(s, EndIf):
                if depth == 0:
                    return j, branches
                depth -= 1
            elif isinstance(s, (ElseIf, Else)) and depth == 0:
                branches.append(j)
        raise NcAlarm(0x023D, "IF...THEN without ENDIF")

    def _scan_end(self, fr: Frame, start: int, do: int | None) -> int:
        blocks = fr.program.blocks
        open_ids: list[int | None] = []
        for j in range(start + 1, len(blocks)):
            s = blocks[j].stmt
            if isinstance(s, While):
                open_ids.append(s.do)
            elif isinstance(s, End):
                if open_ids:
                    inner = open_ids.pop()
                    if inner != s.do:
                        raise NcAlarm(0x022C, "END statement cannot be found (overlapping WHILE ranges)")
                    continue
                if s.do == do:
                    return j
                raise NcAlarm(0x022C, f"END{s.do} closes WHILE ... DO{do}: END statement cannot be found")
        raise NcAlarm(0x0213 if do is None else 0x022C, "WHILE loop without its END")

    # ---- G codes ---------------------------------------------------------------------------
    def _gcodes(self, block: Block) -> list[tuple[int, str, Word]]:
        seen: dict[int, str] = {}
        out = []
        for w in block.all("G"):
            entry = lookup(self.profile, w.value)
            if entry is None:
                raise NcAlarm(0x021D, f"G code {w.text} is not supported on {self.profile.name}")
            grp, fn = entry
            if grp and grp in seen and seen[grp] != fn:
                raise NcAlarm(0x0202, f"two G codes of group {grp:02d} in one block ({w.text})")
            if grp == 0 and fn in seen.values():
                continue
            seen[grp if grp else 100 + len(seen)] = fn
            out.append((grp, fn, w))
        return out

    def _check_letters(self, block: Block, funcs: set[str]) -> None:
        for w in block.words:
            if w.letter in LETTERS or w.letter in self.axes:
                continue
            raise NcAlarm(0x0201, f"address {w.letter} is not defined on this machine ({w.text})")
        for a in ("Y", "A", "B", "C", "X", "Z"):
            if a not in self.axes and block.has(a) and not self._letter_is_arg(a, funcs):
                raise NcAlarm(0x0201, f"axis {a} is not defined on this machine")

    def _letter_is_arg(self, a: str, funcs: set[str]) -> bool:
        return bool(funcs & {"G65", "G66", "G10", "G51", "G68", "G16", "G52"}) or self._cycle_fn(funcs) is not None \
            or (a == "C" and self.profile.is_lathe) or a == "A" and False

    def _cycle_fn(self, funcs: set[str]) -> str | None:
        for fn in funcs:
            if fn in context.MODAL_CYCLES or fn in ("G70", "G71", "G72", "G73", "G74", "G75", "G76"):
                return fn
        return None

    def _is_thread(self, funcs: set[str]) -> bool:
        return bool(funcs & {"G32", "G34"}) or self.state.motion in (32, 34)

    def _set_modal(self, grp: int, fn: str, w: Word, block: Block) -> None:
        st = self.state
        st.groups[grp] = w.value
        if grp == 1:
            st.motion = {"G00": 0, "G01": 1, "G02": 2, "G03": 3, "G2.4": 2.4, "G3.4": 3.4, "G32": 32,
                         "G34": 34}[fn]
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

    def _axis_words(self, block: Block) -> dict[str, tuple[Word, bool]]:
        """axis -> (word, incremental) from X/Y/Z/… and the U/V/W/H incremental addresses (A5)."""
        out: dict[str, tuple[Word, bool]] = {}
        lathe_inc = self.profile.is_lathe
        for a in self.axes:
            w_abs = block.get(a)
            inc_letter = next((k for k, v in INCREMENTAL.items() if v == a), None) if lathe_inc else None
            w_inc = block.get(inc_letter) if inc_letter and inc_letter not in self.axes else None
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

    def _motion(self, block: Block, funcs: set[str]) -> Iterator[Event]:
        st = self.state
        if "G04" in funcs:
            return
        cyc = st.cycle
        # N§3.3.4 note (1): under G91 the end point of G2.4/G3.4 counts from the middle point
        mid = self._three_point
        geo = self._geometry(block, base=None if mid is None else self.to_work(mid))
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
        common = self._move_common(block, geo.target_machine, geo.target_work)
        if st.motion in (2.4, 3.4):
            yield from self._three_point_arc(block, geo, common)
            return
        if st.motion == 0:
            move = Move("rapid", **common)
        elif st.motion == 1:
            move = Move("line", feed=self.feed(), per_rev=st.per_rev, **common)
        else:
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
            c = center_from_radius(s, e, self.distance(r), cw, tol)
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

    def _g_G05(self, block: Block) -> None:
        p = block.get("P")
        if p is None or p.value != int(p.value) or not 0 <= p.value <= 20:
            raise NcAlarm(0x0243, "G05 P must be 0-20")
        self.state.groups[0] = 5
        self.param_group = int(p.value)

    def _g_G09(self, block: Block) -> None:
        return None

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

    def _halt_m(self, mvals: list[int]) -> int | None:
        first = int(self.profile.param("N1.118", 0))
        count = int(self.profile.param("N1.119", 0))
        for m in mvals:
            if first and first <= m < first + count:
                return m
        return None

    def _reset_at_end(self) -> None:
        """M02/M30: G92/G50 shift, length comp, scaling and the tool offset number are cancelled."""
        self.frames.set_shift = {}
        st = self.state
        st.length_comp = 49
        st.tool_offset = 0
        if not self.profile.is_lathe:
            st.groups[8] = 49
        self.frames.tool_shift = {}
        tr = _transforms(self)
        if tr is not None:
            tr.reset(self)

    # ---- calls ---------------------------------------------------------------------------------
    def _args(self, block: Block, skip: set[str]) -> dict[int, float]:
        """Argument letters -> locals (N§3.11.4: 2nd/3rd use at +26/+52, T up to 5)."""
        args: dict[int, float] = {}
        counts: dict[str, int] = {}
        for w in block.words:
            if w.letter in skip or w.letter not in ARG_LETTERS:
                if w.letter not in skip and w.letter not in ("G", "L", "N", "O", "P"):
                    raise NcAlarm(0x0251, f"{w.letter} cannot be a macro argument")
                continue
            k = counts.get(w.letter, 0)
            counts[w.letter] = k + 1
            if self.profile.legacy:
                args[ARG_LETTERS[w.letter]] = w.value  # one use per letter: last wins (A20)
                continue
            slots = [ARG_LETTERS[w.letter], ARG_LETTERS[w.letter] + 26, ARG_LETTERS[w.letter] + 52]
            if w.letter == "T":
                slots += [85, 92]
            if k >= len(slots):
                raise NcAlarm(0x0251, f"argument {w.letter} used more than {len(slots)} times")
            args[slots[k]] = w.value  # unscaled (A4: macro arguments keep their value)
        return args

    def _push_macro(self, number: int, count: int, args: dict[int, float], kind: str,
                    code: str | None = None) -> None:
        depth = sum(1 for f in self.stack if f.locals_pushed)
        if depth >= MAX_MACRO_DEPTH:
            raise NcAlarm(0x0212, f"more than {MAX_MACRO_DEPTH} nested macro calls")
        prog = self.store.find(number, macro_call=kind in ("gcall", "mcall", "tcall"),
                               code=0x0004 if kind != "g65" else 0x0263)
        if count < 1:
            return
        self.vars.push_locals(args)
        self.stack.append(Frame(prog, 0, kind, True, count, call_code=code, args=dict(args)))

    def _macro_call(self, block: Block, modal: bool) -> None:
        p = block.get("P")
        if p is None:
            raise NcAlarm(0x0241, "G65/G66 needs P (program number)")
        if p.value != int(p.value) or not 0 <= p.value <= 9999:
            raise NcAlarm(0x0242, f"P{p.value:g} is not a program number")
        lw = block.get("L")
        count = 1 if lw is None else int(lw.value)
        args = self._args(block, {"G", "P", "L"})
        if modal:
            self.store.find(int(p.value), code=0x0263)
            self.macro_modal = (int(p.value), count, args)
            self.state.macro_modal = True
            return
        self._push_macro(int(p.value), count, args, "g65")

    def _code_call(self, block: Block) -> Iterator[Event] | None:
        """G-, M- and T-code macro calls (N§3.11.4.8–10, L§4.5; A24)."""
        if not block.words:
            return None
        first = block.words[0]
        if first.letter not in ("G", "M", "T"):
            return None
        if first.letter == "T":
            on = self.profile.bit("O9000") if self.profile.legacy else self.profile.bit("N1.010 Bit22")
            if not on or any(f.call_code == "T" for f in self.stack):
                return None
            number, code = 9000, "T"
        else:
            if first.value != int(first.value):
                return None
            number = self._call_table(first.letter, int(first.value))
            code = f"{first.letter}{int(first.value)}"
            if number is None:
                return None
            if any(f.call_code is not None and f.call_code[0] in "GM" for f in self.stack) and \
                    not (first.letter == "G" and self.profile.bit("N1.010 Bit28")):
                return None  # inside a called macro the code is an ordinary code
        rest = [w for w in block.words[1:]]
        if first.letter == "G" and any(w.letter in ("M", "T") and self._call_table(w.letter, int(w.value)) is not None
                                       for w in rest if w.letter == "M"):
            raise NcAlarm(0x024B, "M-code call in a G-code macro call block")
        b = block.copy()
        b.words = rest
        args = self._args(b, set())
        if first.letter == "T":
            args[20] = first.value
        self._push_macro(number, 1, args, {"G": "gcall", "M": "mcall", "T": "tcall"}[first.letter], code)
        return iter(())

    def _call_table(self, letter: str, n: int) -> int | None:
        p = self.profile
        if p.legacy:
            base = 9010 if letter == "G" else 9020
            for i in range(10):
                if p.params.get(f"O{base + i}") == n and n:
                    return base + i
            return None
        single = ("N1.200", 9100) if letter == "G" else ("N1.250", 9150)
        for i in range(50):
            if p.params.get(f"N1.{int(single[0][3:]) + i}") == n and n:
                return single[1] + i
        first, onum, amount = (("N1.120", "N1.121", "N1.122") if letter == "G" else ("N1.123", "N1.124", "N1.125"))
        f0, o0, cnt = int(p.param(first)), int(p.param(onum)), int(p.param(amount))
        if cnt and f0 <= n < f0 + cnt:
            return o0 + n - f0
        return None

    def _sub_call(self, block: Block) -> None:
        p, h, q, lw = block.get("P"), block.get("H"), block.get("Q"), block.get("L")
        depth = sum(1 for f in self.stack if f.kind == "m98")
        if depth >= MAX_SUB_DEPTH:
            raise NcAlarm(0x022D, f"more than {MAX_SUB_DEPTH} nested M98 calls")
        if self.profile.legacy:
            if p is None:
                raise NcAlarm(0x022E, "M98 needs P")
            prog = self.store.find(int(p.value))
            count = 1 if lw is None else int(lw.value)
            if count >= 1:
                self.stack.append(Frame(prog, 0, "m98", False, count))
            return
        if p is None and h is None and q is None:
            raise NcAlarm(0x0261, "M98 needs P, H or Q")
        # App. A 0x0251 lists L among M98's words: the repeat count (A21, revisited in issue 19)
        count = 1 if lw is None else int(lw.value)
        if lw is not None and (lw.value != count or not 0 <= count <= 9999):
            raise NcAlarm(0x0251, f"M98 L{lw.value:g}: the repeat count is 0-9999")
        prog = self.store.find(int(p.value)) if p is not None else self.frame.program
        if count < 1:
            return
        fr = Frame(prog, 0, "m98", False, count)
        if h is not None:  # H has priority over Q
            hits = prog.labels.get(int(h.value))
            if not hits:
                raise NcAlarm(0x022A, f"M98 H{int(h.value)}: N{int(h.value)} not found")
            fr.pc = hits[0]
        elif q is not None:
            idx = next((i for i, b in enumerate(prog.blocks) if b.line >= int(q.value)), None)
            if idx is None or q.value < 1:
                raise NcAlarm(0x0229, f"M98 Q{int(q.value)}: line not found")
            fr.pc = idx
        fr.call_code = None
        fr.entry = fr.pc
        self.stack.append(fr)

    def _m99(self, block: Block) -> None:
        p = block.get("P")
        if len(self.stack) == 1:
            fr = self.frame
            if p is not None and not self.profile.legacy:
                self._jump_label(int(p.value))
                return
            limit = int(self.profile.param("M99 main restarts", 1))
            if fr.restarts >= limit:
                fr.pc = len(fr.program.blocks)  # the emulator stops the endless main loop (A22)
                return
            fr.restarts += 1
            fr.pc = 0
            fr.loops, fr.ifs = [], []
            return
        self._return(None if self.profile.legacy or p is None else int(p.value))

    def _return(self, label: int | None) -> None:
        fr = self.frame
        fr.repeat -= 1
        if fr.repeat > 0:
            # each repetition is the whole call again (N§3.11.4.4 Example 1 (3)): fresh arguments
            fr.pc = fr.entry
            fr.loops, fr.ifs = [], []
            if fr.locals_pushed and fr.args is not None:
                self.vars.pop_locals()
                self.vars.push_locals(dict(fr.args))
            return
        self.stack.pop()
        if fr.locals_pushed:
            self.vars.pop_locals()
        if fr.kind == "m96":
            self._interrupt_return()
        if label is not None:
            self._jump_label(label)

    def _m96(self, block: Block) -> None:
        if len(self.stack) > 1:
            raise NcAlarm(0x0005, "M96 is not supported in a subprogram")
        p = block.get("P")
        if p is None:
            raise NcAlarm(0x0241, "M96 needs P")
        self.store.find(int(p.value))
        self.interrupt_program = int(p.value)

    def _start_interrupt(self) -> Iterator[Event]:
        st = self.state
        if st.comp in (41, 42) or st.scaling:
            raise NcAlarm(0x0005, "M96 interrupt while G41/G42 or G51 is active")
        prog = self.store.find(self.interrupt_program or 0)
        self.stack.append(Frame(prog, 0, "m96", False, 1))
        self._interrupt_resume = None
        stop, self._interrupt_stop = self._interrupt_stop, None
        if stop is not None and self.block is not None:
            # the suspended block still owes the way from `stop` to its end: G00 as a rapid, G01/G02/G03
            # as a straight cutting move at the block's feed (N§3.11.4.6 note 2); built now, sent at M99
            end = dict(self.position)
            kind = "rapid" if st.motion == 0 else "line"
            self._interrupt_resume = Move(
                kind, self.block.line, self.block.text, {}, end, self.to_work(end),
                feed=self.feed() if kind == "line" else None, per_rev=st.per_rev if kind == "line" else False,
                program=self.program_name, plane=PLANES[st.plane], tags=("M96", "resume"))
            self.position.update(stop)
        return iter(())

    def _interrupt_return(self) -> None:
        return None

    def _resume_after_interrupt(self) -> Move:
        mv, self._interrupt_resume = self._interrupt_resume, None
        assert mv is not None
        mv.start = dict(self.position)  # from wherever the interrupt program left the tool
        self.position = dict(mv.end)
        return mv

    def _skip_contour(self, fn: str, block: Block) -> None:
        """After G71/G72/G73 P..Q the contour blocks that follow are not run again as moves."""
        p, q = block.get("P"), block.get("Q")
        if fn not in ("G71", "G72", "G73") or p is None or q is None:
            return
        fr = self.frame
        if fr.pc < len(fr.program.blocks) and fr.program.blocks[fr.pc].n == int(p.value):
            qs = fr.program.labels.get(int(q.value))
            if qs:
                fr.pc = qs[-1] + 1

    # ---- contour access for cycles (context.CycleHost) -----------------------------------------
    def contour_blocks(self, p: int, q: int) -> list[Block]:
        prog = self.frame.program
        ps, qs = prog.labels.get(int(p)), prog.labels.get(int(q))
        if not ps or not qs:
            raise NcAlarm(0x0264, f"N{int(p) if not ps else int(q)} of the cycle's P/Q not found")
        i, j = ps[0], qs[-1]
        if j < i:
            raise NcAlarm(0x0264, f"N{int(q)} comes before N{int(p)}")
        return [self._resolve(b) for b in prog.blocks[i:j + 1]]

    def contour_moves(self, blocks: list[Block], start: dict[str, float] | None = None) -> list[Move]:
        """Interpret blocks on a copy of this interpreter (no side effects), corners expanded."""
        twin = self._clone()
        if start is not None:
            twin.position = dict(start)
        prog = Program(self.frame.program.name, [b for b in blocks if b.stmt is None])

        def gen() -> Iterator[Event]:
            for b in prog.blocks:
                yield from twin._execute(b)
        out = [ev for ev in expand_corners(twin, gen()) if isinstance(ev, Move)]
        return out

    def contour(self, p: int, q: int) -> list[Move]:
        return self.contour_moves(self.contour_blocks(p, q))

    def _clone(self) -> "Interpreter":
        twin = copy.copy(self)
        twin.state = copy.deepcopy(self.state)
        twin.state.cycle = None
        twin.frames = copy.deepcopy(self.frames)
        twin.position = dict(self.position)
        twin.macro_modal = None
        twin.stack = list(self.stack)
        twin.on_statement = None
        return twin

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


def _log_length(profile: Profile) -> int | None:
    """Profile parameter "preview log": how many statements the preview log keeps (< 0: all)."""
    v = profile.param("preview log", 1000)
    try:
        n = int(v)
    except (TypeError, ValueError, OverflowError):
        return 1000
    return None if n < 0 else n


def _transforms(host: "Interpreter"):
    """`nc.transforms` (issue 4) when scaling, mirror or rotation is active, else None."""
    tr = _transforms_module
    if tr is None:
        return None
    try:
        return tr if tr.stack(host).active else None
    except AttributeError:
        return None


def _compensation():
    try:
        from nc.compensation.stream import compensate
    except ImportError:
        return None
    return compensate
