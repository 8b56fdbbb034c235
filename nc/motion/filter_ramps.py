"""Starts, speed-ups and stops the position filter shapes (issue 18, decision motion 52). A mixin of `Planner`.

Under the two moving averages of N1.036/N1.037 a velocity step Δv of the raw interpolation leaves the
filter as an acceleration of at most Δv/T1 and a jerk of at most Δv/(T1·T2) per axis where the axis
velocity changes monotonically over the window (smoothing.py). At F3000 (50 mm/s) on a 16 + 16 ms filter
that is 3 125 mm/s² and 195 000 mm/s³: within the bench's axis limits without any ramp of the planner's
own, whose jerk-limited ramps were paid on top of the filter's lag and settling.

- A *filter start*: from zero acceleration below the block's cap (from rest, or at the speed a slow
  junction was crossed at, after waiting a few cycles there), a ramp to the cap with limits far above the
  axis limits, then a cruise at the cap while the filter still mixes the ramp into its output, as one
  plan across blocks that all allow the cap.
- A *filter stop*: to the end of the queue when nothing more comes before it (`Planner.closed`), one
  solve with those limits.

Each is taken only where it is checked safe: the candidate is sampled (a stop to rest), run through a
copy of the filter from its present state, and every output cycle is checked as `hil check --limits`
checks it (finite-difference velocity, acceleration and jerk per axis, joined to the outputs already
handed out) and against N1.053 (distance to the programmed path, and to the corners it passes).
Otherwise the planner plans as before. What was checked is what runs: a re-plan (hold, reset,
override) waits until it is over, and a stop's re-solves at block boundaries keep its limits.
"""

from __future__ import annotations

import math

import numpy as np

from nc.motion.block import Block
from nc.motion.lookahead import MARGIN, change_distance
from nc.motion.plan_state import _Plan
from nc.motion.planner_cruise import least_limits, plain_rest, tail_speed
from nc.motion.profile import Piecewise, solve_position, solve_velocity
from nc.motion.shares import MAX_FACTOR
from nc.motion.smoothing import PositionFilter

# Raw braking limits tried, as multiples of the full path acceleration (the tangential limit over its
# share); the jerk is that acceleration reached in two cycles. The first whose output passes is kept.
STOP_SCALES = (16.0, 4.0)
HISTORY = 64  # finished segments kept for the deviation check (the outputs lag the raw path by D cycles)
# A vertex whose tangent turns more than this is a corner: N1.053 bounds how far the output stays from it (below,
# the polyline distance alone: between a chord polygon's vertices it differs by less than 0.1 % of N1.053)
CORNER = 0.1
MAX_ROWS = 400  # raw cycles a checked plan may span (the check samples all of them)
# Cycles a start from a slow junction must gain over the planner's own ramp to be taken: its
# plan is cut at every block (no cruise chain, decision 44), which costs a dense program its stretches
GAIN = 3.0


def seg_history(h: tuple) -> list:
    """The last HISTORY finished segments of the chain `Planner._seg_hist` (`Planner._finish_block` adds one a block:
    a 3-tuple a block where a tuple of the last 64 was copied twice a block, ~2k instructions, bench B168), oldest
    first."""
    out = []
    while h and len(out) < HISTORY:
        out.append(h[0])
        h = h[1]
    out.reverse()
    return out


