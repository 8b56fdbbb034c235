"""Issue 17 (decision bench B141): the position filter's state as a stretch saves and puts it back. A stretch
samples ahead and, where a drive would fault or a cut comes, puts the planner back (hil.stretch_state): the
filter's snapshot must give back the same outputs, bit for bit, as if the rows after it had never been pushed;
push_rows (the stretch's few rows) must give what push gives, shares λ included."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from nc.motion.smoothing import PositionFilter


def _moves(rng: np.random.Generator, n: int, axes: int) -> np.ndarray:
    """Moves, stands long enough to snap, short stands and -0.0."""
    x, rows = rng.uniform(-300, 300, axes), []
    while len(rows) < n:
        if rng.random() < 0.15:
            rows += [x.copy()] * int(rng.integers(1, 40))
        else:
            for _ in range(int(rng.integers(1, 60))):
                x = x + rng.normal(0, 0.2, axes) * (rng.random() < 0.9)
                if rng.random() < 0.02:
                    x = np.where(rng.random(axes) < 0.5, -0.0, x)
                rows.append(x.copy())
    return np.array(rows[:n])


@pytest.mark.parametrize("seed", range(6))
def test_push_rows_gives_what_push_gives_with_shares(seed):
    rng = np.random.default_rng(seed)
    n1 = int(rng.integers(2, 20))
    n2 = n1 if seed % 2 else int(rng.integers(1, 20))  # n1 = n2: λ acts (PositionFilter.lag)
    xs = _moves(rng, 800, 3 if seed < 3 else int(rng.integers(1, 6)))
    lam = np.where(rng.random(len(xs)) < 0.6, 1.0, rng.random(len(xs)))
    cuts, k = [], 0
    while k < len(xs):  # chunks of a stretch's few rows, some with no shares given (λ = 1)
        c = int(rng.integers(1, 12))
        given = rng.random() < 0.7
        if not given:
            lam[k:k + c] = 1.0
        cuts.append((k, k + c, given))
        k += c
    one, rows = PositionFilter(n1, n2, xs[0]), PositionFilter(n1, n2, xs[0])
    want = [one.push(x, float(lm)).tolist() for x, lm in zip(xs, lam)]
    got = []
    for a, b, given in cuts:
        got += rows.push_rows(xs[a:b].tolist(), lam[a:b].tolist() if given else None)
    assert got == want
    assert rows.output.tolist() == one.output.tolist() and rows.recent.tolist() == one.recent.tolist()


@pytest.mark.parametrize("seed", range(4))
def test_a_restored_snapshot_gives_the_outputs_of_a_filter_that_never_went_on(seed):
    rng = np.random.default_rng(seed)
    xs = _moves(rng, 600, 3)
    f, ref = PositionFilter(16, 16, xs[0]), PositionFilter(16, 16, xs[0])
    f.push_many(xs[:250])
    ref.push_many(xs[:250])
    snap = f.snapshot()
    assert f.same_state(snap)
    ahead = f.push_many(xs[250:400] + 0.25)  # a stretch sampled ahead, then put back
    assert not f.same_state(snap)
    f.restore(snap)
    assert f.same_state(snap) and f.settled == ref.settled and f._still == ref._still
    assert f.push_many(xs[250:]).tolist() == ref.push_many(xs[250:]).tolist()
    f.restore(snap)  # the snapshot stays as it was taken: it can be put back again
    again = f.push_many(xs[250:400] + 0.25)
    assert again.tolist() == ahead.tolist()


def test_a_copy_goes_on_alone():
    rng = np.random.default_rng(7)
    xs = _moves(rng, 400, 2)
    f, ref = PositionFilter(12, 8, xs[0]), PositionFilter(12, 8, xs[0])
    f.push_many(xs[:200])
    ref.push_many(xs[:200])
    for g in (f.copy(), copy.copy(f)):
        g.push_many(xs[200:] * 2.0)  # its own rows: the original does not see them
        assert g.recent.tolist() != f.recent.tolist()
    assert f.recent.tolist() == ref.recent.tolist()
    assert f.push_many(xs[200:]).tolist() == ref.push_many(xs[200:]).tolist()


def test_a_row_of_the_wrong_width_is_refused():
    f = PositionFilter(8, 8, np.zeros(3))
    with pytest.raises(ValueError, match="3 axes"):
        f.push_rows([[1.0, 2.0]])
