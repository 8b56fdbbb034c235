"""Frames.origins gives its last result again while the offsets hold the same values (issue 16: it
ran for every move a cycle emits); a change made in place to any offset shows at once, and the
memo gives the sums bit for bit as the general formula does."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from nc.interp.state import Frames

AXES = ("X", "Z", "C")


def _sum(f: Frames, wcs: int, a: str) -> float:
    return f.external.get(a, 0.0) + f.work_offsets[wcs].get(a, 0.0) + f.local_shift.get(a, 0.0) \
        + f.set_shift.get(a, 0.0) + f.tool_shift.get(a, 0.0)


def test_an_offset_changed_in_place_shows_at_the_next_call() -> None:
    f = Frames(AXES)
    assert f.origins(0, AXES) == {"X": 0.0, "Z": 0.0, "C": 0.0}
    f.work_offsets[0]["X"] = 12.5  # G10 L2 P1 X12.5 writes the dict in place
    assert f.origins(0, AXES)["X"] == 12.5
    f.tool_shift = {"Z": -3.0}  # a T code replaces its dict
    assert f.origins(0, AXES) == {"X": 12.5, "Z": -3.0, "C": 0.0}
    f.tool_shift["Z"] = -4.0  # #2xxx writes in place
    f.set_shift["X"] = 1.0  # G92 / G50
    assert f.origins(0, AXES) == {"X": 13.5, "Z": -4.0, "C": 0.0}
    assert f.origins(1, AXES) == {"X": 1.0, "Z": -4.0, "C": 0.0}  # G55


zeros = st.sampled_from([0.0, -0.0, 1.5, -2.25, float("nan")])
offsets = st.dictionaries(st.sampled_from(AXES), zeros, max_size=3)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["e", "w", "lo", "s", "t"]), offsets), min_size=1, max_size=8))
def test_every_call_equals_the_sum_bit_for_bit(changes) -> None:
    f = Frames(AXES)
    for which, d in changes:
        if which == "w":
            f.work_offsets[0].clear()
            f.work_offsets[0].update(d)
        else:
            setattr(f, {"e": "external", "lo": "local_shift", "s": "set_shift", "t": "tool_shift"}[which], dict(d))
        got = f.origins(0, AXES)
        for a in AXES:
            want = _sum(f, 0, a)
            assert (math.isnan(got[a]) and math.isnan(want)) or \
                (got[a] == want and math.copysign(1, got[a]) == math.copysign(1, want))
