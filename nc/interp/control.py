"""Macro statements and control flow: assignments, IF/THEN/ELSE, WHILE/END, EXITW, GOTO and label
search (N§3.11). LinuxCNC: interp_o_word.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

import math

from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.moves import Event, Sync
from nc.program.syntax import Assign, Block, Else, ElseIf, End, EndIf, ExitW, Goto, IfGoto, IfThen, While
from nc.program.expr_compiled import assignment, evaluate
from nc.interp.records import Frame, MAX_IF_DEPTH, MAX_WHILE_DEPTH


class ControlMixin:
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

    # ---- statements --------------------------------------------------------------------------
    def _statement(self, block: Block) -> Event | None:
        """Run one macro statement; the Sync it calls for (a write to a live # variable), else None.
        A plain function, not a generator: statements are most blocks of a macro program (issue 16)."""
        s = block.stmt
        self._lean_origin = None  # the lean lane asks for its plain state again (nc.interp.lean)
        if self.on_statement is not None:
            self.on_statement(block, self.stack[-1].program.name)
        if self.budget is not None:
            self.budget.spend()
        if type(s) is Assign:
            vs = self.vars
            n, v = assignment(s, s.target, s.value, vs.get)
            if v is not None and not math.isfinite(v):
                raise NcAlarm(0x0257, "assignment of a non-finite value")
            if 0 < n <= vs._lmax and v is not None:  # a local: `Variables.set` of it, inline (most writes)
                vs.frames[-1][n] = float(v)
                return None
            vs.set(n, v)
            if n > 99 and self.sys.live(n):  # no local variable (#1-#99) is a live system variable
                return Sync(block.line, block.text, f"#{n}")
            return None
        self._control(s, self.stack[-1])
        return None

    def _control(self, s, fr: Frame) -> None:
        """GOTO, IF, WHILE/END and EXITW: where the program counter goes next (WHILE and END first: every
        pass of a loop runs them)."""
        t = type(s)  # the statement classes are final: identity is the cheapest test
        if t is While:
            wpc = fr.pc - 1
            if s.do is not None and s.do not in (1, 2, 3):
                raise NcAlarm(0x0214, f"DO{s.do}: loop numbers are 1, 2 and 3")
            if s.do is None and not self.profile.legacy:
                raise NcAlarm(0x0215, "WHILE without DO")
            if s.do is not None and self.profile.legacy:
                raise NcAlarm(0x0207, "lathe-2018 loops are WHILE [..] ... ENDW")
            active = fr.loops and fr.loops[-1][0] == wpc
            # the END of a loop already entered is known; a scan only when the loop starts
            epc = fr.loops[-1][1] if active else self._scan_end(fr, wpc, s.do)
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
        if t is End:
            if s.do is not None and s.do not in (1, 2, 3):
                raise NcAlarm(0x0225, f"END{s.do}: loop numbers are 1, 2 and 3")
            if not fr.loops or fr.loops[-1][2] != s.do or fr.loops[-1][1] != fr.pc - 1:
                raise NcAlarm(0x022B, f"END{'' if s.do is None else s.do} has no matching WHILE")
            fr.pc = fr.loops[-1][0]
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
        v = evaluate(cond, self.vars.get)
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
