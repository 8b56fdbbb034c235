"""The backward pass from index `lo` (nc.motion.lookahead.backward; its islice/enumerate a C counter since session 31,
decision bench B181): the blocks below `lo` keep their end speeds, and each block from `lo` on gets the end speed,
binding flag and anchor a pass over the whole queue gives it (a block's values depend only on what follows it), bit
for bit; `depth` given by position or by keyword gives the same pass."""

from __future__ import annotations

from collections import deque

import numpy as np

from nc.motion.block import Block
from nc.motion.lookahead import backward

FIELDS = ("vend", "binding", "anchor_v", "anchor_d", "anchor_a", "anchor_j")


def _queue(rng: np.random.Generator, n: int) -> deque[Block]:
    q: deque[Block] = deque()
    for _ in range(n):
        b = Block(None, "path", None, float(rng.uniform(0.01, 5.0)), 0.0, float(rng.uniform(500.0, 3000.0)),
                  float(rng.uniform(1e4, 1e5)), None)
        b.cap = float(rng.uniform(5.0, 80.0))
        b.vjunc = 0.0 if rng.random() < 0.1 else float(rng.uniform(0.0, 90.0))
        b.vend, b.binding = -7.0, False  # a mark: a block the pass does not reach keeps it
        q.append(b)
    return q


def _state(q: deque[Block]) -> list[tuple]:
    return [tuple(getattr(b, f) for f in FIELDS) for b in q]


def test_pass_from_lo_leaves_the_head_and_matches_the_full_pass() -> None:
    rng = np.random.default_rng(181)
    for n in (1, 2, 3, 7, 40):
        for lo in range(0, n):
            seed = int(rng.integers(1 << 30))
            q, whole = _queue(np.random.default_rng(seed), n), _queue(np.random.default_rng(seed), n)
            backward(q, lo, full=True)
            backward(whole, 0, full=True)
            got, want = _state(q), _state(whole)
            assert got[:lo] == [(-7.0, False, 0.0, 0.0, 0.0, 0.0)] * lo  # untouched below lo
            assert got[lo:] == want[lo:]
            assert want[-1][:2] == (0.0, True)  # the tail ends at rest


def test_depth_by_position_or_keyword_is_the_same_pass() -> None:
    rng = np.random.default_rng(31)
    for depth in (0, 1, 3, 10, 60):
        q1, q2 = _queue(np.random.default_rng(depth), 50), _queue(np.random.default_rng(depth), 50)
        for q in (q1, q2):  # a first pass, then new junction speeds the next pass must reach `depth` deep for
            backward(q, 0, full=True)
        for b1, b2 in zip(q1, q2):
            b1.vjunc = b2.vjunc = b1.vjunc * float(rng.uniform(0.5, 1.5)) if rng.random() < 0.3 else b1.vjunc
        backward(q1, 0, False, depth)
        backward(q2, 0, depth=depth)
        assert _state(q1) == _state(q2)
