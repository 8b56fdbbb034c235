"""Property test of G71 roughing on random contours (pure geometry, no interpreter):
no move of the cycle enters the finished contour, no layer is deeper than the programmed depth,
the cycle ends where it started."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from cycles_helpers import contour_x
from nc.cycles.builder import PathBuilder
from nc.cycles.geometry import Seg, point_seg_distance
from nc.cycles.turning import RoughSpec, rough


@st.composite
def contours(draw):
    """Type II contours: Z strictly decreasing steps, X anywhere in 2..18 (pockets included)."""
    n = draw(st.integers(2, 7))
    z = 0.0
    pts = [(z, draw(st.floats(2.0, 18.0)))]
    for _ in range(n):
        z -= draw(st.floats(1.0, 12.0))
        pts.append((z, draw(st.floats(2.0, 18.0))))
    pts.append((pts[-1][0], 20.0))
    return pts


@settings(max_examples=200, deadline=None)
@given(pts=contours(), depth=st.floats(0.3, 4.0), retract=st.floats(0.0, 1.0), h=st.sampled_from([0, 1]))
def test_rough_never_enters_contour(pts, depth, retract, h):
    segs = [Seg(a, b) for a, b in zip(pts, pts[1:])]
    # the P block also moves Z (type II): a feed from the start point onto the contour start
    start = (2.0, 20.0)
    path = [Seg(start, pts[0])] + segs
    b = PathBuilder({"Z": start[0], "X": start[1]}, ("Z", "X"), 1, "", lambda m: dict(m))
    b.feed = 0.2
    rough(b, path, RoughSpec("G71", depth, retract, 0.0, 0.0, h))
    cont = path
    levels = [20.0]
    for m in b.events:
        s = Seg((m.start["Z"], m.start["X"]), (m.end["Z"], m.end["X"]))
        for z, x in s.samples(6):
            if pts[-1][0] + 1e-9 < z < start[0] - 1e-9:
                c = contour_x(cont, z)
                assert x >= c - 1e-6 or min(point_seg_distance((z, x), q) for q in cont) < 1e-6
        if "rough" in m.tags:
            levels.append(m.end["X"])
    lv = sorted(set(round(v, 9) for v in levels), reverse=True)
    assert all(a - b_ <= depth + 1e-9 for a, b_ in zip(lv, lv[1:]))
    assert (b.position["Z"], b.position["X"]) == start


coord = st.floats(-1e4, 1e4, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(p0=st.tuples(coord, coord), p1=st.tuples(coord, coord))
def test_line_depths_from_its_ends(p0, p1):
    """The roughing contour reads a line's depths from its two ends (issue 16): the lowest, the highest
    and the last value, and whether the depth ever falls, are those of its eight-step samples."""
    from nc.cycles.profile import _sample_ds

    full = [p[1] for p in Seg(p0, p1).samples(8)]
    short = _sample_ds(Seg(p0, p1))
    assert (min(short), max(short), short[0], short[-1]) == (min(full), max(full), full[0], full[-1])
    assert any(b < a for a, b in zip(short, short[1:])) == any(b < a for a, b in zip(full, full[1:]))


def test_seg_is_still_a_frozen_dataclass():
    """Seg's own __init__ (issue 16) keeps what the dataclass gave: defaults, equality, hashing,
    dataclasses.replace and refused assignment."""
    import dataclasses

    import pytest

    s = Seg((0.0, 1.0), (2.0, 3.0))
    assert (s.center, s.cw, s.rapid, s.src) == (None, False, False, None)
    assert s == Seg(p0=(0.0, 1.0), p1=(2.0, 3.0)) and hash(s) == hash(Seg((0.0, 1.0), (2.0, 3.0)))
    arc = dataclasses.replace(s, center=(1.0, 1.0), cw=True)
    assert (arc.p0, arc.p1, arc.center, arc.cw, arc.is_arc) == ((0.0, 1.0), (2.0, 3.0), (1.0, 1.0), True, True)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.p0 = (5.0, 5.0)  # type: ignore[misc]
