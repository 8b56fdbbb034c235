"""B200 (issue 17): a lean run (nc.interp.lean_run) writes each of its lines into one LineBlock of its own instead of
making one a line. What a caller reads of `Interpreter.block` at an event is the line of that event all the same: its
line, text, N and words (read as the parser reads the line, again after an earlier line's words were read), equal to
and printed as the parser's Block, with the preview window and without; the run's lines share the one object (the
1.3k instructions a CAM block B200 saves), the line before the run (the shape's `run`) has its own."""

from __future__ import annotations

import pytest

from nc.interp import Interpreter
from nc.interp.lean import LineBlock
from nc.moves import Move
from nc.profiles import make_profile
from nc.program import parse_program


def _program(n: int) -> str:
    lines = ["G90 G17 G94 G01 F3000"]
    for i in range(n):
        lines.append(f"N{10 + i} X{i * 0.5:.3f} Y{-i * 0.25:.4f}")
    lines.append("M30")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("preview", [False, True])
def test_each_event_reads_its_own_line_from_the_runs_block(preview: bool) -> None:
    text = _program(150)
    parsed = parse_program(text).blocks
    by_line = {b.line: b for b in parsed}
    ip = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
    blocks = []
    moves = 0
    for ev in ip.run(parse_program(text), preview=preview):
        if type(ev) is not Move:
            continue
        moves += 1
        b = ip.block
        if preview:  # the window reads ahead: the block is the last line read, not the event's, and all of it that line's
            mine = by_line[b.line]
            assert b.text == mine.text and [(w.letter, w.value) for w in b.words] == [(w.letter, w.value) for w in mine.words]
            assert b == mine and repr(b) == repr(mine) and b.n == mine.n
            continue
        want = by_line[ev.line]
        assert (b.line, b.text, b.n) == (want.line, want.text, want.n) == (ev.line, ev.block, 10 + moves - 1)
        assert [(w.letter, w.value) for w in b.words] == [(w.letter, w.value) for w in want.words]
        assert b == want and repr(b) == repr(want)
        blocks.append(b)
    assert moves == 150
    assert ip._lean.runs >= 2  # the lines were read in chunks
    if not preview:
        assert type(blocks[0]) is LineBlock and all(type(b) is LineBlock for b in blocks)
        assert blocks[0] is not blocks[1]  # the first line's (the shape's `run`): its own
        # the run's lines one LineBlock (chunks of 64, 64, 11, 5, 3 lines), a line the runs leave its own (the last
        # two: the shape's `run`, then a run of one line): 4 objects for 150 lines (held here: distinct ids)
        assert all(b is blocks[1] for b in blocks[1:148])
        assert len({id(b) for b in blocks}) == 4
