"""The contour check's distances: each judged cycle's actual position to the nearest of its candidate
moves' polylines, worked out for all cycles at once (issue 17: the per-run loop built a polyline and
ran a distance call for each of a CAM program's ~4,000 runs of cycles, ≈ 0.5 s of a 1.2 s run).

The candidates of a run of cycles on line L are the moves of every line the trace shows within
`lag_cycles` before the run, and their neighbours (see `hil.checks.check_contour`). Here every
(cycle, segment) pair is listed once, point-major, and the distance of each pair is the same IEEE
operations on the same operands as the per-run loop made, so the minimum per cycle, and so the
check's value, cycle and line, are the per-run loop's bit for bit (tests/test_checks_contour.py).
"""

from __future__ import annotations

import math
import numpy as np

from nc.motion.path import Segment
from nc.moves import Move

FEED_KINDS = ("line", "arc", "thread")
PAIRS_PER_BATCH = 1 << 18  # (cycle, segment) pairs evaluated at once: ≈ 30 MB of temporaries
LONG_RUN = 64  # cycles from which a run is broadcast against its segments on its own


def _move_points(m: Move, axes: tuple[str, ...]) -> np.ndarray | None:
    """The points of one move's polyline (arcs to 0.1 µm chord error); None for a dwell."""
    if m.kind == "dwell":
        return None
    seg = Segment.of(m, axes)
    n = 1
    if seg.kind == "arc" and seg.radius > 0:
        step = math.sqrt(8 * 1e-4 / seg.radius)
        n = int(min(20_000, max(4, math.ceil(abs(seg.theta) * (1 + abs(m.turns)) / step))))
    return seg.points(np.linspace(0.0, seg.length, n + 1)) if seg.length > 0 else np.vstack([seg.start, seg.end])


