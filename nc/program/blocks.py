"""Lexing and parsing of Delta NC program text into blocks of address words and macro statements.

Comment rules (decisions A7): ``(`` … ``)`` is a comment and code may follow the ``)``; an unclosed
``(`` runs to the end of the line; ``;``, ``//`` and ``%`` start a comment that runs to the end of
the line (``;`` is also the end of block).  ``/`` at the start of a block is block skip (A8).

A word's value is a number, or an expression (``X#1``, ``X-#20``, ``X[#1+2]``, ``G#20``) kept in
``Word.expr`` until the interpreter evaluates the block (`Block.resolved`).  A block carries at
most one macro statement (``Block.stmt``): assignment, GOTO, IF…GOTO / IF…THEN / ELSEIF / ELSE /
ENDIF / IF…EXITW, WHILE…DOm / ENDm / EXITW (nc5) or WHILE / ENDW (lathe-2018).
"""

from __future__ import annotations

import re
import unicodedata
from array import array
from bisect import bisect_left
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Union, overload

from nc.alarms import NcAlarm
from nc.program.expr import Expr, ExprParser, Num, Var


@dataclass(slots=True)
class Word:
    letter: str  # address, upper case ("X", "G", or a multi-letter axis name such as "XA1")
    value: float
    text: str  # as written, for alarms
    has_point: bool  # the number carried a decimal point (expressions count as having one)
    expr: Expr | None = None  # unevaluated value (macro expression)


# ---- statements -------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Assign:
    target: Var
    value: Expr


@dataclass(frozen=True, slots=True)
class Goto:
    target: Expr


@dataclass(frozen=True, slots=True)
class IfGoto:
    cond: Expr
    target: Expr


@dataclass(frozen=True, slots=True)
class IfThen:
    cond: Expr


@dataclass(frozen=True, slots=True)
class ElseIf:
    cond: Expr


@dataclass(frozen=True, slots=True)
class Else:
    pass


@dataclass(frozen=True, slots=True)
class EndIf:
    pass


@dataclass(frozen=True, slots=True)
class ExitW:
    cond: Expr | None = None  # IF[..]EXITW


@dataclass(frozen=True, slots=True)
class While:
    cond: Expr
    do: int | None  # None: lathe-2018 WHILE … ENDW


@dataclass(frozen=True, slots=True)
class End:
    do: int | None  # None: ENDW


Statement = Union[Assign, Goto, IfGoto, IfThen, ElseIf, Else, EndIf, ExitW, While, End]


@dataclass(slots=True)
class Block:
    line: int  # 1-based line number in the file
    text: str  # the source line without its line break
    words: list[Word] = field(default_factory=list)
    n: int | None = None  # sequence number
    skip: bool = False  # starts with '/'
    comma: dict[str, float] = field(default_factory=dict)  # ,C ,R ,A
    comment: str = ""
    stmt: Statement | None = None
    comma_expr: dict[str, Expr] = field(default_factory=dict)

    def get(self, letter: str) -> Word | None:
        """The last word with this address (repeated axis words: last wins, decisions A9)."""
        for w in reversed(self.words):
            if w.letter == letter:
                return w
        return None

    def all(self, letter: str) -> list[Word]:
        return [w for w in self.words if w.letter == letter]

    def has(self, letter: str) -> bool:
        for w in self.words:  # a plain loop: this runs several times per block (hot path)
            if w.letter == letter:
                return True
        return False

    @property
    def has_expr(self) -> bool:
        for w in self.words:
            if w.expr is not None:
                return True
        return bool(self.comma_expr)

    def copy(self) -> "Block":
        # the constructor, not dataclasses.replace (which inspects the fields on every call): every
        # block with an expression is copied when it runs
        return Block(self.line, self.text, list(self.words), self.n, self.skip, dict(self.comma), self.comment,
                     self.stmt, self.comma_expr)


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


