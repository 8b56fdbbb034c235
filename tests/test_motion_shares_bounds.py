"""The shares' tolerance verdict (nc.motion.shares._tolerance_free, decision motion 39) decides most junctions
from the bounds of the raised jerk's braking ratio (issue 17): the ratio must stay within [1, RATIO_BOUND],
and the verdict must be the one the exact expression gives, on the mill bench's filter and N1.053."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hil.bench_file import load_bench_file
from nc.motion.blending import FilterCorners
from nc.motion.block import Block
from nc.motion.shares import RATIO_BOUND, _tolerance_free
from nc.moves import Move

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def _corners() -> FilterCorners:
    cfg = load_bench_file(BENCH).motion_config()
    acc = [cfg.limit(a).max_acceleration for a in cfg.axes]
    jerk = [cfg.limit(a).max_jerk for a in cfg.axes]
    return FilterCorners(cfg, acc, jerk)


def test_braking_ratio_of_a_doubled_jerk_is_between_one_and_the_bound():
    fc = _corners()
    rng = np.random.default_rng(5)
    ratios = [fc._boost_ratio(float(a), float(j))
              for a, j in zip(10 ** rng.uniform(-1, 5, 3000), 10 ** rng.uniform(0, 7, 3000))]
    assert min(ratios) >= 1.0
    assert max(ratios) <= 2.0 + 1e-12 < RATIO_BOUND
    assert max(ratios) > 1.5  # the bound is not loose by construction: fast jerks nearly double it


def test_verdict_is_the_exact_expressions():
    fc = _corners()
    assert fc.tol is not None
    rng = np.random.default_rng(11)
    move = Move(kind="line", line=1, block="G01 X1", start={}, end={}, work={})
    seen = set()
    for _ in range(4000):
        du_n = float(10 ** rng.uniform(-4, 0.3))
        a, j = float(10 ** rng.uniform(1, 4)), float(10 ** rng.uniform(2, 6))
        cap = float(rng.uniform(1.0, 200.0))
        tcap = float(cap * rng.uniform(0.5, 3.0))
        b = Block(move, "path", None, 1.0, cap, a, j, 50.0, vtop=cap, cap=cap, s_end=1.0, du_n=du_n,
                  vtol=tcap, vctol=math.inf)
        nxt = Block(move, "path", None, 1.0, cap, a, j, 50.0, vtop=cap, cap=cap * 0.5, s_end=2.0)
        unb, boosted = fc.braking_pair(du_n, a, j)
        exact = cap * (fc.tol - unb) / tcap + boosted <= fc.tol
        assert _tolerance_free(fc, b, [b, nxt], [1.0, 2.0]) is exact
        seen.add(exact)
    assert seen == {True, False}
