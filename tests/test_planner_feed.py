"""The feed side of the planner made cheaper (issue 17, decision bench B166): the run feed's junction tests without
`math.dist` where they decide nothing, and `new_block` in place of `Block(...)`. Each must decide exactly as what
it replaces: the same junction verdict at the very threshold, every field of a block the same."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hil.bench_file import load_bench_file
from nc.motion.block import Block, new_block
from nc.motion.planner import Planner
from nc.motion.spline_feed import NOTHING, RunFeed
from nc.moves import Move
from tests.test_motion_cam import BENCH

AX = ("X", "Y", "Z")


def _cfg(**kw):
    return dataclasses.replace(load_bench_file(BENCH).motion_config(), **kw)


def _line(p, q, feed=3000.0, line=1) -> Move:
    s, e = dict(zip(AX, map(float, p))), dict(zip(AX, map(float, q)))
    return Move("line", line, "", s, e, e, feed=feed, plane=("X", "Y"))


def _junction(u0, u1, feed):
    """A RunFeed and its held state after two 1 mm lines along u0 (the first is held until the second's junction
    decides: straight on, both let through), and a third line along u1 (the junction to test)."""
    rf = RunFeed(_cfg(), Planner(_cfg(), dict(zip(AX, (0.0, 0.0, 0.0)))).lim)
    p0 = (5.0, 5.0, 5.0)
    p1 = tuple(p + d for p, d in zip(p0, u0))
    p2 = tuple(p + d for p, d in zip(p1, u0))
    p3 = tuple(p + d for p, d in zip(p2, u1))
    st = rf.feed(rf.feed(NOTHING, _line(p0, p1, feed)), _line(p1, p2, feed))
    assert not st.moves and not st.fitting
    return rf, st, _line(p2, p3, feed)


def test_the_pay_threshold_decides_as_math_dist_does():
    """|Δu| is summed plainly where it is far from the thresholds; at the very threshold math.dist decides, as
    before. Directions whose plain sum and math.dist differ in the last bit, with the pay threshold (the cached
    `_pay_step`) set to math.dist's |Δu| itself (not fitted: |Δu| > threshold is false) and to the double below
    it (fitted: the run is held)."""
    rng = np.random.default_rng(7)
    found = 0
    for _ in range(20000):
        a = rng.normal(size=3)
        b = a + rng.normal(scale=0.05, size=3)
        rf, st, mv = _junction((a / np.linalg.norm(a)).tolist(), (b / np.linalg.norm(b)).tolist(), 3000.0)
        u = rf.line(mv)[2]  # the directions as the run feed works them out
        du = math.dist(u, st.u)
        d = [p - q for p, q in zip(u, st.u)]
        if math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) == du:  # the plain sum the same: nothing to tell
            continue
        found += 1
        rf._pay[3000.0] = du
        h = rf.feed(st, mv)
        assert not h.fitting and rf.out is None  # through as a line: |Δu| is not above the threshold
        rf._pay[3000.0] = math.nextafter(du, 0.0)
        h = rf.feed(st, mv)
        assert h.fitting and h.moves == (mv,) and rf.out == []  # held: the run is fitted from it
        if found >= 5:
            break
    assert found >= 5


def test_new_block_is_block_with_its_defaults():
    """Every field of `new_block(...)` as `Block(...)` with the same nine arguments gives it (a field added to Block
    with a default must be added to new_block too)."""
    mv = _line((0.0, 0.0, 0.0), (1.0, 0.5, 0.0))
    args = (mv, "path", None, 1.118, 66.6, 4000.0, 200000.0, 50.0, False)
    got, want = new_block(*args), Block(*args)
    assert type(got) is Block
    for f in dataclasses.fields(Block):
        assert repr(getattr(got, f.name)) == repr(getattr(want, f.name)), f.name
