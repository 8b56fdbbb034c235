"""Macro B expressions: tokens, a precedence-climbing parser and an evaluator.

Precedence (docs/decisions/language.md A10), lowest first:
  1. ``||``                                                   (left-assoc)
  2. ``&&``                                                   (left-assoc)
  3. comparisons ``== != < > <= >= EQ NE LT GT LE GE`` and, inside IF/WHILE brackets, ``=`` (A11)
  4. ``+ - OR | XOR ^``                                       (bitwise OR/XOR on 32-bit integers)
  5. ``* / MOD AND &``
  6. unary ``- + ! NOT``
  7. primaries: numbers, ``#n``, ``#[e]``, ``[e]``, ``FUNC[a(,b)]``, ``PI`` ``TRUE`` ``FALSE``
Angles are degrees.  A vacant variable (#0, None) is 0 in arithmetic and comparisons except that
``==``/``!=`` tell vacant from 0 (NC5 App. B.3.1.1).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable, Union

from nc.alarms import NcAlarm

Value = Union[float, None]


# ---- AST -----------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Num:
    value: float


@dataclass(frozen=True, slots=True)
class Var:
    index: "Expr"  # Num for #100, any expression for #[...]


@dataclass(frozen=True, slots=True)
class Unary:
    op: str
    arg: "Expr"


@dataclass(frozen=True, slots=True)
class Binary:
    op: str
    left: "Expr"
    right: "Expr"


@dataclass(frozen=True, slots=True)
class Call:
    name: str
    args: tuple["Expr", ...]


Expr = Union[Num, Var, Unary, Binary, Call]

FUNCTIONS: dict[str, tuple[int, ...]] = {
    "SIN": (1,), "COS": (1,), "TAN": (1,), "ASIN": (1,), "ACOS": (1,), "ATAN": (1, 2), "ATAN2": (2,),
    "SQRT": (1,), "ABS": (1,), "ROUND": (1,), "FIX": (1,), "FUP": (1,), "LN": (1,), "EXP": (1,),
    "POW": (2,), "BIT": (2,), "COMPL": (1,), "BSL": (1,), "BSR": (1,),
}
CONSTANTS = {"PI": math.pi, "TRUE": 1.0, "FALSE": 0.0}
WORD_OPS = {"MOD", "AND", "OR", "XOR", "EQ", "NE", "LT", "GT", "LE", "GE", "NOT"}
LEVELS: list[set[str]] = [
    {"||"},
    {"&&"},
    {"==", "!=", "<", ">", "<=", ">=", "EQ", "NE", "LT", "GT", "LE", "GE", "="},
    {"+", "-", "OR", "|", "XOR", "^"},
    {"*", "/", "MOD", "AND", "&"},
]
_NUM = re.compile(r"[0-9]+\.?[0-9]*|\.[0-9]+")  # ASCII digits only (decisions P1)
_WORD = re.compile(r"[A-Za-z]+")
_INDEX = re.compile(r"[0-9]+")
_SYM = ("||", "&&", "==", "!=", "<>", "<=", ">=", "<", ">", "=", "+", "-", "*", "/", "&", "|", "^", "!")


# Bounds that keep parser and evaluator (both recursive) far from Python's recursion limit; a block
# beyond them is an alarm, not a crash (docs/decisions/language.md "expression size").
MAX_NESTING = 32  # brackets, function calls, #[...] and unary signs inside one another
MAX_OPERATORS = 256  # binary operators in one expression


class ExprParser:
    """Parses expressions out of a block's code text starting at ``pos``; shares the text with the
    block parser so statements and words can be mixed (``IF[...]GOTO#1``)."""

    def __init__(self, text: str, pos: int = 0, *, eq_is_compare: bool = False) -> None:
        self.s = text
        self.pos = pos
        self.eq_is_compare = eq_is_compare
        self.depth = 0
        self.ops = 0

    def _nest(self, by: int) -> None:
        self.depth += by
        if self.depth > MAX_NESTING:
            raise self.error(0x0209, f"expression nested deeper than {MAX_NESTING} levels")

    # -- scanning helpers
    def skip(self) -> None:
        while self.pos < len(self.s) and self.s[self.pos].isspace():
            self.pos += 1

    def peek_word(self) -> str:
        self.skip()
        m = _WORD.match(self.s, self.pos)
        return m.group(0).upper() if m else ""

    def peek_sym(self) -> str:
        self.skip()
        for sym in _SYM:
            if self.s.startswith(sym, self.pos):
                return sym
        return ""

    def error(self, code: int, msg: str) -> NcAlarm:
        return NcAlarm(code, msg)

    def expect(self, ch: str) -> None:
        self.skip()
        if not self.s.startswith(ch, self.pos):
            raise self.error(0x0209 if ch in "[]" else 0x0206, f"expected {ch!r} at {self.s[self.pos:]!r}")
        self.pos += len(ch)

    # -- grammar
    def parse(self, level: int = 0) -> Expr:
        if level == len(LEVELS):
            return self.unary()
        left = self.parse(level + 1)
        ops = LEVELS[level]
        while True:
            op = self._peek_op(ops)
            if not op:
                return left
            self.pos += len(op)
            if op == "=":
                op = "=="
            if op == "<>":
                op = "!="
            self.ops += 1
            if self.ops > MAX_OPERATORS:
                raise self.error(0x0206, f"expression has more than {MAX_OPERATORS} operators")
            right = self.parse(level + 1)
            left = Binary(op.upper(), left, right)

    def _peek_op(self, ops: set[str]) -> str:
        sym = self.peek_sym()
        if sym == "<>" and "!=" in ops:
            return "<>"
        if sym and sym in ops:
            if sym == "=" and not self.eq_is_compare:
                return ""
            return sym
        w = self.peek_word()
        if w:
            # word operators end where the next token starts: 3AND6, 5MOD3, 9LT5
            for op in sorted((o for o in ops if o.isalpha()), key=len, reverse=True):
                if w.startswith(op):
                    return self.s[self.pos:self.pos + len(op)]
        return ""

    def unary(self) -> Expr:
        sym = self.peek_sym()
        if sym in ("-", "+", "!"):
            self.pos += 1
            self._nest(1)
            arg = self.unary()
            self._nest(-1)
            return arg if sym == "+" else Unary(sym, arg)
        if self.peek_word() == "NOT":
            self.pos += 3
            self._nest(1)
            arg = self.unary()
            self._nest(-1)
            return Unary("!", arg)
        self._nest(1)
        e = self.primary()
        self._nest(-1)
        return e

    def primary(self) -> Expr:
        self.skip()
        if self.pos >= len(self.s):
            raise self.error(0x0206, "expression ends too early")
        c = self.s[self.pos]
        if c == "[":
            self.pos += 1
            e = self.parse()
            self.expect("]")
            return e
        if c == "#":
            return self.variable()
        m = _NUM.match(self.s, self.pos)
        if m:
            self.pos = m.end()
            return Num(float(m.group(0)))
        w = self.peek_word()
        if w:
            name = next((f for f in sorted(FUNCTIONS, key=len, reverse=True) if w.startswith(f)), None)
            if name and w == name:
                self.pos += len(name)
                self.expect("[")
                args = [self.parse()]
                while self.peek_sym() == "" and self.s.startswith(",", self.pos):
                    self.pos += 1
                    args.append(self.parse())
                self.expect("]")
                if len(args) not in FUNCTIONS[name]:
                    raise self.error(0x0256, f"{name} takes {' or '.join(map(str, FUNCTIONS[name]))} argument(s)")
                return Call(name, tuple(args))
            const = next((k for k in CONSTANTS if w.startswith(k)), None)
            if const:
                self.pos += len(const)
                return Num(CONSTANTS[const])
            raise self.error(0x0201, f"undefined operator {w!r}")
        raise self.error(0x0206, f"operator syntax error at {self.s[self.pos:]!r}")

    def variable(self) -> Var:
        self.expect("#")
        self.skip()
        if self.s.startswith("#", self.pos):
            raise self.error(0x0206, "two consecutive # symbols (write #[#n])")
        if self.s.startswith("[", self.pos):
            self.pos += 1
            e = self.parse()
            self.expect("]")
            return Var(e)
        m = _INDEX.match(self.s, self.pos)
        if not m:
            raise self.error(0x0206, "# must be followed by a number or [expression]")
        self.pos = m.end()
        return Var(Num(float(m.group(0))))


def parse_expression(text: str, *, compare: bool = False) -> Expr:
    p = ExprParser(text, eq_is_compare=compare)
    e = p.parse()
    p.skip()
    if p.pos != len(text):
        raise NcAlarm(0x0206, f"unexpected {text[p.pos:]!r} after expression")
    return e


# ---- evaluation ----------------------------------------------------------------------------
def _u32(x: float) -> int:
    return int(math.trunc(x)) & 0xFFFFFFFF


def _round_half_away(x: float) -> float:
    return float(math.floor(abs(x) + 0.5)) * (1.0 if x >= 0 else -1.0)


def _num(v: Value) -> float:
    return 0.0 if v is None else v


def evaluate(e: Expr, read: Callable[[int], Value]) -> Value:
    """Evaluate; ``read(n)`` returns variable n (None when vacant).  Raises NcAlarm on domain errors."""
    t = type(e)  # the node classes are final (no subclasses): an identity test is the cheapest dispatch
    if t is Num:
        return e.value
    if t is Var:
        return read(var_index(e, read))
    if t is Unary:
        a = _num(evaluate(e.arg, read))
        return -a if e.op == "-" else (0.0 if a else 1.0)
    if t is Binary:
        lv, rv = evaluate(e.left, read), evaluate(e.right, read)
        op = e.op
        if op in ("==", "EQ", "!=", "NE"):
            eq = (lv is None and rv is None) or (lv is not None and rv is not None and abs(lv - rv) < 1e-9)
            return float(eq if op in ("==", "EQ") else not eq)
        a, b = _num(lv), _num(rv)
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            if b == 0:
                raise NcAlarm(0x0210, "division by zero")
            return a / b
        if op == "MOD":
            ai, bi = int(_round_half_away(a)), int(_round_half_away(b))
            if bi == 0:
                raise NcAlarm(0x0210, "MOD by zero")
            return float(math.fmod(ai, bi))
        if op in ("AND", "&"):
            return float(_u32(a) & _u32(b))
        if op in ("OR", "|"):
            return float(_u32(a) | _u32(b))
        if op in ("XOR", "^"):
            return float(_u32(a) ^ _u32(b))
        if op == "&&":
            return float(bool(a) and bool(b))
        if op == "||":
            return float(bool(a) or bool(b))
        if op in ("<", "LT"):
            return float(a < b)
        if op in (">", "GT"):
            return float(a > b)
        if op in ("<=", "LE"):
            return float(a <= b)
        if op in (">=", "GE"):
            return float(a >= b)
        raise NcAlarm(0x0201, f"undefined operator {op}")
    if t is Call:
        args = [_num(evaluate(a, read)) for a in e.args]
        return _call(e.name, args)
    raise NcAlarm(0x0000, f"bad expression node {e!r}")


def var_index(v: Var, read: Callable[[int], Value]) -> int:
    ix = v.index
    return checked_index(ix.value if type(ix) is Num else evaluate(ix, read))  # `#1`: a number, most variables


def checked_index(raw: Value) -> int:
    """The variable number a `#[...]` index value names, or the alarm."""
    if raw is None:
        raise NcAlarm(0x0235, "#[...] index is vacant")
    idx = _round_half_away(raw)
    if idx < 0 or abs(raw - idx) > 1e-6 or idx > 10_000_000:
        raise NcAlarm(0x0235, f"variable number {raw:g} is not a valid # number")
    return int(idx)


def _call(name: str, a: list[float]) -> float:
    rad = math.radians
    try:
        if name == "SIN":
            return math.sin(rad(a[0]))
        if name == "COS":
            return math.cos(rad(a[0]))
        if name == "TAN":
            c = math.cos(rad(a[0]))
            if abs(c) < 1e-15:
                raise NcAlarm(0x0257, f"TAN[{a[0]:g}] is infinite")
            return math.tan(rad(a[0]))
        if name in ("ASIN", "ACOS"):
            if not -1.0 <= a[0] <= 1.0:
                raise NcAlarm(0x0257, f"{name}[{a[0]:g}]: argument outside -1..1")
            return math.degrees(math.asin(a[0]) if name == "ASIN" else math.acos(a[0]))
        if name == "ATAN":
            return math.degrees(math.atan(a[0]) if len(a) == 1 else math.atan2(a[0], a[1]))
        if name == "ATAN2":
            return math.degrees(math.atan2(a[0], a[1]))
        if name == "SQRT":
            if a[0] < 0:
                raise NcAlarm(0x0257, f"SQRT of negative {a[0]:g}")
            return math.sqrt(a[0])
        if name == "ABS":
            return abs(a[0])
        if name == "ROUND":
            return _round_half_away(a[0])
        if name == "FIX":
            return float(math.trunc(a[0]))
        if name == "FUP":
            t = math.trunc(a[0])
            return float(t if t == a[0] else t + (1 if a[0] > 0 else -1))
        if name == "LN":
            if a[0] <= 0:
                raise NcAlarm(0x0257, f"LN of {a[0]:g}")
            return math.log(a[0])
        if name == "EXP":
            return math.exp(a[0])
        if name == "POW":
            if a[0] < 0:
                raise NcAlarm(0x0257, f"POW of negative base {a[0]:g}")
            return math.pow(a[0], a[1])
        if name == "BIT":
            return float((_u32(a[0]) >> (int(a[1]) & 31)) & 1)
        if name == "COMPL":
            return float(~_u32(a[0]) & 0xFFFFFFFF)
        if name == "BSL":
            return float((1 << (int(a[0]) & 31)) & 0xFFFFFFFF)
        if name == "BSR":
            return float(_u32(a[0]) >> 1)
    except OverflowError:
        raise NcAlarm(0x0257, f"{name}: result out of range") from None
    raise NcAlarm(0x0201, f"unknown function {name}")