def polyline_distance(q: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance of every row of q to the polyline through pts.

    Summed over the axes one (rows, segments) array at a time: numpy's sum over a last axis of three, ((0 + x0) + x1)
    + x2, spelt out, so the same doubles (tests/test_filter_ramps31.py), where its (rows, segments, 3) arrays ran
    numpy's loops three elements at a time (≈ 10k instructions a row, a CAM program's final stop check: session 31,
    decision bench B185)."""
    a, d = pts[:-1], np.diff(pts, axis=0)
    l2 = np.maximum((d * d).sum(1), 1e-30)
    dot = np.zeros((len(q), len(a)))
    for k in range(q.shape[1]):
        dot = dot + (q[:, k, None] - a[None, :, k]) * d[None, :, k]
    t = np.clip(dot / l2, 0.0, 1.0)
    e2 = np.zeros((len(q), len(a)))
    for k in range(q.shape[1]):
        e2 = e2 + ((a[None, :, k] + t * d[None, :, k]) - q[:, k, None]) ** 2
    return np.sqrt(e2).min(1)


CRAWL = tuple(range(0, 17, 2))  # cycles a start from a slow junction may wait at its speed (tried in turn)


def _piece(v: float, dur: float) -> Piecewise:
    """`dur` seconds at the constant speed v, from position 0."""
    z = np.zeros((1, 2))
    return Piecewise(np.array([[0.0, dur]]), np.array([[0.0, v * dur]]), np.full((1, 2), v), z, z.copy(), dur, v * dur)


def _chain(s: float, parts: list[Piecewise]) -> Piecewise:
    """The profiles one after the other from position s (each begins at the speed the one before ends
    at, with zero acceleration): one profile, as ruckig's are stored."""
    cols: list[list[float]] = [[], [], [], [], []]
    t_off, p_off = 0.0, s
    for i, pw in enumerate(parts):
        if pw.duration <= 0.0:
            continue
        p0 = float(pw.p[0, 0])
        last = i + 1 == len(parts)
        for c in range(pw.t0.shape[1] if last else pw.t0.shape[1] - 1):
            if not math.isfinite(pw.t0[0, c]):
                break
            for col, x in zip(cols, (pw.t0[0, c] + t_off, pw.p[0, c] - p0 + p_off, pw.v[0, c], pw.a[0, c], pw.j[0, c])):
                col.append(float(x))
        p_off += float(pw.sample(np.array([pw.duration]))[0][0]) - p0
        t_off += pw.duration
    return Piecewise(*(np.array([c]) for c in cols), t_off, p_off)


def _loss(v0: float, v1: float, a: float, j: float) -> float:
    """Time a jerk-limited speed change v0 -> v1 (zero acceleration at both ends) loses against covering
    its path at the higher speed."""
    dv = abs(v1 - v0)
    t = 2.0 * math.sqrt(dv / j) if dv * j <= a * a else dv / a + a / j
    return t - change_distance(v0, v1, a, j) / max(v0, v1, 1e-9)


def _twin(f: PositionFilter) -> PositionFilter:
    """An independent copy of the filter's state, as copy.deepcopy gives it at a fraction of its cost (2.6 ms of
    the CAM program's final stop check was the deepcopy): PositionFilter.copy copies its buffer of doubles."""
    return f.copy()


def _solve(fn, *args) -> Piecewise | None:
    """A ruckig solve with the large limits, None where ruckig refuses them (plan as before)."""
    try:
        return fn(*args)
    except Exception:  # ruckig.RuckigError, or the NcAlarm solve_velocity raises
        return None


