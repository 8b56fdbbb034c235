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
    """`check` without the quick answers (`_inside`, and the box's straight-line test made with it)."""
    sl._inside = lambda move: False  # type: ignore[method-assign]
    fast, sl._fast = sl._fast, None
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
