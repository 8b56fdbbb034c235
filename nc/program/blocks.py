"""Lexing and parsing of Delta NC program text into blocks of address words and macro statements.

Comment rules (decisions A7): ``(`` … ``)`` is a comment and code may follow the ``)``; an unclosed
``(`` runs to the end of the line; ``;``, ``//`` and ``%`` start a comment that runs to the end of
the line (``;`` is also the end of block).  ``/`` at the start of a block is block skip (A8).

A word's value is a number, or an expression (``X#1``, ``X-#20``, ``X[#1+2]``, ``G#20``) kept in
``Word.expr`` until the interpreter evaluates the block (`Block.resolved`).  A block carries at
most one macro statement (``Block.stmt``): assignment, GOTO, IF…GOTO / IF…THEN / ELSEIF / ELSE /
ENDIF / IF…EXITW, WHILE…DOm / ENDm / EXITW (nc5) or WHILE / ENDW (lathe-2018).

This module reads a program (`parse_program`, `parse_programs`) into a streamed `BlockList`; one line
is read by nc.program.parser into the forms of nc.program.syntax (`Word`, the statements, `Block`).
"""

from __future__ import annotations

import re
from array import array
from bisect import bisect_left
from itertools import accumulate
from struct import pack
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, overload

# the parser and the parsed forms live in their own modules; their names are read from here too
from nc.program.parser import (MAX_DIGITS, _parse_general, non_ascii_alarm, o_number,  # noqa: F401
                               parse_block, strip_comments)
from nc.program.syntax import (Assign, Block, Else, ElseIf, End, EndIf, ExitW, Goto, IfGoto, IfThen,  # noqa: F401
                               Statement, While, Word)


@dataclass
class Program:
    name: str
    blocks: list[Block]
    number: int | None = None  # O number
    path: str | None = None  # file it came from (program store search order)
    labels: dict[int, list[int]] = field(default_factory=dict)  # N -> block indexes
    # The ProgramStore the program was loaded with (nc.store.ProgramStore.load_main): an interpreter
    # built without a store of its own searches it, so M98/G65 work wherever the program runs.
    store: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.labels and not isinstance(self.blocks, BlockList):  # a BlockList indexes its own
            for i, b in enumerate(self.blocks):
                if b.n is not None:
                    self.labels.setdefault(b.n, []).append(i)


# A plain line that `_plain_block` reads without a doubt (no alarm possible): an optional leading
# N of digits, then one-letter addresses other than N and O, each with a number of at most
# MAX_DIGITS + 3 characters. Such lines are kept as text and read when the interpreter needs them.
# Written for the matcher (issue 17, decision bench B138; the lines it takes are those of session 22's
# `[A-MP-Za-mp-z](?=[-+.0-9]{1,12}(?![.0-9]))[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[ \t]*`, which
# tests/test_parse29_plain_form.py keeps): every repeat possessive (a plain line never needs a step back: a
# number ends where the next letter, blank or the line's end is), and the number's length, which a whole
# match only allows where the number is the whole run of [-+.0-9] after its letter, as "no 13 such
# characters" (a third of `parse_program`'s time on a CAM program went to the matcher's backtracking marks)
_WORD_OK = r"[A-MP-Za-mp-z](?![-+.0-9]{13})[+-]?+(?:[0-9]++\.?+[0-9]*+|\.[0-9]++)[ \t]*+"
_PLAIN_OK = re.compile(r"[ \t]*+(?:[Nn]([0-9]{1,12}+)[ \t]*+)?+(?:" + _WORD_OK + ")*+")
# `_PLAIN_OK` but for a blank line (no N, no word): a line `_parse` keeps as text
_PLAIN_ITEM = re.compile(r"[ \t]*+(?:[Nn]([0-9]{1,12}+)[ \t]*+(?:" + _WORD_OK + ")*+|(?:" + _WORD_OK + ")++)")
# a run of `_PLAIN_ITEM` lines without N, each ended by its line break (or the text's end): what `_parse` reads of a
# chunk without N in one call (a line `_PLAIN_ITEM` takes is one this takes: the same words, no "\n" in one)
_PLAIN_RUN = re.compile(r"(?:[ \t]*+(?:" + _WORD_OK + r")++(?:\n|\Z))*+")
_CHUNK = 1 << 16  # characters of program text `_parse` reads at a time
_CACHE_LIMIT = 4096  # parsed plain lines kept (loops and GOTO come back to them); then the cache starts over


