"""Block reading and checking: expressions resolved, G codes looked up by modal group, letters
and codes a block may not hold refused (alarms that need no motion state). LinuxCNC: interp_read + interp_check.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from math import isfinite

from nc.alarms import NcAlarm
from nc.interp import context
from nc.interp.gcodes import lookup
from nc.program.blocks import Block, Word
from nc.program.expr_compiled import evaluate
from nc.interp.records import LETTERS

# letters outside a macro call that functions read on every profile (axes A/B/C/X/Y/Z checked below)
_COMMON_LETTERS = frozenset("ABCDFGHIJKLMNPQRSTXYZ")
_READ_LETTERS: dict[tuple[tuple[str, ...], bool], frozenset[str]] = {}


class ReadingMixin:
    def _resolve(self, block: Block) -> Block:
        """Evaluate the expressions of a block's words; vacant values drop the word (B.3.1.1)."""
        if not block.has_expr:
            return block
        read = self.vars.get
        words = []
        for w in block.words:
            e = w.expr
            if e is None:
                words.append(w)
                continue
            v = evaluate(e, read)
            if v is None:
                continue
            if not isfinite(v):
                raise NcAlarm(0x0223, f"{w.text} is not a finite number")
            words.append(Word(w.letter, v, w.text, True))
        # the constructor: Block.copy would copy the words just replaced (every pass of a loop, issue 16)
        b = Block(block.line, block.text, words, block.n, block.skip, dict(block.comma), block.comment, block.stmt, {})
        for k, e in block.comma_expr.items():
            v = evaluate(e, read)
            if v is not None:
                b.comma[k] = v
        return b

    # ---- G codes ---------------------------------------------------------------------------
    def _gcodes(self, block: Block) -> list[tuple[int, str, Word]]:
        seen: dict[int, str] = {}
        out = []
        for w in block.all("G"):
            entry = lookup(self.profile, w.value)
            if entry is None and round(w.value, 1) == 53.1 and not self.profile.legacy:
                # App. A 0x021B "The G53.1 command must be used after the G68.2 command": G68.2 (tilted working
                # plane) is not an NC5 G code of N§2 and never active here, so G53.1 is always out of place
                raise NcAlarm(0x021B, f"{w.text} must follow G68.2 (tilted working plane), which is not active")
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
        call = "G65" in funcs or "G66" in funcs  # a macro call's arguments take any letter (A-Z but G L N O P)
        for w in block.words:
            if w.letter in self.axes or w.letter in LETTERS and (call or w.letter in self._read_letters()):
                continue
            raise NcAlarm(0x0201, f"address {w.letter} is not defined on this machine ({w.text})")
        for a in ("Y", "A", "B", "C", "X", "Z"):
            if a not in self.axes and block.has(a) and not self._letter_is_arg(a, funcs):
                raise NcAlarm(0x0201, f"axis {a} is not defined on this machine")

    def _read_letters(self) -> frozenset[str]:
        """Letters some NC5 function reads on this machine (language.md, session 21): E is read by none, and
        U/V/W only as the lathe's incremental X/Y/Z and its cycles' depths (N§3.3 note 3, §3.15), so a stray
        `E5` or `V5.` on a mill is 0x0201 as App. A's `G01O100.` rather than silently dropped."""
        key = (self.axes, self.profile.is_lathe)
        got = _READ_LETTERS.get(key)
        if got is None:
            extra = {"U", "W"} | ({"V"} if "Y" in self.axes else set()) if self.profile.is_lathe else set()
            got = _READ_LETTERS[key] = frozenset(_COMMON_LETTERS | extra)
        return got

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
