"""Contour programs of the lathe cycles (G70-G73 P..Q): the blocks P..Q, their moves interpreted
on a clone, and skipping them after the cycle.

A mixin of `nc.interp.interpreter.Interpreter` (issue 16): it holds methods only; the state
they use is the Interpreter's (see its __init__)."""

from __future__ import annotations

from collections.abc import Iterator

from nc.alarms import NcAlarm
from nc.interp.corners import expand_corners
from nc.moves import Event, Move
from nc.program.blocks import Block


class ContourMixin:
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
        run = [b for b in blocks if b.stmt is None]  # run in order on the twin (no Program needed)
        if not any(b.comma or b.comma_expr for b in run):
            # no ,C/,R/,A: expand_corners would hand every event on as it is (a stage less per move)
            return [ev for b in run for ev in twin._execute(b) if isinstance(ev, Move)]

        def gen() -> Iterator[Event]:
            for b in run:
                yield from twin._execute(b)
        out = [ev for ev in expand_corners(twin, gen()) if isinstance(ev, Move)]
        return out

    def contour(self, p: int, q: int) -> list[Move]:
        return self.contour_moves(self.contour_blocks(p, q))

    def _clone(self):  # -> the same Interpreter class
        twin = object.__new__(type(self))  # copy.copy without its reduce protocol (a plain class)
        twin.__dict__.update(self.__dict__)
        twin.state = self.state.copy()
        twin.state.cycle = None
        twin.frames = self.frames.copy()
        twin.position = dict(self.position)
        twin.macro_modal = None
        twin.stack = list(self.stack)
        twin.on_statement = None
        twin._lean = None  # the lane holds the interpreter it runs for (nc.interp.lean)
        twin._lean_origin = None  # found again from the twin's own state
        return twin