_NUMBER = re.compile(r"[+-]?\s*([0-9]+\.?[0-9]*|\.[0-9]+)")
_KEYWORDS = ("ELSEIF", "ENDIF", "EXITW", "WHILE", "GOTO", "THEN", "ELSE", "ENDW", "END", "IF", "DO")
MAX_DIGITS = 9
_COMMENT_START = re.compile(r"[(;%/]")  # a line without these has no comment and no block skip
_NOT_DIGIT = re.compile(r"[^0-9]")
_LETTERS = re.compile(r"[A-Za-z]+")
_AXIS_NAME = re.compile(r"[A-Za-z]{1,2}[0-9]{0,2}\s*=")
_AXIS_SUFFIX = re.compile(r"[0-9]{1,2}\s*=")
_SPACE_EQ = re.compile(r"[\s=]")
# Fast path (`_plain_block`): a block made only of one-letter addresses each followed directly by a
# plain number ("G01 X12.5 Y-3", the bulk of CAM output).  ASCII digits and blanks only, so every
# such block reads exactly as the general parser would read it; anything else takes the general path.
_PLAIN_BLOCK = re.compile(r"[ \t]*(?:[A-Za-z][+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[ \t]*)+")
_PLAIN_WORD = re.compile(r"([A-Za-z])([+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+))")
# A plain line that `_plain_block` reads without a doubt (no alarm possible): an optional leading
# N of digits, then one-letter addresses other than N and O, each with a number of at most
# MAX_DIGITS + 3 characters. Such lines are kept as text and read when the interpreter needs them.
_WORD_OK = r"[A-MP-Za-mp-z](?=[-+.0-9]{1,12}(?![.0-9]))[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[ \t]*"
_PLAIN_OK = re.compile(r"[ \t]*(?:[Nn]([0-9]{1,12})[ \t]*)?(?:" + _WORD_OK + ")*")
_CACHE_LIMIT = 4096  # parsed plain lines kept (loops and GOTO come back to them); then the cache starts over


class BlockList(Sequence):
    """A program's blocks, streamed (issue 16): a plain line (`_PLAIN_OK`) is kept as where it stands
    in the program text (offset and length, no object per line) and parsed when the interpreter
    reaches it; every other block is parsed (and checked) when the program is read. Memory is the
    text plus some 20 bytes a line however long the program; a bulk reader (nc.interp.bulk) takes
    runs of the text without making blocks at all."""

    __slots__ = ("_text", "_starts", "_lengths", "_lines", "_blocks", "_parsed", "_cache")

    def __init__(self, text: str = "") -> None:
        self._text = text  # the program text the plain lines are slices of
        self._starts = array("q")  # offset of each item's line in _text (-1: a block parsed when read)
        self._lengths = array("I")
        self._lines = array("l")  # file line of each item
        self._blocks: dict[int, Block] = {}  # items parsed when the program was read
        self._parsed = array("l")  # their indexes, ascending
        self._cache: dict[int, Block] = {}

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
            block = self._cache[i] = parse_block(self._lines[i], self._text[start:start + self._lengths[i]])
        return block

    def __iter__(self) -> Iterator[Block]:
        for i in range(len(self._lines)):
            yield self[i]

    def plain_at(self, i: int) -> bool:
        """Whether item i is a plain line not yet parsed (what `raw` returns the text of)."""
        return self._starts[i] >= 0

    def raw(self, i: int) -> str | None:
        """The text of a plain line not yet parsed (`_PLAIN_OK`), else None."""
        start = self._starts[i]
        return None if start < 0 else self._text[start:start + self._lengths[i]]

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


def strip_comments(text: str) -> tuple[str, str]:
    """Return (code, comment) for one line."""
    if _COMMENT_START.search(text) is None:
        return text, ""
    out: list[str] = []
    comment: list[str] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "(":
            j = text.find(")", i + 1)
            if j < 0:
                comment.append(text[i + 1:])
                break
            comment.append(text[i + 1:j])
            i = j + 1
            continue
        if c in ";%" or text.startswith("//", i):
            comment.append(text[i + (2 if c == "/" else 1):])
            break
        out.append(c)
        i += 1
    return "".join(out), " ".join(s.strip() for s in comment if s.strip())