class BlockList(Sequence):
    """A program's blocks, streamed (issue 16): a plain line (`_PLAIN_OK`) is kept as where it stands
    in the program text (offset and length, no object per line) and parsed when the interpreter
    reaches it; every other block is parsed (and checked) when the program is read. Memory is the
    text plus some 20 bytes a line however long the program; a bulk reader (nc.interp.bulk) takes
    runs of the text without making blocks at all."""

    __slots__ = ("_text", "_starts", "_lengths", "_lines", "_blocks", "_parsed", "_cache", "_by_text")

    def __init__(self, text: str = "") -> None:
        self._text = text  # the program text the plain lines are slices of
        self._starts = array("q")  # offset of each item's line in _text (-1: a block parsed when read)
        self._lengths = array("I")
        self._lines = array("l")  # file line of each item
        self._blocks: dict[int, Block] = {}  # items parsed when the program was read
        self._parsed = array("l")  # their indexes, ascending
        self._cache: dict[int, Block] = {}
        self._by_text: dict[str, Block] = {}  # a line's text -> the block it read as (a line written again)

    def _add(self, item: Block, line: int) -> None:
        self._blocks[len(self._lines)] = item
        self._parsed.append(len(self._lines))
        self._starts.append(-1)
        self._lengths.append(0)
        self._lines.append(line)

    def _add_text(self, start: int, end: int, line: int) -> None:
        self._starts.append(start)
        self._lengths.append(end - start)
        self._lines.append(line)

    def __len__(self) -> int:
        return len(self._lines)

    @overload
    def __getitem__(self, i: int) -> Block: ...
    @overload
    def __getitem__(self, i: slice) -> list[Block]: ...

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self._lines)))]
        start = self._starts[i]  # IndexError as a list gives it
        if i < 0:
            i += len(self._lines)
        if start < 0:
            return self._blocks[i]
        block = self._cache.get(i)
        if block is None:
            if len(self._cache) >= _CACHE_LIMIT:
                self._cache.clear()
                self._by_text.clear()
            text = self._text[start:start + self._lengths[i]]
            seen = self._by_text.get(text)
            if seen is None:
                block = self._by_text[text] = parse_block(self._lines[i], text)
            else:  # the same text reads the same (issue 16: a repeated part): its words, its own line
                block = Block(self._lines[i], seen.text, list(seen.words), seen.n, seen.skip, dict(seen.comma),
                              seen.comment, seen.stmt, seen.comma_expr)
            self._cache[i] = block
        return block

    def __iter__(self) -> Iterator[Block]:
        for i in range(len(self._lines)):
            yield self[i]

    @property
    def parsed(self) -> Callable[[int], Block | None]:
        """The lookup (one dict call: the program counter asks it for every block) of the items parsed
        when the program was read, by index: None for a plain line still held as text."""
        return self._blocks.get

    def plain_at(self, i: int) -> bool:
        """Whether item i is a plain line not yet parsed (what `raw` returns the text of)."""
        return self._starts[i] >= 0

    def raw(self, i: int) -> str | None:
        """The text of a plain line not yet parsed (`_PLAIN_OK`), else None."""
        start = self._starts[i]
        return None if start < 0 else self._text[start:start + self._lengths[i]]

    def text_index(self) -> tuple[str, array, array, array]:
        """The program text and, by item, each plain line's offset in it (-1: a block parsed when read),
        its length and its file line: `raw` and `line` for a reader that asks for every line (the program
        counter's lean lane, issue 17) without a method call per line. Fixed once the program is read."""
        return self._text, self._starts, self._lengths, self._lines

    def line(self, i: int) -> int:
        return self._lines[i]

    def lines(self, i: int, count: int) -> list[int]:
        """File lines of items i … i + count - 1."""
        return self._lines[i:i + count].tolist()

    def texts(self, i: int, most: int) -> list[str]:
        """The texts of the unparsed plain lines from `i` on (at most `most`), up to the first block."""
        parsed = self._parsed
        k = bisect_left(parsed, i)
        stop = min(i + most, len(self._lines), parsed[k] if k < len(parsed) else len(self._lines))
        text = self._text
        return [text[s:s + n] for s, n in zip(self._starts[i:stop], self._lengths[i:stop])]


_O_LINE = re.compile(r"\s*[Oo]([0-9]+)")


def parse_program(text: str, name: str = "program", number: int | None = None, *, start: int = 0,
                  stop: int | None = None, line0: int = 0) -> Program:
    """Parse one program (one O number): the lines of `text[start:stop]`, the first numbered
    `line0` + 1.  The first line starting with ``O`` is its description (N ch.2).  Raises NcAlarm
    (with line and block) on the first malformed block."""
    return _parse(_one_line_break(text), name, number, start, stop, line0)


