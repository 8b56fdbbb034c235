"""Programs are read in place in the file's text (issue 16: no list of lines, plain lines kept as
offsets; memory flat in program length): every block still carries its file line number and text
as str.splitlines numbers and cuts them, whatever the line breaks (\\n, \\r\\n, \\r, form feed,
U+2028), labels point at their blocks, and each O program of a file gets its own blocks."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from nc.program.blocks import parse_programs

LINES = ["G1 X1. Y2. F100", "N10 G0 X5", "X1.5 Z-2", "  ", "", "(a comment)", "G1 X#1 (why)", "#1 = #1 + 1",
         "N20 X3", "O2000", "O0300 (second)", "%", "/X7.", "M30", "N30 G4 P100", "\tY-0.25", "IF [#1 GT 2] GOTO20"]
BREAKS = ["\n", "\n", "\n", "\r\n", "\r", "\x0c", "\u2028"]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(LINES), st.sampled_from(BREAKS)), max_size=30))
def test_blocks_keep_their_lines_and_texts(pairs) -> None:
    text = "".join(line + brk for line, brk in pairs)
    lines = text.splitlines()
    progs = parse_programs(text, "P.nc")
    seen = []
    for prog in progs:
        for i, b in enumerate(prog.blocks):
            assert b.text == lines[b.line - 1]  # the line as splitlines cuts it, by its number
            assert prog.blocks.line(i) == b.line
            seen.append(b.line)
        for n, where in prog.labels.items():
            assert all(prog.blocks[k].n == n for k in where)
    assert seen == sorted(seen)  # every program after the one before, in file order
    o_lines = [k + 1 for k, line in enumerate(lines) if line.lstrip().upper().startswith("O")]
    numbered = [p.number for p in progs if p.number is not None]
    assert numbered == [int(lines[k - 1].strip()[1:].split()[0]) for k in o_lines]


def test_a_long_plain_program_keeps_no_object_per_line() -> None:
    text = "O1000\n" + "".join(f"G1 X{i}.5 Y{-i}.25 F100\n" for i in range(20000)) + "M30\n"
    prog = parse_programs(text)[0]
    assert len(prog.blocks) == 20001
    assert len(prog.blocks._blocks) == 0  # every G1 line (and M30) is an offset into the text
    assert prog.blocks[12345].text == "G1 X12345.5 Y-12345.25 F100" and prog.blocks[12345].line == 12347
    assert prog.blocks.texts(19998, 10) == ["G1 X19998.5 Y-19998.25 F100", "G1 X19999.5 Y-19999.25 F100", "M30"]
