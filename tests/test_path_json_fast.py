"""`hil path --json` writes every move without intermediate dicts (hil.path_json.move_json,
issue 16): the line must be byte for byte what the general way (move_dict +
strict_json.dumps) writes, for any move, the goldens' seam."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hil import strict_json
from hil.path_json import move_dict, move_json, moves_json
from nc.moves import Move

number = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**6, 10**6),
                   st.sampled_from([0.0, -0.0, 1e-8, -4.9e-8, 5e-8, 123.4567891, 1e16]),
                   st.floats(-1e4, 1e4).map(np.float64))
axes = st.dictionaries(st.sampled_from(["X", "Y", "Z", "A", "C", "Ä"]), number, min_size=1, max_size=5)
moves = st.builds(
    Move, kind=st.sampled_from(["rapid", "line", "arc", "thread", "dwell"]), line=st.integers(0, 10**7),
    block=st.text(max_size=40), start=axes, end=axes, work=axes,
    center=st.one_of(st.none(), axes), dir=st.sampled_from([None, "cw", "ccw"]),
    feed=st.one_of(st.none(), number), duration=st.one_of(st.none(), st.floats(0, 10)),
    per_rev=st.booleans(), exact_stop=st.booleans(),
    tags=st.sampled_from([(), ("G71 rough",), ("G70", "finish", "nose \u00e9\"R")]),
    lead=st.one_of(st.none(), number), lead_change=number, start_angle=number,
    comp=st.sampled_from([None, "G41", "G42"]), comp_radius=number, tip=st.integers(0, 9))


@settings(max_examples=300, deadline=None)
@given(moves)
def test_fast_line_is_the_general_line(m: Move) -> None:
    assert move_json(m) == strict_json.dumps(move_dict(m))


def test_a_plain_feed_move_takes_the_fast_way() -> None:
    m = Move("line", 12, 'G1 X1 "q"', {"X": 0.0, "Z": -0.0}, {"X": 1.00000004, "Z": float("nan")},
             {"X": 2.0, "Z": 1e-9}, feed=1200)
    assert move_json(m) == ('{"kind": "line", "line": 12, "block": "G1 X1 \\"q\\"", "start": {"X": 0.0, "Z": 0.0}, '
                            '"end": {"X": 1.0, "Z": null}, "work": {"X": 2.0, "Z": 0.0}, "center": null, '
                            '"dir": null, "feed": 1200, "duration": null}')


def test_a_compensated_thread_pass_writes_its_additive_keys() -> None:
    m = Move("thread", 7, "G76 X21.4", {"X": 14.0, "Z": 5.0}, {"X": 13.35, "Z": -22.0}, {"X": 26.7, "Z": -22.0},
             feed=2.0, per_rev=True, lead=2.0, tags=("G76", "pass 3"), comp="G42", comp_radius=0.4, tip=3)
    assert move_json(m) == ('{"kind": "thread", "line": 7, "block": "G76 X21.4", "start": {"X": 14.0, "Z": 5.0}, '
                            '"end": {"X": 13.35, "Z": -22.0}, "work": {"X": 26.7, "Z": -22.0}, "center": null, '
                            '"dir": null, "feed": 2.0, "duration": null, "per_rev": true, "tags": ["G76", "pass 3"], '
                            '"lead": 2.0, "lead_change": 0.0, "start_angle": 0.0, "comp": "G42", "comp_radius": 0.4, '
                            '"tip": 3}')


@settings(max_examples=2000, deadline=None)
@given(st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.floats(-1e9, 1e9),
                 st.integers(-10**9, 10**9).map(lambda n: n / 10**7), st.integers(-10**9, 10**9).map(lambda n: n / 2**20),
                 st.sampled_from([1e-4, -1e-4, 0.00009999995, 0.00010000005, 99999999.99999996, 1e8, 0.5e-7,
                                  2.5e-7, 1.00000005, 0.00015])))
def test_seven_decimals_is_repr_of_round(v: float) -> None:
    """The 7-decimal number text of a coordinate ('%.7f' stripped) is repr(round(v, 7)) (issue 16)."""
    from hil.path_json import _seven

    assert _seven(v) == repr(round(v, 7) + 0.0)


@settings(max_examples=200, deadline=None)
@given(st.lists(moves, min_size=1, max_size=6), st.lists(st.booleans(), min_size=6, max_size=6))
def test_a_list_of_moves_is_each_move_alone(ms: list[Move], chained: list[bool]) -> None:
    """moves_json (a cycle's MoveList): a move that starts at the dict the move before it ended at, as a
    cycle's moves do, writes that point as move_json does on its own."""
    for k in range(1, len(ms)):
        if chained[k]:
            ms[k].start = ms[k - 1].end
    assert moves_json(ms) == [strict_json.dumps(move_dict(m)) for m in ms]


def test_a_point_changed_between_two_lists_is_written_anew() -> None:
    a = Move("rapid", 1, "G0", {"X": 0.0, "Z": 0.0}, {"X": 1.0, "Z": 2.0}, {"X": 2.0, "Z": 2.0})
    b = Move("line", 2, "G1", a.end, {"X": 3.0, "Z": 2.0}, {"X": 6.0, "Z": 2.0}, feed=0.1)
    assert moves_json([a]) == [strict_json.dumps(move_dict(a))]
    a.end["Z"] = 5.0  # in place, after its line was written
    assert moves_json([b])[0].startswith('{"kind": "line", "line": 2, "block": "G1", "start": {"X": 1.0, "Z": 5.0}')
