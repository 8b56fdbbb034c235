"""B193 (issue 17): `Ahead.peek` (hil/stretch_reads.py) answers the soft limits of the moves it reads with the box's
straight-line test found once for the reads (`SoftLimits.line_test`), of a move's end alone where its start equals
the end of the last move that test found inside. On random runs of lines, rapids and arcs (starts that continue the
last end, or not; ends on and past the bench's 1st segment, NaN, an axis more or less) during which a G10 L21
value comes in, an axis's 1st segment is switched off or the bench's segments change, peek takes a move as plain
exactly when the full check (no quick answers) finds no alarm for it at the moment it is read, and stops at the
first it finds one for, which the channel then reads with that alarm."""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import SimpleNamespace

from hypothesis import given, settings
from hypothesis import strategies as st

from hil.stretch_reads import Ahead
from nc.budget import StatementBudget
from nc.moves import Move
from nc.softlimits import SoftLimits
from tests.test_softlimits_inside import _full

AXES = ("X", "Y", "Z")
FIRST = {"X": (-500.0, 500.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}
value = st.one_of(st.floats(-600, 600), st.sampled_from([0.0, 500.0, -500.0, 500.0 + 1e-9, 500.0 + 2e-9, 300.0 + 2e-9,
                                                         math.nan]))
step = st.tuples(st.booleans(), st.sampled_from([AXES, AXES, AXES, ("X", "Y")]), st.lists(value, min_size=6, max_size=6),
                 st.sampled_from(["line", "line", "rapid", "arc"]))


def _moves(steps: list, sl: SoftLimits, params: dict, change: int, what: str, verdicts: list) -> Iterator[Move]:
    """The moves, the limits changed as the interpreter would change them while generating the one at `change`; each
    move's verdict (the full check's, at the moment it is read) appended as it is handed out."""
    last_end: dict[str, float] = {"X": 0.0, "Y": 0.0, "Z": 0.0}
    for k, (chain, axes, vals, kind) in enumerate(steps):
        if k == change:
            if what == "param":
                params["soft limit 1 X"] = 100.0
            elif what == "disable":
                sl.disabled.add("Y")
            elif what == "first":
                sl.first = {"X": (-50.0, 50.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}
        start = dict(last_end) if chain else dict(zip(AXES, vals[:3]))  # a program's next line: equal, not the same
        end = dict(zip(axes, vals[3:]))
        mv = Move(kind, k + 1, f"G1 X{k}.", start, end, dict(end), {"X": 0.0, "Y": 0.0} if kind == "arc" else None,
                  "cw", plane=("X", "Y"))
        verdicts.append(_full(sl, mv))
        last_end = end
        yield mv


@settings(max_examples=300, deadline=None)
@given(steps=st.lists(step, min_size=1, max_size=24), change=st.integers(0, 24),
       what=st.sampled_from(["param", "disable", "first", "none"]), budget=st.booleans())
def test_peek_takes_a_move_as_plain_exactly_when_the_full_check_finds_no_alarm(steps: list, change: int, what: str,
                                                                                budget: bool) -> None:
    params: dict[str, float] = {}
    sl = SoftLimits(dict(FIRST), params)
    for _ in range(2):  # the axes' names, then the box found (the first peek's moves: `check` alone without it)
        sl.check(Move("line", 0, "", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 0.0, "Z": 0.0}, {}))
    verdicts: list = []
    ch = SimpleNamespace(statement_budget=StatementBudget() if budget else None, soft_limits=sl, _checked=None)
    a = Ahead(_moves(steps, sl, params, change, what, verdicts), ch)
    taken = 0
    while a.peek(4):
        while a.plain:  # the feed's reads
            mv = next(a)
            assert verdicts[mv.line - 1] is None, f"move {mv.line} taken as plain past its alarm"
            taken += 1
    for mv in a.plain:  # read ahead, not fed yet
        assert verdicts[mv.line - 1] is None
        taken += 1
    # the peek stopped at the first move the full check finds an alarm for (or the program's end)
    first_alarm = next((i for i, v in enumerate(verdicts) if v is not None), None)
    ev, exc, _, _ = a.tail
    if first_alarm is None:
        assert ev is None and isinstance(exc, StopIteration) and taken == len(steps)
    else:
        assert exc is None and ev.line == first_alarm + 1 and taken == first_alarm
        assert sl.check(ev) is not None and sl.check(ev).code == verdicts[first_alarm].code


def test_a_start_equal_to_an_end_found_inside_needs_its_end_alone() -> None:
    """The quick path itself: a line whose start continues the last end is answered by the test of its end (the
    start's verdict is that end's), one that does not by the test of both; a start outside the box is refused even
    where its end is inside."""
    sl = SoftLimits(dict(FIRST), {})
    for _ in range(2):  # the axes' names, then the box found
        sl.check(Move("line", 0, "", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 0.0, "Z": 0.0}, {}))
    test, end_test, params, n = sl.line_test()
    assert params is sl.params and n == 0
    assert end_test({"X": 499.0, "Y": -499.0, "Z": 299.0}) and not end_test({"X": 501.0, "Y": 0.0, "Z": 0.0})
    assert not end_test({"X": 1.0, "Y": 0.0}) and not end_test({"X": 1.0, "Y": 0.0, "A": 0.0})
    assert not test({"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 0.0, "A": 0.0})  # "not known": no KeyError
    moves = [Move("line", 1, "", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 10.0, "Y": 0.0, "Z": 0.0}, {}),
             Move("line", 2, "", {"X": 10.0, "Y": 0.0, "Z": 0.0}, {"X": 20.0, "Y": 0.0, "Z": 0.0}, {}),
             Move("line", 3, "G1 X20.", {"X": 600.0, "Y": 0.0, "Z": 0.0}, {"X": 20.0, "Y": 0.0, "Z": 0.0}, {})]
    ch = SimpleNamespace(statement_budget=None, soft_limits=sl, _checked=None)
    a = Ahead(iter(moves), ch)
    assert not a.peek(4)
    assert list(a.plain) == moves[:2] and a.tail[0] is moves[2]
    assert sl.check(moves[2]).code == 0x0A01
    # the limits changed (a G10 L21 value): no quick answer until the box is found again
    sl.params["soft limit 1 X"] = 15.0
    assert sl.line_test() is None
    b = Ahead(iter([Move("line", 4, "G1 X20.", {"X": 10.0, "Y": 0.0, "Z": 0.0}, {"X": 20.0, "Y": 0.0, "Z": 0.0}, {})]),
              ch)
    b._inside = a._inside  # the last end found inside before the change
    assert not b.peek(4) and b.tail[0].line == 4


def test_a_read_that_runs_a_statement_or_raises_ends_the_peek_with_the_budget_it_left() -> None:
    """Each read opens a cycle's budget (0 used): a move generated without a statement is plain, the first one whose
    generation spent the budget (a macro statement) is the tail with the count it left, and an alarm raised reading
    is the tail too; after the peek the budget stands as before it."""
    budget = StatementBudget()
    budget.used, budget.peak = 5, 7  # a cycle's count before the peek

    def source() -> Iterator[Move]:
        for k in range(1, 4):
            if k == 3:
                budget.spend()
                budget.spend()
            yield Move("line", k, f"G1 X{k}.", {"X": k - 1.0}, {"X": float(k)}, {"X": float(k)}, feed=1000.0)
        raise RuntimeError("the interpreter's alarm")

    ch = SimpleNamespace(statement_budget=budget, soft_limits=None, _checked=None)
    a = Ahead(source(), ch)
    assert not a.peek(4)
    assert [m.line for m in a.plain] == [1, 2]
    ev, exc, used, peak = a.tail
    assert ev.line == 3 and exc is None and used == 2 and peak == 7
    assert (budget.used, budget.peak) == (5, 7)
    assert [next(a).line for _ in range(3)] == [1, 2, 3]  # the tail handed out after the plain ones
    assert budget.used == 2  # as generating it left it
    assert not a.peek(4) and a.tail[0] is None and isinstance(a.tail[1], RuntimeError)