def polyline(moves: list[Move], axes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Segment end points (A, B) approximating each move; arcs to 0.1 µm chord error."""
    key = tuple(axes)
    pts = [p for p in (_move_points(m, key) for m in moves) if p is not None]
    if not pts:
        return np.zeros((0, len(axes))), np.zeros((0, len(axes)))
    return np.vstack([p[:-1] for p in pts]), np.vstack([p[1:] for p in pts])


def _distance_to_boxes(p: np.ndarray, rapids: list[Move], axes: list[str]) -> np.ndarray:
    """Distance to the nearest axis-aligned box spanned by a rapid's start and end: with
    independent rapids each axis runs on its own, so the path is somewhere inside that box."""
    out = np.full(len(p), np.inf)
    for m in rapids:
        seg = Segment.of(m, tuple(axes))
        lo, hi = np.minimum(seg.start, seg.end), np.maximum(seg.start, seg.end)
        gap = np.maximum(np.maximum(lo - p, p - hi), 0.0)
        out = np.minimum(out, np.sqrt(np.einsum("ij,ij->i", gap, gap)))
    return out


def _ranges(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For groups of `counts` items laid end to end: each item's group and its index inside it."""
    owner = np.repeat(np.arange(len(counts)), counts)
    first = np.cumsum(counts) - counts
    return owner, np.arange(int(counts.sum())) - first[owner]


def _unique(x: np.ndarray) -> np.ndarray:
    """np.unique of an int array by sorting (numpy's hash-based unique costs more here). The keys come nearly
    sorted (run-major): the stable sort (timsort) takes them ≈ 7× faster than the default quicksort (the CAM
    program's checks: 39 → 6 ms), and sorted ints are the same whichever sort made them."""
    x = np.sort(x, kind="stable")
    return x[np.concatenate(([True], x[1:] != x[:-1]))] if len(x) else x


def _path_neighbours(moves: list[Move]) -> tuple[np.ndarray, np.ndarray]:
    """Each move's nearest move before and after it that has a path (-1 / len(moves) where none): a zero-length
    block (`X0. Y0.` where the tool stands) between two moves is no corner, the planner blends the moves around
    it, and that blend is judged against both of them (fuzz21, decision B105)."""
    n = len(moves)
    has_path = np.array([m.kind not in ("line", "rapid") or m.start != m.end for m in moves], dtype=bool)
    at = np.where(has_path, np.arange(n), -1)
    prev_path = np.concatenate(([-1], np.maximum.accumulate(at)[:-1])) if n else at
    at = np.where(has_path, np.arange(n), n)
    next_path = np.concatenate((np.minimum.accumulate(at[::-1])[::-1][1:], [n])) if n else at
    return prev_path, next_path


def _run_moves(line: np.ndarray, moves: list[Move], lag_cycles: int):
    """The runs of cycles on one line (a line met again later, in a loop, starts a new run), the judged
    ones (their line holds a feed move), and each judged run's candidate moves as (run, move) pairs,
    sorted: the moves of every line in the run's window and their neighbours. A run's window of lines
    is that of the runs from the one holding its first lagged cycle up to it."""
    n = len(line)
    starts = np.flatnonzero(np.diff(line, prepend=np.nan) != 0)
    ends = np.append(starts[1:], n)
    run_line = line[starts].astype(np.int64)
    lines = _unique(np.concatenate([run_line, np.array([m.line for m in moves], dtype=np.int64)]))
    run_lid = np.searchsorted(lines, run_line)
    # each line's candidates: its moves and their neighbours (a move's corner may be blended), as intervals of
    # move indices: [j - 1, j + 1] about each of its moves j, and j's nearest moves with a path
    mv_lid = np.searchsorted(lines, np.array([m.line for m in moves], dtype=np.int64))
    m_n = len(moves)
    idx = np.arange(m_n)
    prev_path, next_path = _path_neighbours(moves)
    iv_lo = np.concatenate([np.maximum(idx - 1, 0), prev_path, next_path])
    iv_hi = np.concatenate([np.minimum(idx + 1, m_n - 1), prev_path, next_path])
    ok = (iv_lo >= 0) & (iv_hi < m_n)
    l_lo, l_hi = _merge(np.tile(mv_lid, 3)[ok], iv_lo[ok], iv_hi[ok], m_n)
    li_line, l_lo, l_hi = l_lo // m_n, l_lo % m_n, l_hi % m_n
    li_count = np.bincount(li_line, minlength=len(lines))
    li_first = np.cumsum(li_count) - li_count
    feed_lids = _unique(mv_lid[[m.kind in FEED_KINDS for m in moves]])
    runs = np.flatnonzero(np.isin(run_lid, feed_lids))
    lo = np.searchsorted(starts, np.maximum(starts[runs] - lag_cycles, 0), side="right") - 1
    owner, k = _ranges(runs - lo + 1)  # (run, window run) -> (run, line) -> (run, interval) -> (run, move)
    rl = _unique(runs[owner] * len(lines) + run_lid[lo[owner] + k])
    r_of, l_of = np.divmod(rl, len(lines))
    owner, k = _ranges(li_count[l_of])
    iv = li_first[l_of[owner]] + k
    r_lo, r_hi = _merge(r_of[owner], l_lo[iv], l_hi[iv], m_n)  # each run's candidates: disjoint intervals
    owner, k = _ranges(r_hi - r_lo + 1)
    return (starts, ends, runs) + np.divmod(r_lo[owner] + k, m_n)


def _merge(group: np.ndarray, lo: np.ndarray, hi: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The union of each group's intervals [lo, hi] of 0 … size - 1, as disjoint intervals sorted by group and start,
    their ends given as group·size + lo and group·size + hi (a group's keys stay below the next group's)."""
    k_lo, k_hi = group * size + lo, group * size + hi
    if len(k_lo) and not np.all(k_lo[1:] >= k_lo[:-1]):  # (a CAM program's runs, lines and moves come in order)
        order = np.argsort(k_lo, kind="stable")
        k_lo, k_hi = k_lo[order], k_hi[order]
    reach = np.maximum.accumulate(k_hi)
    new = np.ones(len(k_lo), dtype=bool)
    new[1:] = k_lo[1:] > reach[:-1]  # past everything before it: a new interval
    at = np.flatnonzero(new)
    return k_lo[at], reach[np.append(at[1:] - 1, len(k_lo) - 1)] if len(at) else reach[:0]


def _segments(moves: list[Move], need: np.ndarray, axes: list[str]):
    """The polyline segments (A, B) of the moves `need`, with each move's segment count and first row.
    A line's points are Segment.points' at s = 0 and at its length, start + u·(end − start) with u = 0
    and 1 (length / length), spelt out for all lines at once; arcs through _move_points; a dwell has none."""
    key = tuple(axes)
    count = np.zeros(len(moves), dtype=np.int64)
    js = need.tolist()
    lines = [j for j in js if moves[j].kind != "dwell" and (moves[j].kind != "arc" or moves[j].center is None)]
    curves = {j: _move_points(moves[j], key) for j in js if moves[j].kind == "arc" and moves[j].center is not None}
    count[lines] = 1
    for j, p in curves.items():
        count[j] = len(p) - 1
    first = np.cumsum(count) - count
    a, b = np.empty((int(count.sum()), len(key))), np.empty((int(count.sum()), len(key)))
    if lines:
        # (flat, as float64: numpy converts an int coordinate as float() does)
        st = np.array([moves[j].start.get(x, 0.0) for j in lines for x in key], dtype=np.float64)
        en = np.array([moves[j].end.get(x, 0.0) for j in lines for x in key], dtype=np.float64)
        st, en = st.reshape(len(lines), len(key)), en.reshape(len(lines), len(key))
        a[first[lines]], b[first[lines]] = st + 0.0 * (en - st), st + 1.0 * (en - st)
    for j, p in curves.items():
        a[first[j]:first[j] + count[j]], b[first[j]:first[j] + count[j]] = p[:-1], p[1:]
    return a, b, count, first


def contour_distances(act: np.ndarray, line: np.ndarray, moves: list[Move], axes: list[str],
                      lag_cycles: int, independent_rapids: bool) -> np.ndarray:
    """Each cycle's distance from its candidate moves' path (0 on cycles whose line holds no feed move;
    inf where no candidate has a path). `act` is cycles × axes, `line` each cycle's program line."""
    n = len(line)
    dist = np.zeros(n)
    if n == 0 or not moves:
        return dist
    starts, ends, runs, r_of, m_of = _run_moves(line, moves, lag_cycles)
    # a judged cycle is as far as its nearest candidate: inf until one is found
    cyc_run = np.repeat(np.arange(len(starts)), ends - starts)
    judged_run = np.zeros(len(starts), dtype=bool)
    judged_run[runs] = True
    dist[judged_run[cyc_run]] = np.inf
    boxed = np.array([independent_rapids and m.kind == "rapid" for m in moves])
    if boxed[m_of].any():
        for r in _unique(r_of[boxed[m_of]]).tolist():
            r0, r1 = int(starts[r]), int(ends[r])
            rapids = [moves[j] for j in m_of[(r_of == r) & boxed[m_of]].tolist()]
            dist[r0:r1] = np.minimum(dist[r0:r1], _distance_to_boxes(act[r0:r1], rapids, axes))
        keep = ~boxed[m_of]
        r_of, m_of = r_of[keep], m_of[keep]
    a, b, seg_count, seg_first = _segments(moves, np.flatnonzero(np.bincount(m_of, minlength=len(moves))), axes)
    ab = b - a
    ab2 = np.einsum("ij,ij->i", ab, ab)
    ab2 = np.where(ab2 > 0, ab2, 1.0)
    # (run, segment) pairs, grouped by run
    owner, k = _ranges(seg_count[m_of])
    run_seg = seg_first[m_of[owner]] + k
    per_run = np.bincount(r_of[owner], minlength=len(starts))
    run_first = np.cumsum(per_run) - per_run
    # A long run (a lathe's arc, a long line) broadcasts its cycles against its segments as the
    # per-run loop did; the many short runs of a CAM program go as (cycle, segment) pairs at once.
    long_runs = runs[(ends[runs] - starts[runs] >= LONG_RUN) & (per_run[runs] > 0)].tolist()
    for r in long_runs:
        s = run_seg[run_first[r]:run_first[r] + per_run[r]]
        r0, r1 = int(starts[r]), int(ends[r])
        dist[r0:r1] = np.minimum(dist[r0:r1], _broadcast(act[r0:r1], a[s], ab[s], ab2[s]))
    cyc_segs = per_run[cyc_run]
    for r in long_runs:
        cyc_segs[starts[r]:ends[r]] = 0
    cycles = np.flatnonzero(cyc_segs)
    cum = np.cumsum(cyc_segs[cycles])
    # per axis, contiguous: each pair's operands are gathered once, as 1-D arrays (a 2-D row gather and einsum over
    # 3 axes cost numpy's general iterators; the CAM program's 283k pairs: 558 → ... M instructions, B139)
    act_k = [np.ascontiguousarray(act[:, j]) for j in range(act.shape[1])]
    a_k = [np.ascontiguousarray(a[:, j]) for j in range(a.shape[1])]
    ab_k = [np.ascontiguousarray(ab[:, j]) for j in range(ab.shape[1])]
    b0 = 0
    while b0 < len(cycles):  # batches of whole cycles, about PAIRS_PER_BATCH pairs each
        base = cum[b0 - 1] if b0 else 0
        b1 = max(b0 + 1, int(np.searchsorted(cum, base + PAIRS_PER_BATCH, side="right")))
        cyc = cycles[b0:b1]
        cnt = cyc_segs[cyc]
        first = np.cumsum(cnt) - cnt  # each cycle's first pair
        # a cycle's segments are its run's, run_seg[run_first[run]:][:per_run[run]], laid end to end
        s = run_seg[np.arange(int(cnt.sum())) + np.repeat(run_first[cyc_run[cyc]] - first, cnt)]
        ap = [np.repeat(x[cyc], cnt) - y[s] for x, y in zip(act_k, a_k)]
        abs_ = [y[s] for y in ab_k]
        u = _dot(ap, abs_, len(s))
        u /= ab2[s]
        np.clip(u, 0.0, 1.0, out=u)
        d = [p - u * q for p, q in zip(ap, abs_)]
        d2 = np.minimum.reduceat(_dot(d, d, len(s)), first)
        dist[cyc] = np.minimum(dist[cyc], np.sqrt(d2))
        b0 = b1
    return dist


def _dot(x: list[np.ndarray], y: list[np.ndarray], n: int) -> np.ndarray:
    """Σ x_k·y_k over the axes, pair by pair (n pairs), summed from the first axis on (as einsum's "pk,pk->p")."""
    if not x:
        return np.zeros(n)
    out = x[0] * y[0]
    for p, q in zip(x[1:], y[1:]):
        out += p * q
    return out


def _broadcast(p: np.ndarray, a: np.ndarray, ab: np.ndarray, ab2: np.ndarray, chunk: int = 512) -> np.ndarray:
    """Distance from each point (P × k) to the nearest of the segments a→a+ab (S × k), `chunk` points
    against all segments at a time."""
    out = np.empty(len(p))
    for s in range(0, len(p), chunk):
        q = p[s:s + chunk]
        ap = q[:, None, :] - a[None, :, :]
        u = np.clip(np.einsum("psk,sk->ps", ap, ab) / ab2, 0.0, 1.0)
        d = ap - u[..., None] * ab[None, :, :]
        out[s:s + chunk] = np.sqrt(np.min(np.einsum("psk,psk->ps", d, d), axis=1))
    return out
