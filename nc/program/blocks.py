"""Lexing and parsing of Delta NC program text into blocks of address words.

Comment rules (docs/decisions.md A7): ``(`` … ``)`` is a comment and code may follow the ``)``;
an unclosed ``(`` runs to the end of the line; ``;``, ``//`` and ``%`` start a comment that runs
to the end of the line (``;`` is also the end of block).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from nc.alarms import NcAlarm


@dataclass(slots=True)
class Word:
    letter: str  # address, upper case ("X", "G", or a multi-letter axis name such as "XA1")
    value: float
    text: str  # as written, for alarms
    has_point: bool  # the number carried a decimal point


@dataclass(slots=True)
class Block:
    line: int  # 1-based line number in the file
    text: str  # the source line without its line break
    words: list[Word] = field(default_factory=list)
    n: int | None = None  # sequence number
    skip: bool = False  # starts with '/'
    comma: dict[str, float] = field(default_factory=dict)  # ,C ,R ,A
    comment: str = ""

    def get(self, letter: str) -> Word | None:
        """The last word with this address (repeated axis words: last wins, decisions A9)."""
        for w in reversed(self.words):
            if w.letter == letter:
                return w
        return None

    def all(self, letter: str) -> list[Word]:
        return [w for w in self.words if w.letter == letter]

    def has(self, letter: str) -> bool:
        return any(w.letter == letter for w in self.words)


@dataclass
class Program:
    name: str
    blocks: list[Block]
    number: int | None = None  # O number


_NUMBER = re.compile(r"[+-]?\s*(\d+\.?\d*|\.\d+)")


def strip_comments(text: str) -> tuple[str, str]:
    """Return (code, comment) for one line."""
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


def parse_block(line: int, text: str) -> Block:
    code, comment = strip_comments(text)
    block = Block(line=line, text=text.rstrip("\r\n"), comment=comment)
    s = code.strip()
    if s.startswith("/"):
        block.skip = True
        s = s[1:]
    i, n = 0, len(s)
    while i < n:
        c = s[i]
        if c.isspace():
            i += 1
            continue
        if c == ",":
            j = i + 1
            while j < n and s[j].isspace():
                j += 1
            if j >= n or s[j].upper() not in "CRA":
                raise NcAlarm(0x0207, f"',' must be followed by C, R or A: {s[i:].strip()!r}", line=line, block=text)
            letter = s[j].upper()
            m = _NUMBER.match(s, j + 1)
            if not m:
                raise NcAlarm(0x0222, f"no value after ',{letter}'", line=line, block=text)
            block.comma[letter] = float(m.group(0).replace(" ", ""))
            i = m.end()
            continue
        if not c.isalpha():
            raise NcAlarm(0x0206, f"unexpected character {c!r}", line=line, block=text)
        letter = c.upper()
        m = _NUMBER.match(s, i + 1)
        if not m:
            raise NcAlarm(0x0222, f"address {letter} has no value", line=line, block=text)
        raw = m.group(0).replace(" ", "")
        value = float(raw)
        if letter == "N" and not block.words and block.n is None:
            block.n = int(value)
        else:
            block.words.append(Word(letter, value, letter + raw, "." in raw))
        i = m.end()
    return block


def parse_program(text: str, name: str = "program") -> Program:
    """Parse a whole file. Raises NcAlarm (with line and block) on the first malformed block."""
    blocks: list[Block] = []
    number: int | None = None
    for idx, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped:
            continue
        if stripped.upper().startswith("O") and idx == 1 or (stripped.upper().startswith("O") and not blocks
                                                                and re.match(r"[Oo]\d+", stripped)):
            m = re.match(r"[Oo](\d+)", stripped)
            if m:
                number = int(m.group(1))
            continue  # the O line is the file description (NC5 ch.2)
        block = parse_block(idx, raw)
        if block.words or block.n is not None or block.comma:
            blocks.append(block)
    return Program(name=name, blocks=blocks, number=number)
