"""Macro B expressions compiled once into Python functions (issue 16): a statement in a loop is
evaluated thousands of times, and walking its tree node by node (`nc.program.expr.evaluate`:
a type dispatch and a chain of operator tests per node) was the larger part of its cost.

An expression becomes the source of one Python function (`_source`: `#1 + 1` is
`(0.0 if (t0 := r(1)) is None else t0) + 1.0`), compiled once: one call per evaluation, not one
per node as the closures of `compile_expr` (kept for expressions nested too deep for the Python
compiler) took.

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
        hit = _CACHE[id(e)] = (e, compiled(e))
    return hit[1](read)


def assignment(key: object, target: Var, value: Expr, read: Read) -> tuple[int, Value]:
    """`#target = value` of statement `key`: (variable number, value), the number first as
    `var_index` then `evaluate` find them (a constant number is found when compiled)."""
    hit = _CACHE.get(id(key))
    if hit is None or hit[0] is not key:
        if len(_CACHE) >= _CACHE_LIMIT:
            _CACHE.clear()
        hit = _CACHE[id(key)] = (key, _assignment(target, value))  # type: ignore[assignment]
    return hit[1](read)  # type: ignore[return-value]


def _assignment(target: Var, value: Expr) -> Callable[[Read], tuple[int, Value]]:
    ix = target.index
    if type(ix) is Num:
        try:
            n = checked_index(ix.value)
        except NcAlarm:
            n = None
        if n is not None and _depth(value) <= _MAX_DEPTH:  # one function gives both
            return _compile(f"({n}, {{}})", value)  # type: ignore[return-value]
    index, fn = compiled(ix), compiled(value)
    return lambda read: (checked_index(index(read)), fn(read))


def compiled(e: Expr) -> Fn:
    """The function `fn(read)` that evaluates `e` (Python source compiled, else closures)."""
    if _depth(e) > _MAX_DEPTH:
        return compile_expr(e)
    return _compile("{}", e)


def _compile(shape: str, e: Expr) -> Fn:
    """`def _fn(r): return <shape with e's source>`, compiled."""
    consts: dict[str, object] = dict(_HELPERS)
    code = shape.format(_source(e, consts, [0]))
    namespace: dict[str, object] = {}
    exec(compile(f"def _fn(r):\n    return {code}\n", "<macro expression>", "exec"), consts, namespace)
    return namespace["_fn"]  # type: ignore[return-value]


_MAX_DEPTH = 40  # nesting the Python compiler takes with room (its limit is some 200 brackets)


def _depth(e: Expr) -> int:
    t = type(e)
    if t is Var:
        return 1 + _depth(e.index)
    if t is Unary:
        return 1 + _depth(e.arg)
    if t is Binary:
        return 1 + max(_depth(e.left), _depth(e.right))
    if t is Call:
        return 1 + max((_depth(a) for a in e.args), default=0)
    return 1


_HELPERS: dict[str, object] = {"_ci": checked_index, "_sin": math.sin, "_cos": math.cos, "_rad": math.radians,
                               "_call": _call}
# operators written inline as Python operators on two numbers (vacant read as 0)
_INLINE = {"+": "+", "-": "-", "*": "*"}
_COMPARE = {"<": "<", "LT": "<", ">": ">", "GT": ">", "<=": "<=", "LE": "<=", ">=": ">=", "GE": ">="}


def _const(value: object, consts: dict[str, object]) -> str:
    if type(value) is float and value - value == 0:  # finite: its repr reads back as the same float
        return f"({value!r})"
    name = f"_k{len(consts)}"
    consts[name] = value
    return name


def _source(e: Expr, consts: dict[str, object], temp: list[int]) -> str:
    """Python source of `e` as a value that may be None (a vacant variable)."""
    t = type(e)
    if t is Num:
        return _const(e.value, consts)
    if t is Var:
        ix = e.index
        if type(ix) is Num:
            try:
                return f"r({checked_index(ix.value)})"
            except NcAlarm:  # a bad constant number: the alarm when (and only if) it is evaluated
                return f"r(_ci({_const(ix.value, consts)}))"
        return f"r(_ci({_source(ix, consts, temp)}))"
    if t is Unary:
        if e.op == "-":
            return f"(-{_number(e.arg, consts, temp)})"
        return f"(0.0 if {_source(e.arg, consts, temp)} else 1.0)"  # NOT: vacant is 0
    if t is Binary:
        op = e.op
        if op in ("==", "EQ", "!=", "NE"):  # these tell vacant from 0: the raw values
            name = "_eq" if op in ("==", "EQ") else "_ne"
            consts[name] = _equal if name == "_eq" else _unequal
            return f"{name}({_source(e.left, consts, temp)}, {_source(e.right, consts, temp)})"
        a, b = _number(e.left, consts, temp), _number(e.right, consts, temp)
        if op in _INLINE:
            return f"({a} {_INLINE[op]} {b})"
        if op in _COMPARE:
            return f"(1.0 if {a} {_COMPARE[op]} {b} else 0.0)"
        fn = _ARITH.get(op)
        if fn is None:
            fn = _undefined(op)
        return f"{_const(fn, consts)}({a}, {b})"
    if t is Call:
        args = [_number(a, consts, temp) for a in e.args]
        if e.name in ("SIN", "COS") and len(args) == 1:  # as `_call` computes them, without its list
            return f"_{e.name.lower()}(_rad({args[0]}))"
        return f"_call({e.name!r}, [{', '.join(args)}])"
    raise NcAlarm(0x0000, f"bad expression node {e!r}")


def _number(e: Expr, consts: dict[str, object], temp: list[int]) -> str:
    """Python source of `e` as a number (vacant is 0.0): only a variable read can be vacant."""
    code = _source(e, consts, temp)
    if type(e) is not Var:
        return code
    k = temp[0]
    temp[0] += 1
    return f"(0.0 if (t{k} := {code}) is None else t{k})"


def _equal(lv: Value, rv: Value) -> float:
    return float((lv is None and rv is None) or (lv is not None and rv is not None and abs(lv - rv) < 1e-9))


def _unequal(lv: Value, rv: Value) -> float:
    return 1.0 - _equal(lv, rv)


def _undefined(op: str) -> Callable[[float, float], float]:
    def undefined(a: float, b: float) -> float:
        raise NcAlarm(0x0201, f"undefined operator {op}")
    return undefined


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
