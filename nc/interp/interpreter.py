"""The block executor: turns parsed blocks into canonical events in machine coordinates.

The interpreter is a generator so the channel can pull it block by block and stop reading ahead
where the controller would (a `Sync` event).  Execution is a program counter over the block list
of the current program with a call stack (M98, G65, G66, G/M/T-code macros, M96 interrupts);
macro statements (assignments, IF, WHILE, GOTO) run when the block is read.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

from nc.alarm_table import ENDLESS_LOOP
from nc.alarms import NcAlarm, internal_error
from nc.budget import StatementBudget
from nc.interp.corners import expand_corners
from nc.interp.lean import MISS, NOTHING, LeanLane
from nc.interp.preview import Passing, PreviewWindow
from nc.interp.servo import ServoPort
from nc.interp.state import Frames, ModalState
from nc.interp.sysvars import SystemVariables
from nc.interp.tools import ToolTable
from nc.interp.variables import Variables
from nc.moves import BUSY, Event, Move, ProgramEnd
from nc.profiles import Profile
from nc.program.blocks import Block, Program
from nc.store import ProgramStore
from nc.interp.calls import CallsMixin
from nc.interp.canonical import CanonicalMixin
from nc.interp.contour import ContourMixin
from nc.interp.control import ControlMixin
from nc.interp.execute import ExecuteMixin
from nc.interp.modal import ModalMixin
from nc.interp.motion import MotionMixin
from nc.interp.nonmodal import NonModalMixin
from nc.interp.reading import ReadingMixin
from nc.interp.records import Frame, PreviewRecord, _compensation, _log_length


def _located(exc: Exception, block: Block, program: str) -> NcAlarm:
    """The alarm a block raised, or its numerical error as 0x0257, at the block's line."""
    if isinstance(exc, NcAlarm):
        return exc.at(block.line, block.text, program)
    return NcAlarm(0x0257, f"numerical error: {exc}", line=block.line, block=block.text, program=program)


