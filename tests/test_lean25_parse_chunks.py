"""B122 (issue 17): `parse_program` reads a chunk of lines at a time (split, measured and matched in C, only the
lines that are not plain motion text looked at one by one). It gives the BlockList, labels, O number and first
alarm that reading line by line gave: the reading it replaced is kept here as the reference, and both read
random texts (plain lines with and without N, blank lines, O lines, comments, statements, malformed lines, no
final line break, lines longer than a chunk) with chunks as small as a few characters."""

from __future__ import annotations

from unittest.mock import patch

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import nc.program.blocks as blocks_mod
from nc.alarms import NcAlarm
from nc.program.blocks import BlockList, Program, _PLAIN_OK, _O_LINE, o_number, parse_block, parse_program


def reference(text: str, name: str = "p.nc") -> Program:
    """The line-by-line reading of session 23 (nc/program/blocks.py `_parse`)."""
    blocks = BlockList(text)
    labels: dict[int, list[int]] = {}
    number = None
    idx, pos, stop = 0, 0, len(text)
    while pos < stop:
        end = text.find("\n", pos, stop)
        if end < 0:
            end = stop
        idx += 1
        m = _PLAIN_OK.fullmatch(text, pos, end)
        if m is not None and end > pos:
            if m.group(1) is not None:
                labels.setdefault(int(m.group(1)), []).append(len(blocks._lines))
            elif text[pos:end].isspace():
                pos = end + 1
                continue
            blocks._add_text(pos, end, idx)
            pos = end + 1
            continue
        raw = text[pos:end]
        pos = end + 1
        stripped = raw.strip()
        if not stripped:
            continue
        o = _O_LINE.match(stripped)
        if o and not blocks and number is None:
            number = o_number(o.group(1), idx, raw)
            continue
        if o and not blocks:
            continue
        block = parse_block(idx, raw)
        if block.words or block.n is not None or block.comma or block.stmt is not None or block.comma_expr:
            if block.n is not None:
                labels.setdefault(block.n, []).append(len(blocks))
            blocks._add(block, idx)
    return Program(name=name, blocks=blocks, number=number, labels=labels)


def _read(parse, text: str) -> tuple:
    try:
        prog = parse(text)
    except NcAlarm as exc:
        return ("alarm", repr(exc.alarm))
    bl = prog.blocks
    items = [(bl.line(i), bl.raw(i), repr(bl[i])) for i in range(len(bl))]
    return prog.number, prog.labels, items, list(bl._starts), list(bl._lengths), list(bl._parsed)


LINES = st.sampled_from([
    "X1.5 Y2.25", "x1 y-2.", "N10 X1.", "n20", "N30", "G1 X1. F1200", "  G0 Z5.", "\tX.5", "", " ", "\t \t",
    "O1234", "O0001 (main)", "(a comment)", "G1 X1. (why)", "#1 = 2", "IF [#1 GT 1] GOTO 10", "M30", "X1.5Y2",
    "X123456789012345.", "X1-2", "G1 X#1", "/X1.", "G1 X1. ,C0.5", "; just a comment", "% start", "X",
    "N1 G90 G54", "X1.e5", "N7 X1. Y2. Z3.", "Y" + "1" * 11, "Z" + "9" * 13,
])


@settings(max_examples=300, deadline=None)
@given(lines=st.lists(LINES, max_size=30), final=st.booleans(), chunk=st.integers(1, 64))
def test_chunked_reading_gives_what_line_by_line_gave(lines: list[str], final: bool, chunk: int) -> None:
    text = "\n".join(lines) + ("\n" if final and lines else "")
    with patch.object(blocks_mod, "_CHUNK", chunk):
        got = _read(lambda t: parse_program(t, "p.nc"), text)
    assert got == _read(reference, text)


def test_a_long_program_across_many_chunks_and_a_line_longer_than_a_chunk(monkeypatch: pytest.MonkeyPatch) -> None:
    text = "O0042\n" + "\n".join(f"X{i * 0.01:.4f} Y{-i * 0.02:.4f}" + (f"\nN{i}" if i % 97 == 0 else "")
                                  for i in range(3000)) + "\nG1 X1. (" + "long comment " * 40 + ")\nM30"
    monkeypatch.setattr(blocks_mod, "_CHUNK", 100)
    got = _read(lambda t: parse_program(t, "p.nc"), text)
    assert got == _read(reference, text)
    assert got[0] == 42 and len(got[2]) == 3000 + 31 + 2 and got[1][97] == [99]  # N0 … N2910; N97 after 98 X lines


def test_the_first_malformed_line_raises_as_before() -> None:
    text = "X1.\nX2.\nG1 X1. Q\nX3.\nG1 Y1. Q\n"
    with pytest.raises(NcAlarm) as exc:
        parse_program(text, "p.nc")
    assert (exc.value.alarm.line, exc.value.alarm.block) == (3, "G1 X1. Q")


@settings(max_examples=300, deadline=None)
@given(lines=st.lists(LINES.filter(lambda s: "N" not in s and "n" not in s), max_size=40), final=st.booleans(),
       chunk=st.sampled_from([8, 17, 64, 1 << 16]))
def test_chunks_without_n_read_by_runs_give_what_line_by_line_gave(lines: list[str], final: bool, chunk: int) -> None:
    """A chunk without N is read a run of plain lines at a time (`_PLAIN_RUN`, bench B167): blank, non-plain and
    too-long-number lines anywhere in it, a last line with or without its line break."""
    text = "\n".join(lines) + ("\n" if final and lines else "")
    with patch.object(blocks_mod, "_CHUNK", chunk):
        got = _read(lambda t: parse_program(t, "p.nc"), text)
    assert got == _read(reference, text)
