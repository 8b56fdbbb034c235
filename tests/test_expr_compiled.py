"""Macro expressions compiled into closures (nc.program.expr_compiled, issue 16) give what the tree
walker nc.program.expr.evaluate gives: the same value, or the same alarm, for any expression and
any variable values (vacant ones too)."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.program import expr as tree
from nc.program import expr_compiled as compiled
from nc.program.expr import Binary, Call, Num, Unary, Var, parse_expression

OPS = ["+", "-", "*", "/", "MOD", "AND", "&", "OR", "|", "XOR", "^", "&&", "||", "<", "LT", ">", "GT",
       "<=", "LE", ">=", "GE", "==", "EQ", "!=", "NE", "??"]
_few = st.sampled_from([0.0, 1.0, -1.0, 0.5, 2.0, 3.0, 1e-10, 1e300, -7.5])  # often equal: ties tested
numbers = st.one_of(_few, _few, _few, st.floats(-1e6, 1e6, allow_nan=False))
leaves = st.one_of(numbers.map(Num), st.sampled_from([1, 2, 3, 4, -1, 1.5]).map(lambda n: Var(Num(float(n)))))


def _grow(children):
    return st.one_of(
        st.builds(Unary, st.sampled_from(["-", "!"]), children),
        st.builds(Binary, st.sampled_from(OPS), children, children),
        st.builds(Var, children),
        st.builds(lambda n, a: Call(n, (a,)), st.sampled_from(["SIN", "COS", "TAN", "SQRT", "ABS", "ROUND", "FIX",
                                                               "FUP", "LN", "EXP", "ASIN", "ATAN", "BSR"]), children),
        st.builds(lambda n, a, b: Call(n, (a, b)), st.sampled_from(["POW", "ATAN2", "BIT", "ATAN"]), children, children))


expressions = st.recursive(leaves, _grow, max_leaves=12)
values = st.fixed_dictionaries({1: st.one_of(st.none(), numbers), 2: st.one_of(st.none(), numbers),
                                3: st.one_of(st.none(), numbers), 4: st.one_of(st.none(), numbers)})


def _outcome(evaluate, e, read):
    try:
        v = evaluate(e, read)
    except NcAlarm as exc:
        return ("alarm", exc.alarm.code, exc.alarm.message)
    except (ValueError, ArithmeticError) as exc:  # the interpreter reports these as 0x0257
        return ("error", type(exc).__name__)
    return ("nan",) if v is not None and math.isnan(v) else ("value", v)


@settings(max_examples=400, deadline=None)
@given(expressions, values)
def test_compiled_equals_the_tree_walker(e, vs) -> None:
    read = vs.get
    assert _outcome(compiled.evaluate, e, read) == _outcome(tree.evaluate, e, read)


def test_a_loop_statement_evaluates_with_its_variables() -> None:
    e = parse_expression("SIN[#1] * 10 + COS[#1 * 2] * 5 - #[#2 + 1] / 4")
    read = {1: 30.0, 2: 2.0, 3: 8.0}.get
    assert compiled.evaluate(e, read) == tree.evaluate(e, read)
    assert abs(compiled.evaluate(e, read) - (5.0 + 2.5 - 2.0)) < 1e-12
    assert compiled.evaluate(e, {1: 90.0, 2: 2.0}.get) == tree.evaluate(e, {1: 90.0, 2: 2.0}.get)  # #3 vacant


def test_a_bad_constant_variable_number_alarms_when_evaluated() -> None:
    e = parse_expression("#1 / 0 + #[1.5]")
    for ev in (compiled.evaluate, tree.evaluate):
        try:
            ev(e, {1: 1.0}.get)
        except NcAlarm as exc:
            assert exc.alarm.code == 0x0210  # the division comes first, as the tree walker finds it


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.sampled_from([1.0, 3.0, 100.0, 1.5, -2.0, 0.0]).map(Num), expressions), expressions, values)
def test_an_assignment_gives_the_number_then_the_value_as_the_tree_walker(index, value, vs) -> None:
    """`#[index] = value` compiled as one function: the variable number (or its alarm) first, then the value."""
    def tree_pair(read):
        return tree.var_index(Var(index), read), tree.evaluate(value, read)

    def outcome(pair):
        try:
            n, v = pair(vs.get)
        except NcAlarm as exc:
            return ("alarm", exc.alarm.code, exc.alarm.message)
        except (ValueError, ArithmeticError) as exc:
            return ("error", type(exc).__name__)
        return n, (("nan",) if v is not None and math.isnan(v) else ("value", v))

    assert outcome(compiled._assignment(Var(index), value)) == outcome(tree_pair)
