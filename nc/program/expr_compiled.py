"""Macro B expressions compiled once into Python closures (issue 16): a statement in a loop is
evaluated thousands of times, and walking its tree node by node (`nc.program.expr.evaluate`:
a type dispatch and a chain of operator tests per node) was the larger part of its cost.

`evaluate(e, read)` here gives what `nc.program.expr.evaluate` gives, value and alarm alike, in
the same order of evaluation (left operand, right operand, then the operator; no short-circuit);
pinned by tests/test_expr_compiled.py (hypothesis, both evaluators on random expressions).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from nc.alarms import NcAlarm
from nc.program.expr import (Binary, Call, Expr, Num, Unary, Value, Var, _call, _round_half_away, _u32,
                             checked_index)

Read = Callable[[int], Value]
Fn = Callable[[Read], Value]

_CACHE: dict[int, tuple[Expr, Fn]] = {}  # id(node) -> (node, closure); the node kept so its id stays its own
_CACHE_LIMIT = 65536  # then it starts over (a program of millions of distinct expressions stays flat)


def evaluate(e: Expr, read: Read) -> Value:
    hit = _CACHE.get(id(e))
    if hit is None or hit[0] is not e:
        if len(_CACHE) >= _CACHE_LIMIT:
            _CACHE.clear()
        hit = _CACHE[id(e)] = (e, compile_expr(e))
    return hit[1](read)


def compile_expr(e: Expr) -> Fn:
    t = type(e)
    if t is Num:
        value = e.value
        return lambda read: value
    if t is Var:
        return _var(e)
    if t is Unary:
        arg = compile_expr(e.arg)
        if e.op == "-":
            def neg(read: Read) -> Value:
                a = arg(read)
                return -(0.0 if a is None else a)
            return neg
        return lambda read: 0.0 if arg(read) else 1.0  # NOT: vacant is 0
    if t is Binary:
        return _binary(e.op, compile_expr(e.left), compile_expr(e.right))
    if t is Call:
        return _function(e.name, tuple(compile_expr(a) for a in e.args))
    raise NcAlarm(0x0000, f"bad expression node {e!r}")


def _var(e: Var) -> Fn:
    ix = e.index
    if type(ix) is Num:
        try:
            n = checked_index(ix.value)
        except NcAlarm:  # a bad constant number: the alarm when (and only if) it is evaluated
            value = ix.value
            return lambda read: read(checked_index(value))
        return lambda read: read(n)
    index = compile_expr(ix)
    return lambda read: read(checked_index(index(read)))


def _binary(op: str, left: Fn, right: Fn) -> Fn:
    if op in ("==", "EQ", "!=", "NE"):
        want = op in ("==", "EQ")

        def equal(read: Read) -> Value:
            lv, rv = left(read), right(read)
            eq = (lv is None and rv is None) or (lv is not None and rv is not None and abs(lv - rv) < 1e-9)
            return float(eq if want else not eq)
        return equal
    arith = _ARITH.get(op)
    if arith is None:
        def undefined(read: Read) -> Value:
            left(read), right(read)
            raise NcAlarm(0x0201, f"undefined operator {op}")
        return undefined

    def binary(read: Read) -> Value:
        a, b = left(read), right(read)
        return arith(0.0 if a is None else a, 0.0 if b is None else b)
    if op == "+":  # the commonest operators without the extra call
        def add(read: Read) -> Value:
            a, b = left(read), right(read)
            return (0.0 if a is None else a) + (0.0 if b is None else b)
        return add
    if op == "*":
        def mul(read: Read) -> Value:
            a, b = left(read), right(read)
            return (0.0 if a is None else a) * (0.0 if b is None else b)
        return mul
    if op == "-":
        def sub(read: Read) -> Value:
            a, b = left(read), right(read)
            return (0.0 if a is None else a) - (0.0 if b is None else b)
        return sub
    return binary


def _div(a: float, b: float) -> float:
    if b == 0:
        raise NcAlarm(0x0210, "division by zero")
    return a / b


def _mod(a: float, b: float) -> float:
    ai, bi = int(_round_half_away(a)), int(_round_half_away(b))
    if bi == 0:
        raise NcAlarm(0x0210, "MOD by zero")
    return float(math.fmod(ai, bi))


_ARITH: dict[str, Callable[[float, float], float]] = {
    "+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b, "/": _div, "MOD": _mod,
    "AND": lambda a, b: float(_u32(a) & _u32(b)), "&": lambda a, b: float(_u32(a) & _u32(b)),
    "OR": lambda a, b: float(_u32(a) | _u32(b)), "|": lambda a, b: float(_u32(a) | _u32(b)),
    "XOR": lambda a, b: float(_u32(a) ^ _u32(b)), "^": lambda a, b: float(_u32(a) ^ _u32(b)),
    "&&": lambda a, b: float(bool(a) and bool(b)), "||": lambda a, b: float(bool(a) or bool(b)),
    "<": lambda a, b: float(a < b), "LT": lambda a, b: float(a < b),
    ">": lambda a, b: float(a > b), "GT": lambda a, b: float(a > b),
    "<=": lambda a, b: float(a <= b), "LE": lambda a, b: float(a <= b),
    ">=": lambda a, b: float(a >= b), "GE": lambda a, b: float(a >= b),
}


def _function(name: str, args: tuple[Fn, ...]) -> Fn:
    if name in ("SIN", "COS") and len(args) == 1:  # as `_call` computes them, without its list
        f, (arg,) = (math.sin if name == "SIN" else math.cos), args
        rad = math.radians

        def trig(read: Read) -> Value:
            a = arg(read)
            return f(rad(0.0 if a is None else a))
        return trig
    return lambda read: _call(name, [0.0 if (v := a(read)) is None else v for a in args])


def var_index(v: Var, read: Read) -> int:
    """`nc.program.expr.var_index` with the index expression compiled."""
    ix = v.index
    return checked_index(ix.value if type(ix) is Num else evaluate(ix, read))
