"""Subprogram and macro calls and returns: G65/G66, M98, G-/M-/T-code calls (parameter tables),
M99, and the M96/M97 interrupt program.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.interp.state import PLANES
from nc.moves import Event, Move, ProgramEnd
from nc.program.blocks import Block
from nc.interp.records import ARG_LETTERS, Frame, MAX_MACRO_DEPTH, MAX_SUB_DEPTH


class CallsMixin:
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
        limit = self._block_limit  # the run's guard (Interpreter._run)
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

    # ---- calls ---------------------------------------------------------------------------------
    def _args(self, block: Block, skip: set[str]) -> dict[int, float]:
        """Argument letters -> locals (N§3.11.4: 2nd/3rd use at +26/+52, T up to 5)."""
        args: dict[int, float] = {}
        counts: dict[str, int] = {}
        legacy = self.profile.legacy
        for w in block.words:
            letter = w.letter
            if letter in skip:
                continue
            slots = _ARG_SLOTS.get(letter)
            if slots is None:
                if letter not in ("G", "L", "N", "O", "P"):
                    raise NcAlarm(0x0251, f"{letter} cannot be a macro argument")
                continue
            if legacy:
                args[slots[0]] = w.value  # one use per letter: last wins (A20)
                continue
            k = counts.get(letter, 0)
            counts[letter] = k + 1
            if k >= len(slots):
                raise NcAlarm(0x0251, f"argument {letter} used more than {len(slots)} times")
            args[slots[k]] = w.value  # unscaled (A4: macro arguments keep their value)
        return args

    def _push_macro(self, number: int, count: int, args: dict[int, float], kind: str,
                    code: str | None = None) -> None:
        # a count of the frames only when there are enough of them (every call pays for this test)
        if len(self.stack) >= MAX_MACRO_DEPTH and sum(1 for f in self.stack if f.locals_pushed) >= MAX_MACRO_DEPTH:
            raise NcAlarm(0x0212, f"more than {MAX_MACRO_DEPTH} nested macro calls")
        prog = self.store.find(number, macro_call=kind in ("gcall", "mcall", "tcall"),
                               code=0x0004 if kind != "g65" else 0x0263)
        if count < 1:
            return
        self.vars.push_locals(args)  # a copy: the macro writes its locals, every repetition starts from `args`
        self.stack.append(Frame(prog, 0, kind, True, count, call_code=code, args=args))

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
            n = int(first.value)
            if first.value != n:
                return None
            # `_call_table`, inline: every block that starts with a G or M code asks
            tables = self._call_tables
            if tables is None:
                tables = self._call_tables = call_tables(self.profile)
            single, (f0, o0, cnt) = tables[first.letter]
            number = single.get(n)
            if number is None:
                if not (cnt and f0 <= n < f0 + cnt):
                    return None
                number = o0 + n - f0
            code = f"{first.letter}{int(first.value)}"
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
        """The macro program a G or M code calls, else None. The tables are built from the parameters
        once per interpreter (issue 16: formatting and looking up ~60 parameter names on every block
        was a quarter of the interpreting time); the interpreter never writes these parameters, and a
        caller that changes them mid-run calls `params_changed()`."""
        tables = self._call_tables
        if tables is None:
            tables = self._call_tables = call_tables(self.profile)
        single, span = tables[letter]
        hit = single.get(n)
        if hit is not None:
            return hit
        f0, o0, cnt = span
        if cnt and f0 <= n < f0 + cnt:
            return o0 + n - f0
        return None

    def params_changed(self) -> None:
        """Parameters were changed from outside: derived tables are built again on next use."""
        self._call_tables = None

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

    def _m99(self, block: Block) -> bool:
        """M99: a subprogram returns; the main program runs again (True: it loops, where M2x026 may end it)."""
        p = block.get("P")
        if len(self.stack) == 1:
            fr = self.frame
            if p is not None and not self.profile.legacy:
                self._jump_label(int(p.value))
                return True
            limit = int(self.profile.param("M99 main restarts", 1))
            if fr.restarts >= limit:
                fr.pc = len(fr.program.blocks)  # the emulator stops the endless main loop (A22)
                return False
            fr.restarts += 1
            fr.pc = 0
            fr.loops, fr.ifs = [], []
            return True
        self._return(None if self.profile.legacy or p is None else int(p.value))
        return False

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
        self._lean_origin = None
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

# the locals each argument letter fills, first use first (N§3.11.4: 2nd/3rd use at +26/+52, T also #85 #92)
_ARG_SLOTS: dict[str, tuple[int, ...]] = {
    letter: (n, n + 26, n + 52) + ((85, 92) if letter == "T" else ()) for letter, n in ARG_LETTERS.items()}

CallTable = tuple[dict[int, int], tuple[int, int, int]]


def call_tables(p) -> dict[str, CallTable]:
    """G and M code-call tables of profile `p`: single codes (N1.200-N1.249 -> O9100…, N1.250-N1.299
    -> O9150…; lathe-2018 O9010-O9019 / O9020-O9029) and the range (N1.120-N1.122 / N1.123-N1.125).
    The first parameter naming a code wins, as the search in that order did."""
    out: dict[str, CallTable] = {}
    for letter in ("G", "M"):
        single: dict[int, int] = {}
        if p.legacy:
            base = 9010 if letter == "G" else 9020
            for i in range(10):
                v = p.params.get(f"O{base + i}")
                if v and float(v).is_integer():
                    single.setdefault(int(v), base + i)
            out[letter] = (single, (0, 0, 0))
            continue
        first_param, onum = (200, 9100) if letter == "G" else (250, 9150)
        for i in range(50):
            v = p.params.get(f"N1.{first_param + i}")
            if v and float(v).is_integer():
                single.setdefault(int(v), onum + i)
        first, o, amount = ("N1.120", "N1.121", "N1.122") if letter == "G" else ("N1.123", "N1.124", "N1.125")
        out[letter] = (single, (int(p.param(first)), int(p.param(o)), int(p.param(amount))))
    return out