class FilterStops:
    """Methods of `nc.motion.planner.Planner` (its state is the planner's own: see that module's doc)."""

    def _init_filter_stops(self) -> None:
        self._fs_tail: Block | None = None  # the queue's last block while a filter stop runs to it
        self._fs_limits = (0.0, 0.0, 0.0)  # its acceleration, jerk and top speed
        # the finished segments as a chain (segment, the chain before it, its length), () before the first: rebound,
        # never changed in place (hil.stretch_state copies the planner shallowly); `seg_history` reads the last HISTORY
        self._seg_hist: tuple = ()
        self._fr_plan: _Plan | None = None  # the filter start being executed

    def _filter_ramp(self, b: Block, s: float, v: float, a: float, cap: float, t0: float) -> _Plan | None:
        """A filter stop or start from (s, v, a) in blocks[0] = b, or None (plan as before)."""
        blocks = self.blocks
        if self._fs_tail is not None and self._fs_tail is not blocks[-1]:
            self._fs_tail = None
        if self._fs_tail is not None:
            return self._filter_stop(s, v, a, cap, t0, committed=True)
        if self.held or cap <= 1e-9 or not self._plain(b):
            return None
        if abs(a) < 1e-12 and (fr := self._filter_start(b, s, max(v, 0.0), cap, t0)) is not None:
            return fr
        self.lookahead()  # the junction speeds as the ordinary solve reads them
        T = self.cfg.cycle
        rest = self._stop_rest(s)
        if rest is None:
            return None
        blocks = self.blocks
        lo_a, lo_j = least_limits(blocks)  # min(x.a for x in blocks), min(x.j for x in blocks): compiled (bench B168)
        brake = change_distance(v, 0.0, MARGIN * lo_a, MARGIN * lo_j)
        if rest <= brake + 2.0 * v * T:
            return self._filter_stop(s, v, a, cap, t0) if rest < v * (MAX_ROWS - 2 * self.filter.span) * T else None
        if abs(a) < 1e-12 and abs(v - cap) <= 1e-9 * cap and self._tail_speed(cap) >= v * (1.0 - 1e-9):
            return self._cruise_to(s, v, rest - brake - v * T, t0)
        return None

    def _cruise_to(self, s: float, v: float, d: float, t0: float) -> _Plan:
        """Cruising at the cap to a stop the ordinary braking would begin d ahead: cruise d (one solve may
        span the whole block), then try the filter stop there."""
        return _Plan("ramp", _chain(s, [_piece(v, max(d, 0.0) / v)]), max(d, 0.0) / v, t0, 0.0, v)

    def _deferred(self) -> bool:
        """A re-plan (hold, reset, override) waits while a filter stop runs or a filter start's output
        is being shaped: what was checked is what runs (at most the span of the filter plus a few cycles)."""
        return (self._fs_tail is not None and bool(self.blocks) and self._fs_tail is self.blocks[-1]) \
            or (self._fr_plan is not None and self._fr_plan is self.plan)

    def _plain(self, b: Block) -> bool:
        mv = b.move
        # Under an NC5 acc. and dec. or S-curve time the move ramps at its own limits, which the filter only
        # smooths, not as a velocity step the filter shapes (decision motion 94)
        return b.kind == "path" and not mv.per_rev and mv.css is None and "G31" not in mv.tags \
            and not (self.lim.rapid_whole if b.rapid else self.lim.cut_on)

    def _filter_start(self, b: Block, s: float, v0: float, cap: float, t0: float) -> _Plan | None:
        """From v0 at zero acceleration (rest, or the speed a slow junction was crossed at): a ramp to
        b's cap with the stop limits, then a cruise at the cap for as long as the filter mixes the ramp into
        its output (span + 4 cycles), across blocks whose caps and junctions allow the cap all the way, with
        room left after it to brake with the ordinary limits to anything slower ahead; taken when its
        filtered output is checked within the limits and the tolerance."""
        f = self.filter
        if f is None or not self.cfg.path_tolerance or v0 >= cap * (1.0 - 1e-9):
            return None
        T = self.cfg.cycle
        share = self.cfg.share_tangential
        if cap - v0 > b.a / share * f.n1 * T or cap - v0 > b.j / share * f.n1 * f.n2 * T * T:
            return None  # the filter turns that step into more than the axes allow (module doc)
        start = b.s_end - b.length
        if self._zones is not None and self._zones.near(start + s - 1.0, start + s + 2.0 * cap * (f.span + 8) * T):
            return None
        self.lookahead()
        ra, rj = self._stop_limits(STOP_SCALES[0], [b])
        # The first wait's test (k = 0, below) asked before the solve and the cruise it needs: most starts end there
        # (114 of 260 on the CAM program, a ruckig solve each, bench B168); only within finite positive limits, where
        # `_loss` cannot raise (otherwise as before: the solve first)
        if 0.0 < ra < math.inf and 0.0 < rj < math.inf and 0.0 < b.a < math.inf and 0.0 < b.j < math.inf \
                and 0 * T * (1.0 - v0 / cap) + _loss(v0, cap, ra, rj) + GAIN * T >= _loss(v0, cap, b.a, MAX_FACTOR * b.j):
            return None
        keep = _piece(cap, (f.span + 4) * T)
        ramp = _solve(solve_velocity, 0.0, v0, 0.0, cap, ra, rj)
        if ramp is None:
            return None
        # From a slow junction the ramp may have to wait: the filter still mixes the junction's corner into
        # its output, and a faster path after it moves the output off the path (checked). Waiting costs
        # about a cycle a cycle; the ordinary ramp (v0 -> cap at the tangential jerk) costs more than CRAWL.
        best = _loss(v0, cap, b.a, MAX_FACTOR * b.j)  # the ordinary ramp at its best (decision 39)
        for k in CRAWL if v0 > 0.0 else (0,):
            if k * T * (1.0 - v0 / cap) + _loss(v0, cap, ra, rj) + GAIN * T >= best:
                return None  # waiting longer costs more than the planner's own ramp
            pw = _chain(s, [_piece(v0, k * T), ramp, keep])
            if not self._room_after(s, pw.p_max, cap):
                return None
            if self._output_ok(pw, t0, rest=False):
                self._fr_plan = _Plan("ramp", pw, pw.duration, t0, 0.0, cap)
                return self._fr_plan
        return None

    def _room_after(self, s: float, end: float, cap: float) -> bool:
        """Every block on [s, end] (path lengths from blocks[0]'s start) is plain and allows `cap`, its
        junctions too, and after `end` the ordinary limits can brake from `cap` to every slower junction,
        block cap and the end of the queue."""
        pos, lo_a, lo_j = 0.0, math.inf, math.inf
        blocks = self.blocks
        for k, x in enumerate(blocks):
            if pos + x.length <= s:  # behind the plan's start
                pos += x.length
                if k + 1 == len(blocks):
                    return False
                continue
            if pos >= end:  # a block starting beyond the plan: its cap is a speed to brake to
                if x.cap < cap and pos - end < change_distance(cap, x.cap, MARGIN * lo_a, MARGIN * lo_j):
                    return False
            elif not self._plain(x) or x.cap < cap * (1.0 - 1e-9):
                return False
            lo_a, lo_j = min(lo_a, x.a), min(lo_j, x.j)
            pos += x.length
            stop = change_distance(cap, 0.0, MARGIN * lo_a, MARGIN * lo_j)
            if k + 1 == len(blocks):
                return pos - end >= stop  # the queue ends at rest
            vj = x.vjunc
            if pos <= end:
                if vj < cap * (1.0 - 1e-9):
                    return False
            elif vj < cap and pos - end < change_distance(cap, vj, MARGIN * lo_a, MARGIN * lo_j):
                return False
            if pos - end >= stop:
                return True
        return False

    def _filter_stop(self, s: float, v: float, a: float, cap: float, t0: float,
                     committed: bool = False) -> _Plan | None:
        """A filter stop to the end of the queue (`committed`: the one already taken, solved again)."""
        blocks = self.blocks
        dist = sum(b.length for b in blocks)
        vmax = self._tail_speed(cap)
        if committed:  # the checked profile's top speed (a hold or an override waits for the stop)
            vmax = self._fs_limits[2]
        if vmax <= 1e-9:
            return None
        tries = [self._fs_limits[:2]] if committed else [self._stop_limits(sc, blocks) for sc in STOP_SCALES]
        for ra, rj in tries:
            pw = _solve(solve_position, s, v, a, dist, 0.0, vmax, ra, rj)
            if pw is None or pw.p_max > dist + 1e-7 or pw.v_min() < -1e-7:
                continue
            if committed or self._output_ok(pw, t0, rest=True):
                self._fs_tail, self._fs_limits = blocks[-1], (ra, rj, vmax)
                return _Plan("path", pw, pw.duration, t0, target=dist, queued=self._pushes)
        return None

    def _stop_limits(self, scale: float, blocks) -> tuple[float, float]:
        acc = least_limits(blocks)[0] / self.cfg.share_tangential * scale  # min(b.a for b in blocks)
        return acc, acc / (2.0 * self.cfg.cycle)

    def _stop_rest(self, s: float) -> float | None:
        """The path left to the end of the queue when the rest of the motion is all known and plain
        path (no exact stop, feed per revolution, CSS, skip, thread, dwell in it, λ = 1 near it);
        None otherwise."""
        blocks = self.blocks
        if not self.closed or self._stopping or not self.cfg.path_tolerance:
            return None
        if self._zones is not None and self._zones.near(blocks[0].s_end - blocks[0].length - 1.0, blocks[-1].s_end):
            return None  # λ < 1 somewhere near: the raw path is not all filtered there
        # for each block: not self._plain(b) or (not the last and b.vjunc <= 1e-9) -> None; else rest += b.length
        # (compiled, bench B168)
        lim = self.lim
        return plain_rest(blocks, s, lim.rapid_whole, lim.cut_on)

    def _tail_speed(self, cap: float) -> float:
        """The least cap and junction speed from blocks[0] to the end of the queue."""
        return tail_speed(self.blocks, cap)  # compiled (bench B168)

    def _output_ok(self, pw: Piecewise, t0: float, rest: bool) -> bool:
        """The candidate's filtered output, every cycle of it (`rest`: and on until the filter settles),
        within the axis limits (with the look-ahead's MARGIN) and N1.053 of the programmed path."""
        T = self.cfg.cycle
        n = int(math.floor((pw.duration - t0) / T + 1e-9)) + 1
        if n <= 0 or n > MAX_ROWS:
            return False
        t = t0 + T * np.arange(n)
        sp = pw.sample(t)[0]
        raw = self._path_points(sp)
        if rest:
            raw = np.vstack([raw, self._path_points(pw.sample(np.array([pw.duration]))[0])])
            raw = np.vstack([raw, np.repeat(raw[-1:], self.filter.span + 1, axis=0)])
        out = _twin(self.filter).push_many(raw)
        p = np.vstack([self.filter.recent, out] + ([np.repeat(out[-1:], 3, axis=0)] if rest else []))
        vel = np.diff(p, axis=0) / T
        acc = np.diff(vel, axis=0) / T
        jerk = np.diff(acc, axis=0) / T
        lim = self.lim
        if np.any(np.abs(vel) > lim.v * MARGIN) or np.any(np.abs(acc[1:]) > lim.acc * MARGIN) \
                or np.any(np.abs(jerk) > lim.jerk * MARGIN):
            return False
        tol = self.cfg.path_tolerance
        pts, corners = self._path_vertices(float(sp[-1]))
        if float(polyline_distance(out, pts).max()) > tol:
            return False
        # N1.053 at a corner is also how close the output comes to its vertex (decision 35 charges that):
        # for every vertex the output passes closest within these cycles (not at their first or last)
        if not len(corners):
            return True
        d = np.sqrt(((out[:, None, :] - corners[None]) ** 2).sum(2))
        k = d.argmin(axis=0)
        inside = (k > 0) & (k < len(out) - 1)
        return not np.any(d.min(axis=0)[inside] > tol)

    def _path_points(self, sp: np.ndarray) -> np.ndarray:
        """Positions at path lengths sp measured from blocks[0]'s start, over the queue."""
        ends = np.cumsum([b.length for b in self.blocks])
        idx = np.minimum(np.searchsorted(ends, sp, side="left"), len(ends) - 1)
        out = np.empty((len(sp), len(self.axes)))
        order = np.sort(idx)  # np.unique's values (np.unique imports numpy.ma on first use: ≈ 9 ms of `hil run`)
        for k in order[np.concatenate(([True], order[1:] != order[:-1]))]:
            m = idx == k
            b = self.blocks[int(k)]
            base = ends[k] - b.length
            out[m] = b.seg.points(np.clip(sp[m] - base, 0.0, b.length))
        return out

    def _path_vertices(self, upto: float) -> tuple[np.ndarray, np.ndarray]:
        """The programmed path behind (the last HISTORY segments) and ahead up to path length `upto` from
        blocks[0]'s start, as a fine polyline, and its vertices (where one segment meets the next)."""
        segs = seg_history(self._seg_hist)
        pos = 0.0
        for b in self.blocks:
            if pos > upto:
                break
            segs.append(b.seg)
            pos += b.length
        segs = [seg for seg in segs if seg is not None]
        pieces, rows = [], []  # consecutive lines' points as plain rows (the same values), one array each run
        for seg in segs:
            if seg.kind == "line":
                rows += [seg.start.tolist(), seg.end.tolist()]
                continue
            if rows:
                pieces.append(np.array(rows))
                rows = []
            m = max(2, int(math.ceil(seg.length / 0.005)) + 1)
            pieces.append(seg.points(np.linspace(0.0, seg.length, m)))
        if rows:
            pieces.append(np.array(rows))
        return np.vstack(pieces), _corners(segs, len(self.axes))