class _BlockParser:
    def __init__(self, line: int, text: str, code: str) -> None:
        self.line, self.text = line, text
        self.p = ExprParser(code)

    @property
    def s(self) -> str:
        return self.p.s

    def alarm(self, code: int, msg: str) -> NcAlarm:
        return NcAlarm(code, msg, line=self.line, block=self.text)

    def at_end(self) -> bool:
        self.p.skip()
        return self.p.pos >= len(self.s)

    def keyword(self) -> str:
        w = self.p.peek_word()
        return w if w in _KEYWORDS else ""

    def take(self, kw: str) -> None:
        self.p.skip()
        self.p.pos += len(kw)

    def cond(self) -> Expr:
        self.p.skip()
        if not self.s.startswith("[", self.p.pos):
            raise self.alarm(0x020E, "IF/WHILE needs a [condition]")
        self.p.pos += 1
        old = self.p.eq_is_compare
        self.p.eq_is_compare = True
        e = self.p.parse()
        self.p.eq_is_compare = old
        self.p.expect("]")
        return e

    def int_value(self, what: str) -> Expr:
        self.p.skip()
        if self.at_end():
            raise self.alarm(0x0225 if what == "END" else 0x0226 if what == "DO" else 0x0224,
                             f"no value after {what}")
        return self.p.primary() if self.s[self.p.pos] in "#[" else self._number_expr()

    def _number_expr(self) -> Expr:
        m = _NUMBER.match(self.s, self.p.pos)
        if not m:
            raise self.alarm(0x0222, f"no value at {self.s[self.p.pos:]!r}")
        self.p.pos = m.end()
        return Num(float(m.group(0).replace(" ", "")))

    def statement(self, kw: str, first: bool) -> Statement:
        if not first and kw in ("IF", "WHILE"):
            raise self.alarm(0x0203, f"{kw} must be at the beginning of the block")
        if first and kw in ("DO", "THEN"):
            raise self.alarm(0x0204, f"{kw} cannot start a block")
        self.take(kw)
        if kw == "GOTO":
            return Goto(self.int_value("GOTO"))
        if kw == "IF":
            c = self.cond()
            nxt = self.keyword()
            if nxt == "GOTO":
                self.take("GOTO")
                return IfGoto(c, self.int_value("GOTO"))
            if nxt == "THEN":
                self.take("THEN")
                return IfThen(c)
            if nxt == "EXITW":
                self.take("EXITW")
                return ExitW(c)
            raise self.alarm(0x0238, "IF must be followed by GOTO, THEN or EXITW")
        if kw == "ELSEIF":
            c = self.cond()
            if self.keyword() != "THEN":
                raise self.alarm(0x023A, "ELSEIF [..] needs THEN")
            self.take("THEN")
            return ElseIf(c)
        if kw == "ELSE":
            return Else()
        if kw == "ENDIF":
            return EndIf()
        if kw == "EXITW":
            return ExitW()
        if kw == "WHILE":
            self.p.skip()
            if not self.s.startswith("[", self.p.pos):
                raise self.alarm(0x020F, "WHILE needs a [condition]")
            c = self.cond()
            if self.keyword() == "DO":
                self.take("DO")
                return While(c, self._loop_id("DO", 0x0226))
            return While(c, None)
        if kw == "ENDW":
            return End(None)
        if kw == "END":
            return End(self._loop_id("END", 0x0225))
        raise self.alarm(0x0239 if kw == "THEN" else 0x0207, f"{kw} out of place")

    def _loop_id(self, what: str, code: int) -> int:
        self.p.skip()
        m = _NUMBER.match(self.s, self.p.pos)
        if not m:
            raise self.alarm(code, f"no value after {what}")
        self.p.pos = m.end()
        v = float(m.group(0).replace(" ", ""))
        if v != int(v):
            raise self.alarm(0x0214, f"{what} number must be an integer")
        return int(v)

    def word_value(self, letter: str) -> tuple[float, str, bool, Expr | None]:
        p = self.p
        p.skip()
        start = p.pos
        if p.pos < len(self.s) and self.s[p.pos] == "=":
            p.pos += 1
            p.skip()
        neg = False
        if p.pos < len(self.s) and self.s[p.pos] in "+-":
            j = p.pos + 1
            while j < len(self.s) and self.s[j].isspace():
                j += 1
            if j < len(self.s) and self.s[j] in "#[":
                neg = self.s[p.pos] == "-"
                p.pos = j
        if p.pos < len(self.s) and self.s[p.pos] in "#[":
            e = p.primary()
            if neg:
                from nc.program.expr import Unary
                e = Unary("-", e)
            return 0.0, letter + self.s[start:p.pos], True, e
        m = _NUMBER.match(self.s, p.pos)
        if not m:
            raise self.alarm(0x0222, f"address {letter} has no value")
        raw = m.group(0).replace(" ", "")
        digits = len(_NOT_DIGIT.sub("", raw).lstrip("0"))
        if digits > MAX_DIGITS + 3:
            raise self.alarm(0x0223, f"{letter}{raw} has too many digits")
        p.pos = m.end()
        return float(raw), letter + raw, "." in raw, None

    def parse(self, block: Block) -> None:
        p = self.p
        first = True
        while not self.at_end():
            c = self.s[p.pos]
            if c == "#":
                if not first:
                    raise self.alarm(0x0208, "an assignment and other words cannot share a block")
                target = p.variable()
                p.skip()
                judge = next((op for op in ("==", "<>", ">=", "<=", ">", "<") if self.s.startswith(op, p.pos)), None)
                if judge is not None:  # App. A 0x020D wrong example '#1>G01': a judgement is no statement
                    raise self.alarm(0x020D, f"judgement operator {judge!r} where an assignment '=' belongs")
                if not self.s.startswith("=", p.pos):
                    raise self.alarm(0x0211, "# variable without '=' (assignment expected)")
                p.pos += 1
                if self.at_end():
                    raise self.alarm(0x0211, "nothing after '='")
                value = p.parse()
                if not self.at_end():
                    raise self.alarm(0x0208, f"unexpected {self.s[p.pos:]!r} after the assignment")
                block.stmt = Assign(target, value)
                return
            if c == ",":
                p.pos += 1
                p.skip()
                if self.at_end() or self.s[p.pos].upper() not in "CRA":
                    raise self.alarm(0x0207, f"',' must be followed by C, R or A")
                letter = self.s[p.pos].upper()
                p.pos += 1
                v, _, _, e = self.word_value(letter)
                if e is not None:
                    block.comma_expr[letter] = e
                else:
                    block.comma[letter] = v
                first = False
                continue
            if not (c.isascii() and c.isalpha()):  # Ά, é are no addresses
                raise self.alarm(0x0209 if c in "[]" else 0x0206,
                                 f"unexpected character {c!r}")
            kw = self.keyword()
            if kw:
                if block.stmt is not None or (kw in ("IF", "WHILE") and block.words):
                    code = 0x0203 if kw in ("IF", "WHILE") else 0x0239 if kw == "THEN" else 0x0207
                    raise self.alarm(code, f"{kw} out of place" + (" (THEN follows only IF [..] or ELSEIF [..])"
                                                                   if kw == "THEN" else ""))
                block.stmt = self.statement(kw, first)
                if kw in ("END", "ENDW", "ENDIF", "ELSE", "EXITW") or isinstance(block.stmt, (IfThen, ElseIf)):
                    if not self.at_end():
                        raise self.alarm(0x0205, f"{kw} must be at the end of the block")
                first = False
                continue
            if block.stmt is not None and not isinstance(block.stmt, (Goto, IfGoto)):
                raise self.alarm(0x0208, "statement and NC words in one block")
            m = _LETTERS.match(self.s, p.pos)
            run = m.group(0).upper()
            if len(run) > 1:
                # a multi-character axis name must be followed by '=' (XA1=100., N§3.1.1)
                m2 = _AXIS_NAME.match(self.s, p.pos)
                if not m2:
                    raise self.alarm(0x0201, f"undefined operator {run!r}")
                name = _SPACE_EQ.sub("", m2.group(0)).upper()
                p.pos = m2.end() - 1
                letter = name
            else:
                letter = run
                p.pos += 1
                m2 = _AXIS_SUFFIX.match(self.s, p.pos)
                if m2 and letter in "XYZUVWABC":
                    letter += _SPACE_EQ.sub("", m2.group(0))
                    p.pos = m2.end() - 1
            value, text, point, e = self.word_value(letter)
            if letter == "N" and first and block.n is None and e is None:
                if point or value != int(value) or value < 0:
                    raise self.alarm(0x0207, f"sequence number {text} must be a whole number")
                block.n = int(value)
                continue
            if letter == "O":
                raise self.alarm(0x0201, "O is only allowed at the start of a program")
            block.words.append(Word(letter, value, text, point, e))
            first = False


