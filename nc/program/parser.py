"""One line of NC program text into a `Block` (nc.program.syntax): comments, block skip, address
words, macro statements, and the alarms of a malformed block. The rules are those of
nc.program.blocks (its docstring); split out of it (issue 16).
"""

from __future__ import annotations

import re
import unicodedata

from nc.alarms import NcAlarm
from nc.program.expr import Expr, ExprParser, Num
from nc.program.syntax import (Assign, Block, Else, ElseIf, End, EndIf, ExitW, Goto, IfGoto, IfThen, Statement, While,
                               Word)

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