def _corners(segs: list, n_axes: int) -> np.ndarray:
    """The starts of the segments whose tangent turns more than CORNER from the one before, as the per-pair
    `np.linalg.norm(seg.unit_tangent(False) - prev.unit_tangent(True)) > CORNER` tells (issue 17: that loop was
    ~10 us a segment over the 64 behind and the queue). A line's tangent is (end - start) / length element by
    element as unit_tangent computes it; the norms are taken for all pairs at once and only one within 1e-9 of
    CORNER (where the summation order could tell otherwise) is measured again as before."""
    if len(segs) < 2:
        return np.empty((0, n_axes))
    starts = np.array([seg.start for seg in segs])
    d = np.array([seg.end for seg in segs]) - starts
    lengths = np.array([seg.length for seg in segs])
    live = lengths > 0.0
    d[live] /= lengths[live, None]
    d[~live] = 0.0
    t_in, t_out = d, d.copy()
    for k, seg in enumerate(segs):
        if seg.kind != "line" and seg.length > 0.0:
            t_in[k], t_out[k] = seg.unit_tangent(False), seg.unit_tangent(True)
    turn = t_in[1:] - t_out[:-1]
    norm = np.sqrt((turn * turn).sum(1))
    near = np.flatnonzero(np.abs(norm - CORNER) <= 1e-9)
    sharp = norm > CORNER
    for k in near:
        sharp[k] = np.linalg.norm(turn[k]) > CORNER
    return starts[1:][sharp].reshape(-1, n_axes)