def _plain_block(line: int, text: str, code: str) -> Block | None:
    """The general parser's result for a `_PLAIN_BLOCK` line, without its character scanner;
    None when the line needs the general path (an O word, a bad N, too many digits), which then
    raises the alarm."""
    block = Block(line=line, text=text)
    words = block.words
    first = True
    for letter, raw in _PLAIN_WORD.findall(code):
        if len(raw) > MAX_DIGITS + 3:
            return None  # may have too many digits (0x0223)
        letter = letter.upper()
        value = float(raw)
        point = "." in raw
        if letter == "N" and first and block.n is None:
            if point or value != int(value) or value < 0:
                return None
            block.n = int(value)
            continue
        if letter == "O":
            return None
        words.append(Word(letter, value, letter + raw, point))
        first = False
    return block


def parse_block(line: int, text: str) -> Block:
    if _PLAIN_BLOCK.fullmatch(text) is not None:  # no comment, no line break: text is the code
        block = _plain_block(line, text, text)
        if block is not None:
            return block
    return _parse_general(line, text)


def _parse_general(line: int, text: str) -> Block:
    code, comment = strip_comments(text)
    block = Block(line=line, text=text.rstrip("\r\n"), comment=comment)
    if not code.isascii():
        raise non_ascii_alarm(code, line, block.text)
    s = code.strip()
    if s.startswith("/"):
        block.skip = True
        s = s[1:]
    try:
        _BlockParser(line, text.rstrip("\r\n"), s).parse(block)
    except NcAlarm as exc:
        raise exc.at(line, block.text) from None
    return block