def _parse(text: str, name: str, number: int | None, start: int, stop: int | None, line0: int) -> Program:
    """`parse_program` of a text whose only line break is "\n". Read a chunk of lines at a time (issue 17): the
    lines of a chunk are split, measured and matched against `_PLAIN_ITEM` in C (`str.split`, `map`), and only
    the lines that are not plain motion text (a block to parse, a blank line, an N to index) are looked at one
    by one, in order; a run of plain lines between them is added to the BlockList at once. The items, their
    lines and labels, and the first alarm are those of reading line by line; memory stays a chunk's lines."""
    blocks = BlockList(text)
    starts, lengths, n_items = blocks._starts, blocks._lengths, blocks._lines
    labels: dict[int, list[int]] = {}
    plain_ok = _PLAIN_ITEM.fullmatch
    plain_run = _PLAIN_RUN.match
    stop = len(text) if stop is None else stop
    idx, pos = line0, start
    while pos < stop:  # a chunk at a time, not a list of all lines (a 1M-block program, issue 16)
        cut = stop if pos + _CHUNK >= stop else text.rfind("\n", pos, pos + _CHUNK) + 1
        if cut <= pos:  # a line longer than a chunk: up to its end
            cut = text.find("\n", pos + _CHUNK, stop) + 1 or stop
        chunk = text[pos:cut]
        lines = chunk.split("\n")
        if not lines[-1]:
            lines.pop()  # the chunk's last line break ends its last line (no empty line after it)
        sizes = list(map(len, lines))
        offsets = list(accumulate([size + 1 for size in sizes], initial=pos))
        # the lines to look at one by one: not plain items (None), and plain ones with an N (a label)
        found: list | None = None
        if "N" in chunk or "n" in chunk:
            found = list(map(plain_ok, lines))
            odd = [i for i, m in enumerate(found) if m is None or m.lastindex]
        else:  # no label: a run of plain lines is matched in one call (`_PLAIN_RUN`: no match object per line,
            # issue 17), ending at the start of the next line that is not plain
            odd = []
            k, p, size, last = 0, 0, len(chunk), len(lines)
            while k < last:
                e = plain_run(chunk, p).end()
                k += chunk.count("\n", p, e)
                if e >= size:
                    break
                odd.append(k)
                k += 1
                if k < last:
                    p = offsets[k] - pos
        done = 0  # lines of the chunk added or skipped
        for i in odd + [len(lines)]:
            if i > done:  # plain lines: kept as text, no block object per line; the run's numbers packed at
                # once (an array's `extend` converts item by item, a fifth of the time of reading a CAM program)
                n = i - done
                starts.frombytes(pack(f"{n}q", *offsets[done:i]))
                lengths.frombytes(pack(f"{n}I", *sizes[done:i]))
                n_items.frombytes(pack(f"{n}l", *range(idx + done + 1, idx + i + 1)))
            if i == len(lines):
                break
            done = i + 1
            m = None if found is None else found[i]
            if m is not None:  # a plain line with N: kept as text, indexed by its N
                labels.setdefault(int(m.group(1)), []).append(len(n_items))
                starts.append(offsets[i])
                lengths.append(sizes[i])
                n_items.append(idx + i + 1)
                continue
            raw = lines[i]
            stripped = raw.strip()
            if not stripped:
                continue
            o = _O_LINE.match(stripped)
            if o and not blocks and number is None:
                number = o_number(o.group(1), idx + i + 1, raw)
                continue
            if o and not blocks:
                continue
            block = parse_block(idx + i + 1, raw)
            if block.words or block.n is not None or block.comma or block.stmt is not None or block.comma_expr:
                if block.n is not None:
                    labels.setdefault(block.n, []).append(len(blocks))
                blocks._add(block, idx + i + 1)
        idx += len(lines)
        pos = cut
    return Program(name=name, blocks=blocks, number=number, labels=labels)


# Line breaks str.splitlines knows besides "\n"; a text holding one is rewritten with "\n" alone
_OTHER_BREAKS = re.compile("[\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]")


def _one_line_break(text: str) -> str:
    """`text` with its lines (as str.splitlines reads them) joined by "\n" alone: line numbers
    stay; the common file (only "\n") is returned as it is, not copied."""
    if text.isascii():  # known without a look at the text; then a search for each ASCII break (C's memchr)
        if not ("\r" in text or "\x0b" in text or "\x0c" in text or "\x1c" in text or "\x1d" in text
                or "\x1e" in text):
            return text
    elif _OTHER_BREAKS.search(text) is None:
        return text
    return "\n".join(text.splitlines())


_O_START = re.compile(r"^[^\S\n]*[Oo]([0-9]+)", re.M)  # a line starting with O<n> (`_O_LINE` per line)


def parse_programs(text: str, name: str = "program") -> list[Program]:
    """A file holding several O programs: each line starting with ``O<n>`` (outside a comment)
    begins a new program.  Text before the first O line (if any code) is an unnamed program.
    The programs are parsed in place in the file's text (no copy of it, no list of its lines)."""
    text = _one_line_break(text)
    starts: list[tuple[int, int, int]] = []  # (offset, index of its line, O number)
    line, last = 0, 0
    for m in _O_START.finditer(text):
        line += text.count("\n", last, m.start())
        last = m.start()
        eol = text.find("\n", last)
        starts.append((last, line, o_number(m.group(1), line + 1, text[last:eol if eol >= 0 else len(text)])))
    out: list[Program] = []
    first = starts[0][0] if starts else len(text)
    if not starts or strip_comments(text[:first].replace("\n", " "))[0].strip():
        prog = _parse(text, name, None, 0, first, 0)
        prog.number = None
        out.append(prog)
    for k, (off, line, num) in enumerate(starts):
        end = starts[k + 1][0] if k + 1 < len(starts) else len(text)
        prog = _parse(text, f"O{num:04d}" if len(starts) > 1 or out else name, None, off, end, line)
        prog.number = num
        out.append(prog)
    return out
