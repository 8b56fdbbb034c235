"""`SoftLimits.check`'s quick answer for a line inside both segments (`_inside`, issue 17) never hides
an alarm: on random lines, arcs, limits (bench, G10 L21 P1-P4, a diameter axis, a disabled axis) the
alarm is the one the full check over the path ranges gives, and a move that crosses is refused."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from nc.moves import Move
from nc.softlimits import SoftLimits

AXES = ("X", "Y", "Z")
value = st.one_of(st.floats(-400, 400), st.sampled_from([0.0, -0.0, 300.0, -300.0, 300.0 + 1e-9, 150.0]))
limit = st.one_of(st.none(), st.floats(-350, 350))


@st.composite
def limits(draw) -> SoftLimits:
    first = {a: tuple(sorted((draw(st.floats(-350, 350)), draw(st.floats(-350, 350)))))
             for a in draw(st.lists(st.sampled_from(AXES), unique=True))}
    params = {f"soft limit {p} {a}": v for p in (1, 2, 3, 4) for a in AXES if (v := draw(limit)) is not None}
    sl = SoftLimits(first, params, draw(st.sampled_from([(), ("X",)])))
    sl.disabled = set(draw(st.lists(st.sampled_from(AXES), unique=True, max_size=1)))
    return sl


@st.composite
def moves(draw) -> Move:
    start = {a: draw(value) for a in AXES}
    end_axes = draw(st.sampled_from([AXES, AXES, ("X", "Z")]))
    end = {a: draw(value) for a in end_axes}
    kind = draw(st.sampled_from(["line", "rapid", "arc", "thread"]))
    centre = {a: draw(value) for a in AXES} if kind == "arc" else None
    return Move(kind, 7, "G1 X1.", start, end, dict(end), centre, "cw" if draw(st.booleans()) else "ccw",
                plane=("X", "Y"))


def _full(sl: SoftLimits, mv: Move):
    """`check` without the quick answers (`_fast`, the box test, and `_inside`)."""
    fast = sl._fast
    sl._fast = lambda limits, move: False
    sl._inside = lambda move: False  # type: ignore[method-assign]
    try:
        return sl.check(mv)
    finally:
        del sl._inside
        sl._fast = fast


def _same_alarm(sl: SoftLimits, mv: Move) -> None:
    quick = sl.check(mv)
    full = _full(sl, mv)
    assert (quick is None) == (full is None)
    if full is not None:
        assert (quick.code, quick.message, quick.axis) == (full.code, full.message, full.axis)


@settings(max_examples=600, deadline=None)
@given(sl=limits(), mv=moves())
def test_the_quick_answer_gives_the_full_checks_alarm(sl: SoftLimits, mv: Move) -> None:
    _same_alarm(sl, mv)


@settings(max_examples=400, deadline=None)
@given(sl=limits(), bench_only=st.booleans(), mvs=st.lists(moves(), min_size=2, max_size=5))
def test_moves_after_the_first_give_the_full_checks_alarm(sl: SoftLimits, bench_only: bool, mvs: list[Move]) -> None:
    """Several moves against one SoftLimits (the parameter names it keeps per axis known from the second move
    on), with G10 L21 values or the bench's 1st segment alone (the CAM program's case)."""
    if bench_only:
        sl.params = {}
    for mv in mvs:
        _same_alarm(sl, mv)


def test_a_line_past_a_g10_l21_limit_is_refused_and_one_inside_passes() -> None:
    sl = SoftLimits({"X": (-300.0, 300.0)}, {"soft limit 3 Y": 50.0}, ())
    inside = Move("line", 3, "X1. Y2.", {"X": 0.0, "Y": 0.0}, {"X": 299.0, "Y": 49.0}, {"X": 299.0, "Y": 49.0})
    past = Move("line", 4, "Y60.", {"X": 0.0, "Y": 0.0}, {"X": 0.0, "Y": 60.0}, {"X": 0.0, "Y": 60.0})
    assert sl.check(inside) is None
    alarm = sl.check(past)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A03, "Y", 4)
    sl.params = {"soft limit 3 Y": 70.0}  # G10 L21 P3 changed: read again
    assert sl.check(past) is None


def test_a_g10_l21_limit_set_after_moves_that_had_none_is_read() -> None:
    """The bench's 1st segment while no G10 L21 value is set (the names kept after the first move);
    a value set later in place (G10 L21 P1, P4) is read by the next move, a disabled axis is skipped."""
    sl = SoftLimits({"X": (-300.0, 300.0)}, {}, ())
    mv = Move("line", 5, "X250. Y-40.", {"X": 0.0, "Y": 0.0}, {"X": 250.0, "Y": -40.0}, {"X": 250.0, "Y": -40.0})
    far = Move("line", 6, "X310.", {"X": 0.0, "Y": 0.0}, {"X": 310.0, "Y": 0.0}, {"X": 310.0, "Y": 0.0})
    assert sl.check(mv) is None and sl.check(mv) is None
    alarm = sl.check(far)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A01, "X", 6)
    low = Move("line", 7, "X-300.5", {"X": -299.0, "Y": 0.0}, {"X": -300.5, "Y": 0.0}, {"X": -300.5, "Y": 0.0})
    alarm = sl.check(low)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A01, "X", 7)
    sl.disabled.add("X")  # MLC M2x368: the 1st segment of X off
    assert sl.check(far) is None
    sl.disabled.clear()
    sl.params["soft limit 1 X"] = 200.0  # G10 L21 P1 X200.
    alarm = sl.check(mv)
    assert alarm is not None and (alarm.code, alarm.axis) == (0x0A01, "X")
    del sl.params["soft limit 1 X"]
    sl.params["soft limit 4 Y"] = -30.0  # G10 L21 P4 Y-30.: the 2nd segment
    alarm = sl.check(mv)
    assert alarm is not None and (alarm.code, alarm.axis) == (0x0A03, "Y")


def test_an_axis_first_seen_after_others_has_its_g10_l21_limit_read() -> None:
    """The quick answer keeps the G10 L21 names of the axes it has seen (`_names`; bench B136 tried looking for
    all of them at once): a move on an axis none before it had (Z after X/Y moves) still reads that axis's P3,
    set while the X/Y moves ran, and a move inside it passes."""
    sl = SoftLimits({"X": (-300.0, 300.0), "Y": (-200.0, 200.0)}, {}, ())
    xy = Move("line", 1, "X10. Y10.", {"X": 0.0, "Y": 0.0}, {"X": 10.0, "Y": 10.0}, {"X": 10.0, "Y": 10.0})
    assert sl.check(xy) is None and sl.check(xy) is None
    sl.params["soft limit 3 Z"] = 50.0  # G10 L21 P3 Z50.
    assert sl.check(xy) is None
    up = Move("line", 9, "Z60.", {"X": 10.0, "Y": 10.0, "Z": 0.0}, {"X": 10.0, "Y": 10.0, "Z": 60.0},
              {"X": 10.0, "Y": 10.0, "Z": 60.0})
    alarm = sl.check(up)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A03, "Z", 9)
    low = Move("line", 10, "Z40.", {"X": 10.0, "Y": 10.0, "Z": 0.0}, {"X": 10.0, "Y": 10.0, "Z": 40.0},
               {"X": 10.0, "Y": 10.0, "Z": 40.0})
    assert sl.check(low) is None


def _line(line: int, start: dict[str, float], end: dict[str, float]) -> Move:
    return Move("line", line, "X1.", start, end, dict(end))


def test_the_box_test_holds_only_for_the_box_it_was_made_for() -> None:
    """`check`'s first test (`_box_test`, issue 17: the bench's 1st segments as straight-line code) answers a line
    inside the box at once; what it was not made for goes to the full check: the params replaced by others of the
    same length, the bench's segments replaced, an axis switched off, a start with an axis the end has not, an arc
    bulging past a limit between two ends inside, a NaN end (inside, as `_inside` has it)."""
    sl = SoftLimits({"X": (-300.0, 300.0), "Y": (-200.0, 200.0), "Z": (-150.0, 150.0)}, {"max blocks": 9.0}, ())
    xyz = {"X": 0.0, "Y": 0.0, "Z": 0.0}
    inside = _line(1, xyz, {"X": 250.0, "Y": -190.0, "Z": 100.0})
    for _ in range(3):  # the axes' names kept, the box found, its test made
        assert sl.check(inside) is None
    assert sl._fast(sl, inside) is True
    past = _line(2, xyz, {"X": 250.0, "Y": -190.0, "Z": 160.0})
    alarm = sl.check(past)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A01, "Z", 2)
    sl.params = {"soft limit 1 X": 200.0}  # as many params, G10 L21 P1 X among them
    alarm = sl.check(inside)
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A01, "X", 1)
    sl.params = {"max blocks": 9.0}
    assert sl.check(inside) is None
    sl.first = {"X": (-300.0, 240.0), "Y": (-200.0, 200.0), "Z": (-150.0, 150.0)}  # another bench segment
    alarm = sl.check(inside)
    assert alarm is not None and (alarm.code, alarm.axis) == (0x0A01, "X")
    sl.disabled.add("X")  # MLC M2x368
    assert sl.check(inside) is None
    sl.disabled.clear()
    sl.first = {"X": (-300.0, 300.0), "Y": (-200.0, 200.0), "Z": (-150.0, 150.0)}
    assert sl.check(inside) is None and sl._fast(sl, inside) is True
    assert sl._fast(sl, _line(7, xyz, {"X": float("nan"), "Y": 0.0, "Z": 0.0})) is True  # as `_inside` has it
    extra = _line(3, {"X": 0.0, "Y": 0.0, "A": 500.0}, {"X": 1.0, "Y": 1.0, "Z": 0.0})
    assert sl._fast(sl, extra) is False
    wide = _line(4, {"X": 0.0, "Y": 0.0, "Z": 0.0, "A": 500.0}, {"X": 1.0, "Y": 1.0, "Z": 0.0, "A": 500.0})
    assert sl.check(wide) is None  # A has no limit
    arc = Move("arc", 5, "G2 X190. Y0. R95.", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 190.0, "Y": 0.0, "Z": 0.0},
               {"X": 190.0, "Y": 0.0, "Z": 0.0}, {"X": 95.0, "Y": 0.0, "Z": 0.0}, "ccw", plane=("X", "Y"))
    arc.center = {"X": 95.0, "Y": 0.0, "Z": 0.0}
    assert sl.check(arc) is None  # bulges to Y-95, inside
    big = Move("arc", 6, "G2 X250. Y0. R125.", {"X": 0.0, "Y": -150.0, "Z": 0.0}, {"X": 250.0, "Y": -150.0, "Z": 0.0},
               {"X": 250.0, "Y": -150.0, "Z": 0.0}, {"X": 125.0, "Y": -150.0, "Z": 0.0}, "ccw", plane=("X", "Y"))
    alarm = sl.check(big)  # both ends inside, the arc reaches Y-275
    assert alarm is not None and (alarm.code, alarm.axis, alarm.line) == (0x0A01, "Y", 6)
    nan = _line(7, xyz, {"X": float("nan"), "Y": 0.0, "Z": 0.0})
    assert sl.check(nan) is None  # as `_inside` has it