def non_ascii_alarm(code: str, line: int | None, block: str | None) -> NcAlarm:
    """The alarm for the first non-ASCII character outside a comment (decisions P1): NC words take
    ASCII only, so `X١٠.` (Arabic-Indic) or `X１０.` (fullwidth) is never read as X10.  A digit is
    0x020A (wrong command characters), any other character 0x0206 as before (Ά, é: language.md)."""
    c = next(ch for ch in code if not ch.isascii())
    digit = c.isdigit() or unicodedata.category(c) == "Nd"
    kind = "digit" if digit else "character"
    name = unicodedata.name(c, f"U+{ord(c):04X}")
    return NcAlarm(0x020A if digit else 0x0206, f"non-ASCII {kind} {c!r} ({name}): NC words take ASCII letters, digits 0-9 "
                           "and signs only", line=line, block=block)


def o_number(digits: str, line: int | None, block: str | None) -> int:
    """The number of an ``O`` line; more than MAX_DIGITS significant digits is 0x0223 (the NC5
    names O0001-O9999 and O50000/O60000, a file name cannot hold 5,000 digits)."""
    if len(digits.lstrip("0")) > MAX_DIGITS:
        raise NcAlarm(0x0223, f"O number with {len(digits)} digits (at most {MAX_DIGITS})",
                      line=line, block=block)
    return int(digits)


_O_LINE = re.compile(r"\s*[Oo]([0-9]+)")


def parse_program(text: str, name: str = "program", number: int | None = None, *, start: int = 0,
                  stop: int | None = None, line0: int = 0) -> Program:
    """Parse one program (one O number): the lines of `text[start:stop]`, the first numbered
    `line0` + 1.  The first line starting with ``O`` is its description (N ch.2).  Raises NcAlarm
    (with line and block) on the first malformed block."""
    return _parse(_one_line_break(text), name, number, start, stop, line0)


def _parse(text: str, name: str, number: int | None, start: int, stop: int | None, line0: int) -> Program:
    """`parse_program` of a text whose only line break is "\n"."""
    blocks = BlockList(text)
    add_text, n_items = blocks._add_text, blocks._lines
    labels: dict[int, list[int]] = {}
    plain_ok = _PLAIN_OK.fullmatch
    stop = len(text) if stop is None else stop
    idx, pos = line0, start
    while pos < stop:  # line by line without a list of lines (a 1M-block program, issue 16)
        end = text.find("\n", pos, stop)
        if end < 0:
            end = stop
        idx += 1
        m = plain_ok(text, pos, end)
        if m is not None and end > pos:  # kept as text (BlockList): no block object per line
            if m.group(1) is not None:
                labels.setdefault(int(m.group(1)), []).append(len(n_items))
            elif text[pos:end].isspace():
                pos = end + 1
                continue
            add_text(pos, end, idx)
            pos = end + 1
            continue
        raw = text[pos:end]
        pos = end + 1
        stripped = raw.strip()
        if not stripped:
            continue
        m = _O_LINE.match(stripped)
        if m and not blocks and number is None:
            number = o_number(m.group(1), idx, raw)
            continue
        if m and not blocks:
            continue
        block = parse_block(idx, raw)
        if block.words or block.n is not None or block.comma or block.stmt is not None or block.comma_expr:
            if block.n is not None:
                labels.setdefault(block.n, []).append(len(blocks))
            blocks._add(block, idx)
    return Program(name=name, blocks=blocks, number=number, labels=labels)


# Line breaks str.splitlines knows besides "\n"; a text holding one is rewritten with "\n" alone
_OTHER_BREAKS = re.compile("[\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]")


def _one_line_break(text: str) -> str:
    """`text` with its lines (as str.splitlines reads them) joined by "\n" alone: line numbers
    stay; the common file (only "\n") is returned as it is, not copied."""
    if _OTHER_BREAKS.search(text) is None:
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
