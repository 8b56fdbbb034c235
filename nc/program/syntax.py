"""The parsed forms of NC program text: address words (`Word`), macro statements (`Assign`, `While`, …)
and blocks (`Block`). nc.program.parser reads one line into them, nc.program.blocks a program (split
out of nc.program.blocks, issue 16)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from nc.program.expr import Expr, Var


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