class Interpreter(ExecuteMixin, ReadingMixin, ModalMixin, MotionMixin, NonModalMixin, ControlMixin, CallsMixin, ContourMixin, CanonicalMixin):
    # True: plain motion lines in the plain state run straight from their text (nc.interp.lean, issue 17);
    # False runs every block through `_execute` (tests compare the two)
    lean = True

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
        # axes whose origin status is missing (a bench axis that needs homing, run with --no-home): G28/G30/G53
        # move them in machine coordinates and raise App. A 0x0A08 (decisions language.md A42)
        self.unreferenced: frozenset[str] = frozenset()
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
        self._block_limit = int(profile.param("max blocks", 1_000_000))  # set per run by _run
        self._call_tables = None  # G/M code-call tables from the parameters (CallsMixin._call_table)
        self._plans: dict[str, tuple] = {}  # block text -> (block, G codes, functions, steps, M codes) (_read_run)
        self._gcall_depth = 0
        self._three_point: dict[str, float] | None = None  # G2.4/G3.4 middle point
        self._plain_axes = frozenset(self.axes) - {"G", "M", "T", "F", "S", "D"}  # `_axis_block` letters
        # True: runs of plain G0/G1 blocks come as one MoveBatch event (nc.interp.bulk); for a consumer
        # that formats them in bulk (`hil path`), never the channel, which plans Move by Move
        self.bulk = False
        self.corner_pending = False  # a ,C/,R block waits for its motion block (set by expand_corners)
        self._bulk_skip: tuple | None = None  # (blocks, first, end): a run nc.interp.bulk found too short
        self._lean: LeanLane | None = None  # plain motion lines run from their text (nc.interp.lean)
        # the lean lane's work origin while the state is its plain one, None when anything may have changed
        # that (every block `_execute` or `_statement` runs, a system variable written, a run begun)
        self._lean_origin: dict[str, float] | None = None

    # ---- public ---------------------------------------------------------------------------

    def take_position(self, start: dict[str, float]) -> None:
        """Start from where the axes stand (machine coordinates), before the program runs."""
        self.position.update({a: v for a, v in start.items() if a in self.position})
        # the last block's end is where the axes stand too: a G43/G44/G49 block without Z keeps it
        # (`_length_comp_move`) and #21032+ read it; left at 0 a first `G49` dived to Z0 (fuzz21)
        self.last_target = self.work_position()
    def variable(self, number: int) -> float | None:
        return self.vars.get(number)

    def record_skip(self, machine: dict[str, float]) -> None:
        """Issue 5 reports where a G31 move stopped; #21048…/#21064… read it back."""
        self.skip_position = dict(machine)
        self.position.update(machine)

    def run(self, program: Program, *, preview: bool = True) -> Iterator[Event]:
        passing = Passing() if preview else None  # what the preview window may read past the stages
        events: Iterator[Event] = expand_corners(self, self._run(program, passing))
        comp = _compensation()
        if comp is not None:
            events = comp(events, self.profile, passing)
        if preview:
            events = iter(PreviewWindow(self, events, int(self.profile.param("preview depth", 8)), passing))
        return events

    # ---- the program counter -----------------------------------------------------------------
    def _run(self, program: Program, passing: Passing | None = None) -> Iterator[Event]:
        """The program counter, with a bug in the interpreter reported as 0x0000 at the block it was reading (the
        guide's standard: an internal error names the file, line and block too), not without a place. One
        generator (the guard was a second one around it, a frame resumed a block: issue 17, decisions bench B173)."""
        try:
            self.program_name = program.name
            self._lean_origin = None
            self.stack = [Frame(program)]
            if not self._own_store and program.store is not None:
                self.store = program.store
            if program.number is not None:
                self.store.loaded.setdefault(program.number, program)
            # A straight program runs each of its lines once, however long (a 1M-line CAM file); the guard
            # counts what loops and calls add beyond that (decision P5).
            limit = self._block_limit = int(self.profile.param("max blocks", 1_000_000)) + len(program.blocks)
            last: Block | None = None
            budget = self.budget
            bulk = None
            if self.bulk:  # a consumer that takes MoveBatch events (`hil path`)
                from nc.interp import bulk
            lean = self._lean
            if lean is None:
                lean = self._lean = LeanLane(self)
            take, nothing, miss = lean.take, NOTHING, MISS
            cur = None  # the frame `blocks`, `count`, `parsed` and `name` are of (read again when it changes)
            while self.stack:
                if budget is not None and budget.used >= budget.limit:  # `spent`, without a property call a block
                    yield BUSY  # the rest of the macro next cycle; the cycle never stalls (decisions B2)
                    continue
                fr = self.stack[-1]
                if self._interrupt_pending:
                    self._interrupt_pending = False
                    yield from self._start_interrupt()
                    continue
                if fr is not cur:
                    cur, blocks, name = fr, fr.program.blocks, fr.program.name
                    count = len(blocks)
                    # a BlockList's parsed items by index (None: a plain line, read when reached); a list of blocks
                    # has no plain lines
                    parsed = getattr(blocks, "parsed", None) or blocks.__getitem__
                    lean_unread = self.lean  # the frame's lines for the lean lane: looked up at its first plain line
                    index = None
                pc = fr.pc
                if pc >= count:
                    if len(self.stack) == 1:
                        break
                    self._return(None)  # end of a subprogram without M99 returns like M99
                    continue
                block = parsed(pc)
                if block is None:  # a plain line: the bulk lane is asked only there (never at a statement)
                    if bulk is not None and not self.corner_pending and (batch := bulk.take(self, fr, limit)) is not None:
                        if len(batch):  # a run of plain G0/G1 blocks read in one pass (nc.interp.bulk); one
                            yield batch  # that moved nothing (`G1 F100` lines) is no event, as block by block
                        last = self.block
                        continue
                    # a plain motion line in the plain state, run from its text (nc.interp.lean, issue 17)
                    if lean_unread:
                        lean_unread = False
                        index, refused = lean.lines(blocks)
                        if index is not None:
                            text, starts, lengths, file_lines = index
                    if index is not None and pc not in refused:
                        # the line's text and file line read here (`BlockList.raw`, `line`), and the shape of
                        # the last line taken tried here: no call per line but the shape's own
                        start = starts[pc]
                        raw = text[start:start + lengths[pc]]
                        shape = lean.last
                        if shape is None or (ev := shape.run(lean, self, fr, pc, raw, limit, file_lines[pc])) is miss:
                            ev = take(fr, pc, raw, limit, file_lines[pc])
                        if ev is not None:
                            last = self.block
                            if ev is not nothing:
                                yield ev  # type: ignore[misc]
                                # the lines after it of the same shape read in one pass, handed out Move by Move
                                # (nc.interp.lean_run, issue 17): until one is not, or anything may differ
                                if bulk is None and (stream := lean.last.stream) is not None \
                                        and (pc := fr.pc) not in lean.retry:
                                    lean_run = stream(lean, self, fr, pc, limit, text, starts, lengths, file_lines,
                                                      count, budget)
                                    if passing is None:
                                        yield from lean_run
                                    else:  # the preview window may read it past the stages (nc.interp.preview)
                                        passing.stream = lean_run
                                        yield from lean_run  # at once done when the window has read it to its end
                                        passing.stream = None
                                    last = self.block
                            continue
                    block = blocks[pc]
                last = block
                # `_take_block`, inline: this runs for every block
                fr.pc = pc + 1
                self._executed += 1
                if self._executed > limit:
                    self._too_many(fr, limit, block)
                if block.skip and self.block_skip:
                    continue
                self.program_name = name
                if block.stmt is not None:  # a macro statement: a plain call, no generator (issue 16)
                    # and the statements after it in this frame, without the checks above: a statement
                    # neither pushes nor pops a frame, and nothing outside runs until this generator yields
                    # (a statement budget is checked above, statement by statement)
                    try:
                        while (ev := self._statement(block)) is None and budget is None:
                            pc = fr.pc
                            if pc >= count or (nxt := parsed(pc)) is None or nxt.stmt is None or nxt.skip:
                                break
                            last = block = nxt
                            fr.pc = pc + 1
                            self._executed += 1
                            if self._executed > limit:
                                self._too_many(fr, limit, block)
                    except (NcAlarm, ValueError, ArithmeticError, OverflowError) as exc:
                        raise _located(exc, block, fr.program.name) from None
                    if ev is not None:
                        yield ev
                    continue
                try:
                    end = False
                    for ev in self._execute(block):
                        yield ev
                        if isinstance(ev, ProgramEnd):
                            end = True
                    if end:
                        return
                except (NcAlarm, ValueError, ArithmeticError, OverflowError) as exc:
                    raise _located(exc, block, fr.program.name) from None
            self._check_no_pending_angle()
            yield ProgramEnd(last.line if last else 0, last.text if last else "", 0)
        except NcAlarm:
            raise
        except Exception as exc:
            b = self.block
            raise NcAlarm(0x0000, internal_error(exc).message, line=getattr(b, "line", None),
                          block=getattr(b, "text", None), program=self.program_name) from exc

    _guarded = _run  # the name benchmarks/interp_layers.py reads

    def _take_block(self, fr: Frame, limit: int, block: Block | None = None) -> Block | None:
        """Advance `fr` by one block (`block`, when the caller has read it) and count it; None for a
        skipped '/' block."""
        if block is None:
            block = fr.program.blocks[fr.pc]
        fr.pc += 1
        self._executed += 1
        if self._executed > limit:
            self._too_many(fr, limit, block)
        if block.skip and self.block_skip:
            return None
        self.program_name = fr.program.name
        return block

    def _too_many(self, fr: Frame, limit: int, block: Block) -> None:
        extra = int(self.profile.param("max blocks", 1_000_000))
        raise NcAlarm(ENDLESS_LOOP, f"more than {extra} blocks executed beyond the program's own {limit - extra} "
                                    "blocks (endless loop?; parameter 'max blocks')",
                      line=block.line, block=block.text, program=fr.program.name)

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
