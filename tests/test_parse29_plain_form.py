"""B138 (issue 17): `parse_program` finds the plain lines it keeps as text with patterns written for the matcher
(possessive repeats, the number's length as "no 13 number characters") and looks for line breaks other than
"\\n" in an ASCII text by a search per break character. The lines it keeps as plain, and the N it indexes, are
those of session 22's patterns (kept here as the reference), over every short line of the characters that
matter and over random lines of long numbers; every line break str.splitlines knows still ends a line."""

from __future__ import annotations

import itertools
import random
import re

import pytest

from nc.program.blocks import _PLAIN_ITEM, _PLAIN_OK, parse_program

# session 22's forms (nc/program/blocks.py before B138)
_WORD_22 = r"[A-MP-Za-mp-z](?=[-+.0-9]{1,12}(?![.0-9]))[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[ \t]*"
_PLAIN_OK_22 = re.compile(r"[ \t]*(?:[Nn]([0-9]{1,12})[ \t]*)?(?:" + _WORD_22 + ")*")
_PLAIN_ITEM_22 = re.compile(r"[ \t]*(?:[Nn]([0-9]{1,12})[ \t]*(?:" + _WORD_22 + ")*|(?:" + _WORD_22 + ")+)")

PAIRS = [(_PLAIN_OK_22.fullmatch, _PLAIN_OK.fullmatch), (_PLAIN_ITEM_22.fullmatch, _PLAIN_ITEM.fullmatch)]
PARTS = ["X", "Y", "N", "n", "O", "G", "1", "0", "9", ".", "-", "+", " ", "\t", "12", "0.5", "123456789012",
         "1234567890123", "-12345678901", "-123456789012", "1.234567890", ".12345678901", ".123456789012", "1.",
         "#", "=", "z", "N123456789012", "N1234567890123", "X0.0177 Y0.0089"]


def _read(match, line: str) -> tuple | None:
    m = match(line)
    return None if m is None else (m.lastindex, m.group(1))


def _check(lines) -> int:
    n = 0
    for line in lines:
        for old, new in PAIRS:
            assert _read(new, line) == _read(old, line), repr(line)
        n += 1
    return n


def test_every_short_line_is_plain_as_before() -> None:
    # letters (N, O and one other), blank, tab, signs, a digit, a point and two characters a plain line never holds
    alphabet = "XNO +-.0\t#"
    assert _check("".join(t) for k in range(6) for t in itertools.product(alphabet, repeat=k)) == 111111


def test_lines_of_long_numbers_are_plain_as_before() -> None:
    rng = random.Random(29)
    lines = ["".join(rng.choice(PARTS) for _ in range(rng.randint(1, 8))) for _ in range(40_000)]
    assert _check(lines) == 40_000
    # the 12-character limit (MAX_DIGITS + 3) on both sides of it, a plain line and a refused one
    assert _PLAIN_ITEM.fullmatch("X-12345678.90 Y1") and not _PLAIN_ITEM.fullmatch("X-123456789.01 Y1")
    assert _PLAIN_ITEM.fullmatch("N123456789012 X1.") and not _PLAIN_ITEM.fullmatch("N1234567890123 X1.")


@pytest.mark.parametrize("brk", ["\r\n", "\r", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029"])
@pytest.mark.parametrize("other", ["", " (é)"])  # an ASCII text, and one that is not
def test_every_line_break_ends_a_line(brk: str, other: str) -> None:
    text = f"G1 X1. F100{other}{brk}X2.{brk}{brk}Y3.\nM30\n"
    blocks = parse_program(text).blocks
    assert [(b.line, b.text) for b in blocks] == [(1, f"G1 X1. F100{other}"), (2, "X2."), (4, "Y3."), (5, "M30")]
