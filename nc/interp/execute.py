"""One block in the NC5 order of execution, as one table of steps (LinuxCNC: execute_block).

`_execute` reads and checks the block (`BlockRun`), then runs `EXECUTION_ORDER` top to bottom;
each step is a function of (interpreter, run) and may end the block (`run.done`). The order is
the NC5's (seed 003 §1.2, N§3.2.1 code calls first, App. B M-code timing) and is tabled in
docs/architecture.md.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.codes import lathe_hole_clamp
from nc.interp import context
from nc.interp.gcodes import STOP_PREVIEW
from nc.interp.records import (INCREMENTAL, MAX_M_PER_BLOCK, M_BEFORE_MOTION, M_END, NO_MOTION_FUNCS,
                               REFUSED_UNDER_G68, TRANSFORM_ARG_FUNCS, _transforms)
from nc.moves import Aux, Event, MainLoop, Move, MoveList, ProgramEnd, Sync
from nc.program.blocks import Block, Word


@dataclass(slots=True)
class BlockRun:
    """One block as read and checked: what its steps share."""

    block: Block
    gcodes: list[tuple[int, str, Word]]
    funcs: set[str]
    mvals: list[int]
    was_css: bool
    moved: bool = False  # an axis moved (G66 calls its macro after such a block)
    done: bool = False  # a step ended the block (a call, a return, the program end)


def _moves(events: Iterable[Event], run: BlockRun) -> Iterator[Event]:
    for ev in events:
        if isinstance(ev, Move) and ev.kind != "dwell":
            run.moved = True
        yield ev


def step_g65(ip, run: BlockRun) -> None:
    """G65 P: the macro runs instead of the rest of the block."""
    if "G65" in run.funcs:
        ip._macro_call(run.block, modal=False)
        run.done = True


def step_preview_stop(ip, run: BlockRun) -> Iterator[Event]:
    """Codes that stop the preview (G31, G53, G10 L40 …) and the halt M codes of N1.118/N1.119."""
    block, funcs = run.block, run.funcs
    if not funcs.isdisjoint(STOP_PREVIEW):
        group = ip._g05_group(block) if "G05" in funcs else None  # checked here: its Sync carries it
        yield Sync(block.line, block.text, next(fn for fn in funcs if fn in STOP_PREVIEW), group, ip.program_name)
    halt_m = ip._halt_m(run.mvals) if run.mvals else None
    if halt_m is not None:
        yield Sync(block.line, block.text, f"M{halt_m}")


def step_modal(ip, run: BlockRun) -> None:
    """Modal G codes by group; G66 arms its macro (and ends the block), G67 cancels it."""
    for grp, fn, w in run.gcodes:
        if grp:
            ip._set_modal(grp, fn, w, run.block)
    if "G66" in run.funcs:
        ip._macro_call(run.block, modal=True)
        run.done = True
    elif "G67" in run.funcs:
        ip.macro_modal = None
        ip.state.macro_modal = False


def step_feed_d(ip, run: BlockRun) -> None:
    """F (not for G31 or a cycle, whose F is its own) and the D number."""
    block, funcs, st = run.block, run.funcs, ip.state
    f = block.get("F")
    if f is not None and f.value < 0:  # a feed or a lead alike, in a cycle's block too (fuzz21: it said 0x1001)
        raise NcAlarm(0x0223, "F must not be negative")
    if f is not None and "G31" not in funcs and not (st.cycle or ip._cycle_fn(funcs)):
        st.feed = f.value
    elif f is not None and f.value >= 0 and "G31" not in funcs and not ip._is_thread(funcs):
        st.feed = f.value
    if block.has("D") and not ip._cycle_fn(funcs) and not st.cycle:
        d = block.get("D").value
        if d != int(d) or d < 0 or d > 512:
            raise NcAlarm(0x0217, f"D{d:g} is out of range")
        st.d_number = int(d)


def _cycle_owns_s_t(ip, funcs: set[str]) -> bool:
    """Whether a cycle takes the block's S and T as its own words. The lathe's stock removal cycles do not:
    their `P_ Q_ U_ W_ F_ S_ T_` block names the roughing tool and spindle speed (N§3.15.2-3.15.4)."""
    fn = ip._cycle_fn(funcs)
    return fn is not None and not (ip.profile.is_lathe and fn in ("G71", "G72", "G73"))


def step_spindle(ip, run: BlockRun) -> Iterator[Event]:
    """S: spindle speed or (G96) surface speed, issued before the motion; G96/G97 alone switch now."""
    block, funcs, st = run.block, run.funcs, ip.state
    s = block.get("S")
    # G50/G92 S is the speed clamp and G10 L1100 S the data setting's own speed (issued there, once)
    if s is not None and not funcs & {"set", "G10"} and not _cycle_owns_s_t(ip, funcs):
        if s.value < 0 or s.value > 600000:
            raise NcAlarm(0x0223, f"S{s.value:g} out of range 0-600000")
        top = ip.profile.param("N0.1008", 0.0)
        if not st.css and top > 0 and s.value > top and ip.profile.bit("N0.1000 Bit7"):  # App. A 0x0C03
            raise NcAlarm(0x0C03, f"S{s.value:g} exceeds the spindle's maximum speed N0.1008 = {top:g} rpm")
        st.spindle_speed = s.value
        if st.css:
            st.surface_speed = s.value
        spindle = block.get("P")
        args = {"P": spindle.value} if spindle is not None and not funcs & {"G04", "G10", "G30", "G31", "G900", "G05"} \
            and 98 not in run.mvals else {}
        if st.css:  # G96: S is a surface speed (m/min); the channel turns it into rpm (issue 5)
            args = {**args, "css": 1.0}
            if "X" in ip.axes:  # machine X of the work centre: the diameter before any move
                args["x0"] = ip.frames.origins(st.wcs, ip.axes)["X"]
        yield Aux("S", s.value, block.line, block.text, args=args, program=ip.program_name)
    elif st.css != run.was_css and s is None:
        yield ip._css_switch(block)  # G96 / G97 alone switch when read, not at the next move


def step_tool(ip, run: BlockRun) -> Iterator[Event] | None:
    """T: tool selection and offsets (not a cycle's T)."""
    t = run.block.get("T")
    if t is not None and not _cycle_owns_s_t(ip, run.funcs):
        return ip._tool(run.block, t)
    return None


def step_m_before(ip, run: BlockRun) -> Iterator[Event]:
    """M codes issued to the MLC before the motion starts (M3 M4 M8 M19 M29)."""
    block = run.block
    for m in run.mvals:
        if m in M_BEFORE_MOTION:
            if m in (3, 4):
                ip.state.spindle_dir = 1 if m == 3 else -1
            yield Aux("M", m, block.line, block.text, program=ip.program_name)


def step_nonmodal(ip, run: BlockRun) -> Iterator[Event]:
    """Group-0 G codes (G04 G10 G28 G53 …: `_g_<code>` of NonModalMixin) and the lathe cycles G70-G76."""
    block, funcs = run.block, run.funcs
    if "G53" in funcs and funcs & {"G28", "G30"}:
        raise NcAlarm(0x0265, "G53 and G28/G30 cannot be programmed together")
    for grp, fn, _ in run.gcodes:
        if grp != 0:
            continue
        handler = getattr(ip, "_g_" + fn.replace(".", "_"), None)
        if handler is not None:
            r = handler(block)
            if r is not None:
                yield from _moves(r, run)
        elif fn in ("G70", "G71", "G72", "G73", "G74", "G75", "G76"):
            events = context.run_cycle(ip, fn, block)
            # a computed list of plain uncompensated moves goes on as one event to a consumer that
            # takes batches (issue 16: a G71's thousands of moves, one by one, were a fifth of `hil path`)
            if ip.bulk and type(events) is list and len(events) > 1 \
                    and all([type(e) is Move and e.comp is None for e in events]):
                yield MoveList(events)
            else:
                yield from events
            run.moved = True
            ip._skip_contour(fn, block)


def step_motion(ip, run: BlockRun) -> Iterator[Event] | None:
    """The modal motion (G0 G1 G2 G3 G32 a modal cycle …) unless a group-0 code or a transform owns
    the block's axis words."""
    for grp, fn, _ in run.gcodes:  # a loop, not a list of the group-0 codes (every block, issue 16)
        if grp == 0 and fn in NO_MOTION_FUNCS:
            return None
    if TRANSFORM_ARG_FUNCS.isdisjoint(run.funcs):
        if _still(ip, run):
            return None
        if ip.macro_modal is None:  # `run.moved` is read only for a modal G66 call: no wrapper per move
            return ip._motion(run.block, run.funcs)
        return _moves(ip._motion(run.block, run.funcs), run)
    return None


_STILL_FUNCS = frozenset({"G43", "G44", "G49"})  # a length offset change moves Z without an axis word


def _still(ip, run: BlockRun) -> bool:
    """A block `_motion` would find nothing to do in (`M99`, `M05`, `T0101` …; issue 16): no axis,
    incremental, centre word or ,A, no length offset code, and no modal cycle, pending ,A or G2.4
    partner or polar mode that a block without axis words still acts on."""
    st = ip.state
    if st.cycle is not None or st.polar or ip._angle_pending is not None or ip._three_point is not None \
            or "A" in run.block.comma or not _STILL_FUNCS.isdisjoint(run.funcs):
        return False
    letters = _MOTION_LETTERS.get(ip.axes)
    if letters is None:
        letters = _MOTION_LETTERS[ip.axes] = frozenset(ip.axes) | frozenset(INCREMENTAL) | {"I", "J", "K"}
    for w in run.block.words:
        if w.letter in letters:
            return False
    return True


_MOTION_LETTERS: dict[tuple[str, ...], frozenset[str]] = {}


def step_m_after(ip, run: BlockRun) -> Iterator[Event]:
    """M codes after the motion: M5, the program end M2/M30, M98 call, M99 return, M96/M97 (preview
    stops), every other M to the MLC."""
    block = run.block
    for m in run.mvals:
        if m in M_BEFORE_MOTION:
            continue
        if m == 5:
            ip.state.spindle_dir = 0
        if m in M_END:
            yield Aux("M", m, block.line, block.text, program=ip.program_name)
            ip._check_no_pending_angle()
            ip._reset_at_end()
            yield ProgramEnd(block.line, block.text, m)
            run.done = True
            return
        if m == 98:
            ip._sub_call(block)
            run.done = True
            return
        if m == 99:
            if ip._m99(block):
                yield MainLoop(block.line, block.text)  # the MLC's M99 Call Stop may end the program here
            if ip._interrupt_resume is not None and not any(f.kind == "m96" for f in ip.stack):
                yield ip._resume_after_interrupt()
            run.done = True
            return
        if m == 96:
            # a preview stop: M2x019 is honoured from this block's execution on, not from its reading
            yield Sync(block.line, block.text, "M96")
            ip._m96(block)
            continue
        if m == 97:
            yield Sync(block.line, block.text, "M97")
            ip.interrupt_program = None
            continue
        yield Aux("M", m, block.line, block.text, program=ip.program_name)


def step_g66_call(ip, run: BlockRun) -> None:
    """G66: the macro is called after every block that moved an axis, never inside the macro (A18)."""
    if run.moved and ip.macro_modal is not None and not any(f.kind == "g66" for f in ip.stack):
        prog, count, args = ip.macro_modal
        ip._push_macro(prog, count, dict(args), "g66")


Step = Callable[..., "Iterator[Event] | None"]


class Shape:
    """What a block holds that decides which steps can act on it: its letters, G functions and
    their modal groups (the same for every run of a block whose G and M words are plain numbers)."""

    __slots__ = ("letters", "funcs", "groups")

    def __init__(self, letters: frozenset[str], funcs: frozenset[str], groups: frozenset[int]) -> None:
        self.letters, self.funcs, self.groups = letters, funcs, groups


# The NC5 order of execution of one block, after it is read and checked (docs/architecture.md):
# (name, step, when it can act). A step whose condition is false for a block's shape is a no-op for
# it (its body tests the same words) and is left out of the block's plan (issue 16).
EXECUTION_ORDER: tuple[tuple[str, Step, Callable[[Shape], bool]], ...] = (
    ("G65 macro call", step_g65, lambda s: "G65" in s.funcs),
    ("preview stops", step_preview_stop, lambda s: "M" in s.letters or not s.funcs.isdisjoint(STOP_PREVIEW)),
    ("modal G codes, G66/G67", step_modal, lambda s: bool(s.groups - {0})),
    ("F, D", step_feed_d, lambda s: "F" in s.letters or "D" in s.letters),
    ("S", step_spindle, lambda s: "S" in s.letters or 17 in s.groups),  # G96/G97 (group 17) switch alone
    ("T", step_tool, lambda s: "T" in s.letters),
    ("M before motion", step_m_before, lambda s: "M" in s.letters),
    ("group-0 G codes, lathe cycles", step_nonmodal, lambda s: 0 in s.groups),
    ("motion", step_motion, lambda s: True),
    ("M after motion, calls, returns, end", step_m_after, lambda s: "M" in s.letters),
    ("G66 call after a move", step_g66_call, lambda s: True),
)
ALL_STEPS: tuple[Step, ...] = tuple(step for _, step, _ in EXECUTION_ORDER)


def plan(shape: Shape) -> tuple[Step, ...]:
    """The steps of EXECUTION_ORDER that can act on a block of this shape, in order."""
    return tuple(step for _, step, when in EXECUTION_ORDER if when(shape))


def _one_call(funcs: set[str], mvals: list[int]) -> None:
    """One call command per block (G65, G66, M98, M96), else 0x024B."""
    calls = [c for c in ("G65", "G66") if c in funcs] + [f"M{m}" for m in mvals if m in (98, 96)]
    if len(calls) > 1:
        raise NcAlarm(0x024B, f"one block can only hold one call command ({' '.join(calls)})")


_PLAN_LIMIT = 4096  # blocks whose plan is remembered; then the memo starts over (memory flat)


class ExecuteMixin:
    # ---- one block -----------------------------------------------------------------------------
    def _execute(self, raw: Block) -> Iterator[Event]:
        self._lean_origin = None  # the lean lane asks for its plain state again (nc.interp.lean)
        if raw.stmt is not None:  # a macro statement (ControlMixin); `_run` runs most of them itself
            ev = self._statement(raw)
            if ev is not None:
                yield ev
            return
        block = self._resolve(raw)
        self.block = block
        words = block.words
        # lean path: every step below is a no-op for such a block (asked only of a block that starts
        # with an axis word)
        if words and words[0].letter in self._plain_axes and self._axis_block(block):
            yield from self._motion(block, set())
            return
        # code-called macros: the calling code must be first in the block (N§3.2.1)
        called = self._code_call(block)
        if called is not None:
            yield from called
            return
        run, steps = self._read_run(block, raw)
        for step in steps:
            r = step(self, run)
            if r is not None:
                yield from r
            if run.done:
                return

    def _read_run(self, block: Block, raw: Block | None = None) -> tuple[BlockRun, tuple[Step, ...]]:
        """Read and check the block's G and M codes: letters it may not hold, M ranges, one call per
        block; with the steps that can act on it. What depends on the block's text alone (G lookup,
        letter check, M codes and their checks, plan) is done once per block `raw` whose G and M words
        are plain numbers (a loop body runs thousands of times). Remembered by the block's text: a line
        written again reads the same (a repeated part, a lathe contour's G71 and G70 runs, issue 16)."""
        memo = self._plans
        hit = memo.get(raw.text) if raw is not None else None
        if hit is not None:
            gcodes, funcs, steps, mvals = hit[1], hit[2], hit[3], hit[4]
            if steps is None:  # the block's own letters are refused: as checked on its values
                self._check_letters(block, funcs)
                steps = ALL_STEPS
            self._check_g68(funcs)
            return BlockRun(block, gcodes, funcs, mvals, self.state.css), steps
        gcodes = self._gcodes(block)
        funcs = {fn for _, fn, _ in gcodes}
        self._check_letters(block, funcs)
        steps: tuple[Step, ...] | None = ALL_STEPS
        plain = raw is not None and not any(w.expr is not None and w.letter in "GM" for w in raw.words)
        if plain:
            try:  # the raw block's letters (a vacant word is dropped from `block`, never added)
                self._check_letters(raw, funcs)
                steps = plan(Shape(frozenset(w.letter for w in raw.words), frozenset(funcs),
                                   frozenset(g for g, _, _ in gcodes)))
            except NcAlarm:
                steps = None
        self._check_g68(funcs)
        mvals = self._mcodes(block, funcs)
        if plain:  # remembered once its M codes passed their checks (they alarm again on every read)
            if len(memo) >= _PLAN_LIMIT:
                memo.clear()
            memo[raw.text] = (raw, gcodes, funcs, steps, mvals)
        return BlockRun(block, gcodes, funcs, mvals, self.state.css), steps or ALL_STEPS

    def _check_g68(self, funcs: set[str]) -> None:
        if (self.state.rotation or "G68" in funcs) and "G69" not in funcs and funcs & REFUSED_UNDER_G68:
            raise NcAlarm(0x025F, f"{' '.join(sorted(funcs & REFUSED_UNDER_G68))} while G68 rotation is on: "
                                  "cancel it with G69 first")

    def _mcodes(self, block: Block, funcs: set[str]) -> list[int]:
        """The block's M codes, checked: range, count, one call per block, M98 alone."""
        mcodes = block.all("M")
        for w in mcodes:
            if w.value != int(w.value) or not 0 <= w.value <= 65534:
                raise NcAlarm(0x0249, f"M code {w.text} out of range")
        mvals = [int(w.value) for w in mcodes]
        if mvals and lathe_hole_clamp(self.profile, self._cycle_fn(funcs), block) is not None:
            mvals = []  # the hole cycle's own M_ (clamp at the hole, M+1 at R), not an ordinary M
        if len(mvals) > MAX_M_PER_BLOCK:
            raise NcAlarm(0x0248, f"{len(mvals)} M codes in one block (at most {MAX_M_PER_BLOCK})")
        _one_call(funcs, mvals)
        if 98 in mvals and len(mvals) > 1:
            raise NcAlarm(0x0249, "M98 must be the only M code of its block")
        return mvals

    def _halt_m(self, mvals: list[int]) -> int | None:
        first = int(self.profile.param("N1.118", 0))
        if not first:  # no halt M codes (the default)
            return None
        count = int(self.profile.param("N1.119", 0))
        for m in mvals:
            if first and first <= m < first + count:
                return m
        return None

    def _reset_at_end(self) -> None:
        """M02/M30: G92/G50 shift, length comp, scaling and the tool offset number are cancelled."""
        self._lean_origin = None
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
