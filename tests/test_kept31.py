"""A kept profile's checks in C (nc.motion.profile `time_at`, `peak_speed`, `fits_queue`, `later`; nc.motion.hold_stop
re-exports them; session 31, decision bench B184): where the planner is compiled they are C functions, and they answer
as the Python walks before them (hold_stop's, kept below as the reference) did, bit for bit, on random solves from
accelerating, cruising and braking states and random queues of blocks around the profile's end."""

from __future__ import annotations

import random

import pytest

from nc.motion import hold_stop, profile
from nc.motion.block import Block
from nc.motion.compiled import BUILD
from nc.motion.profile import solve_position


# ---- the reference: nc/motion/hold_stop.py's functions before B184, reading the profile through `at` -------------
def _phases(pw):
    pw.at(0.0)
    return pw._lists[1:]


def time_at_before(pw, x: float, lo: float = 0.0) -> float:
    hi = pw.duration
    t = lo
    for _ in range(60):
        p, v, _ = pw.at(t)
        if p < x:
            lo = t
        else:
            hi = t
        if abs(p - x) <= 1e-13 or hi - lo <= 1e-15:
            break
        t = t - (p - x) / v if v > 1e-12 else -1.0
        if not lo < t < hi:
            t = 0.5 * (lo + hi)
    return t


def peak_speed_before(pw, t: float) -> float:
    t0, _, _, a, j = _phases(pw)
    dur = pw.duration
    top = max(pw.at(t)[1], pw.at(dur)[1])
    for k in range(len(t0)):
        lo, hi = max(t0[k], t), min(t0[k + 1] if k + 1 < len(t0) else dur, dur)
        if lo >= hi:
            continue
        top = max(top, pw.at(hi)[1])
        if j[k] != 0.0 and lo < t0[k] - a[k] / j[k] < hi:
            top = max(top, pw.at(t0[k] - a[k] / j[k])[1])
    return top


def fits_queue_before(pw, t: float, end: float, blocks) -> bool:
    top = peak_speed_before(pw, t) * (1.0 - 1e-9) - 1e-12
    at = 0.0
    for b in blocks:
        if b.kind != "path" or b.cap < top:
            return False
        at += b.length
        if abs(at - end) <= 1e-9:
            return pw.v_end() <= b.vend * (1.0 + 1e-9) + 1e-12
        if at > end or b.vjunc < top:
            return False
    return False


def _solves(seed: int, n: int):
    """(profile, its target) of random position solves: from rest, accelerating, above the top speed, braking."""
    rng = random.Random(seed)
    out = []
    while len(out) < n:
        v0 = rng.choice([0.0, rng.uniform(0.0, 80.0), rng.uniform(60.0, 120.0)])
        a0 = rng.choice([0.0, rng.uniform(-2000.0, 2000.0)])
        dist = rng.uniform(0.05, 40.0)
        v1 = rng.choice([0.0, rng.uniform(0.0, 60.0)])
        pw = solve_position(0.0, v0, a0, dist, v1, rng.uniform(20.0, 100.0), rng.uniform(500.0, 3000.0),
                            rng.uniform(5e3, 1e5))
        if pw is not None and pw.duration > 0.0:
            out.append((pw, dist))
    return out


def _queue(rng: random.Random, dist: float, top: float) -> list[Block]:
    """Blocks whose junctions fall on `dist` (or miss it), caps and junction speeds around the profile's top speed."""
    cuts = sorted(rng.uniform(0.0, dist) for _ in range(rng.randint(0, 4)))
    ends = cuts + ([dist] if rng.random() < 0.8 else [dist * 1.01]) + [dist + rng.uniform(0.1, 5.0)]
    blocks, prev = [], 0.0
    for e in ends:
        b = Block(None, "path" if rng.random() < 0.95 else "dwell", None, e - prev, 200.0, 1000.0, 1e4, 1.0)
        b.cap = top * rng.choice([1.0, 1.1, 0.999999, 0.9])
        b.vjunc = top * rng.choice([1.0, 1.2, 0.99])
        b.vend = rng.choice([0.0, top, top * 0.5, 200.0])
        blocks.append(b)
        prev = e
    return blocks


def test_the_checks_are_c_functions_where_the_planner_is_compiled() -> None:
    for name in ("time_at", "peak_speed", "fits_queue", "later"):
        assert getattr(hold_stop, name) is getattr(profile, name)  # one implementation, the profile's
        if BUILD == "compiled":
            assert type(getattr(profile, name)).__name__ != "function", name


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_checks_answer_as_the_python_walks_did(seed: int) -> None:
    rng = random.Random(100 + seed)
    checked = kept = 0
    for pw, dist in _solves(seed, 60):
        for _ in range(4):
            x = rng.uniform(0.0, dist)
            t = profile.time_at(pw, x)
            assert t == time_at_before(pw, x)  # the same Newton steps: the same double
            lo = rng.uniform(0.0, t)
            assert profile.time_at(pw, x, lo) == time_at_before(pw, x, lo)
            assert profile.peak_speed(pw, t) == peak_speed_before(pw, t)
            top = peak_speed_before(pw, t)
            blocks = _queue(rng, dist, top)
            got = profile.fits_queue(pw, t, dist, blocks)
            assert got == fits_queue_before(pw, t, dist, blocks)
            kept += got
            later = profile.later(pw, t)
            t0, p, v, a, j = _phases(pw)
            assert later.duration == pw.duration - t and later.p_max == pw.p_max
            assert later._lists[1:] == ([x0 - t for x0 in t0], p, v, a, j)
            assert later.at(0.0) == pytest.approx(pw.at(t), rel=1e-9, abs=1e-9)  # its clock from t: the state there
            checked += 1
    assert checked == 240 and 0 < kept < checked  # both answers met
