"""Runs of short feed lines fitted as one curve while they stream into the planner (issue 18, decisions
motion 56-58).

Corner blends hold dense CAM programs at 1.15-1.22x LinuxCNC's time (decision 47); a quintic smoothing spline
fitted to the run within N1.053 (nc.motion.spline_runs, decisions 48-51) lets the feed hold. Here the planner
gets it: `Planner.push` hands each move to `RunFeed.push`, which holds back the moves of a run and lets
through what is fixed:

- a move is *eligible* when it is a G01 line at feed (not feed per revolution, G96, G31, G09/G61) shorter than
  `MAX_LEN`; an eligible move turning by more than `MAX_TURN` from the one before, or anything else, ends the run;
- a run is fitted only where it pays: where the tolerance's cap of one of its corners alone
  (`FilterCorners.corner_tolerance`, decision 37) is below `PAY` times the feed (chord circles, the issue-17 sine:
  no), or without the filter where the one-cycle corner is (`Limits.junction(raw=True)`'s jerk term);
- moves are held until `AHEAD` more are known beyond them (the fit is local: a span is fixed to 2e-7 mm 10
  segments ahead, decision 51), then a window of `BEHIND` fixed segments, the new ones and the ahead ones is
  fitted and the new ones go to the planner as spans (a `SplineSpan` each, one block a programmed line);
- the run ends, and everything held is fitted to its end and let through, on a move that is not eligible, when
  the channel says nothing follows (`Planner.closed`: program end, an M/S/T or preview barrier), at a feed
  hold or an interrupt, or when the channel reads nothing while the queue runs dry (single block, a macro
  taking cycles: `Planner.release_run`). A reset flushes it with the queue.

The held state (`Held`) is immutable and replaced on every change: a stretch's saved planner dict (hil.stretch_state)
then restores it with the rest. Deterministic; memory flat in program length (at most BATCH + AHEAD moves
held, BEHIND + 1 vertices kept).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115; this module since bench B136)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.motion.limits import MotionConfig

if cython.compiled:  # C's sqrt, the function math.sqrt calls (as nc.motion.lookahead, decision bench B148)
    from cython.cimports.libc.math import sqrt as _c_sqrt
else:
    _c_sqrt = math.sqrt
from nc.moves import Move

if TYPE_CHECKING:
    from nc.motion.fit_memo import FitMemo
    from nc.motion.spline_runs import SplineSpan



def load_fit() -> None:
    """Import what a window's fit runs: nc.motion.spline_runs, spline_fit and spline_join, fit_memo's keys, and
    scipy's fitting parts (spline_fit.load_scipy). Each is imported by the first window fitted, not with the planner,
    so a run whose program has no run to fit never loads them (bench decision B91); `hil`'s runner calls this before
    paced cycles or a real bus, where an import inside a cycle would overrun it."""
    import nc.motion.fit_memo  # noqa: F401
    import nc.motion.spline_join  # noqa: F401
    from nc.motion.spline_fit import load_scipy

    load_scipy()

AHEAD = 10  # segments known beyond a span before it is fixed (decision 51)
BEHIND = 10  # fixed segments a window refits in front of the new ones (so the joint is the same curve)
BATCH = 20  # new segments fixed per window (the fit's cost is per window: fewer windows, less refitting)
MAX_LEN = 5.0  # mm: a longer line ends the run (it needs no fit: its corners are few)
MAX_TURN = math.radians(60.0)  # a sharper vertex ends the run (and is slowed as an ordinary corner)
PAY = 2.0  # fit where a corner's own cap is below PAY x the feed
SHARP = 2.0 * math.sin(MAX_TURN / 2.0)  # |Δu| of a MAX_TURN vertex
SPLIT = 4  # spans a segment (each its own speed cap: a span's cap is its slowest point's)
PIN = 1e-6  # mm: a run's curve must meet its first and last vertex this closely (else it runs as lines)
FIT_TOL = 0.985  # of N1.053: the fit's own tolerance (the joints' shifts take < 3e-4 mm)


_dist = math.dist  # one name to look up (per push)


@cython.locals(p=list, q=list, p0=cython.double, p1=cython.double, p2=cython.double, q0=cython.double,
               q1=cython.double, q2=cython.double)
def _joined(p: list[float], q: list[float]) -> bool:
    """math.dist(p, q) <= 1e-9 (the same points: no call; compiled, C doubles compared)."""
    if len(p) == 3 and len(q) == 3:
        p0, p1, p2 = p[0], p[1], p[2]
        q0, q1, q2 = q[0], q[1], q[2]
        if p0 == q0 and p1 == q1 and p2 == q2:
            return True
    return _dist(p, q) <= 1e-9


@cython.locals(p=list, q=list, d0=cython.double, d1=cython.double, d2=cython.double, p0=cython.double,
               p1=cython.double, p2=cython.double, q0=cython.double, q1=cython.double, q2=cython.double)
def _step(p: list[float], q: list[float]) -> float:
    """|p - q| as a plain sum of squares (3 axes), else math.dist: the caller compares it with a margin."""
    if len(p) == 3 and len(q) == 3:
        p0, p1, p2 = p[0], p[1], p[2]
        q0, q1, q2 = q[0], q[1], q[2]
        d0 = p0 - q0
        d1 = p1 - q1
        d2 = p2 - q2
        return _c_sqrt(d0 * d0 + d1 * d1 + d2 * d2)  # (>= 0: no domain error to raise)
    return _dist(p, q)


@cython.ccall
@cython.returns(cython.double)
@cython.locals(p=dict)
def _get(p: dict[str, float], a: str) -> float:
    """float(p.get(a, 0.0)) of a dict (compiled: the dict's own get, a C double back)."""
    return float(p.get(a, 0.0))


@dataclass  # never changed in place, only replaced; compiled, an extension type (spline_feed.pxd: built on every push,
class Held:  # its generated __init__ as Python took half of `push`, bench B136), so no slots=True (Cython's takes none)
    """The moves a run holds back, the vertices behind them (already let through, for the next window) and
    whether the run is being fitted (False: a first move waits for the junction that decides)."""

    moves: tuple[Move, ...] = ()
    behind: tuple[tuple[float, ...], ...] = ()
    fitting: bool = False
    end: list[float] | None = None  # end point and direction of the last eligible move (held or let through):
    u: list[float] | None = None  # its junction with the next decides
    tail: SplineSpan | None = None  # the last span let through (a run's next window joins it)
    key: bytes = b""  # the key of the window that made `tail` (nc.motion.fit_memo)


NOTHING = Held()


class RunFeed:
    """The fitting rules for one planner's configuration (its state is the planner's `_held`).

    Compiled, an extension type (spline_feed.pxd, session 29): the planner calls `feed` and `line` as C calls and
    their fields are a struct's, not a dictionary's (bench B166)."""

    def __init__(self, cfg: MotionConfig, lim) -> None:
        self.tol = float(cfg.path_tolerance or 0.0)
        self.axes = cfg.axes
        self.blend = lim.blend  # FilterCorners, or None without the filter
        self.acc = cfg.share_tangential * float(lim.acc.min())
        self.corner_j = cfg.share_corner * float(min(lim._corner_j))
        self._pay: dict[float, float] = {}
        # The last eligible move's geometry (`geom`: move, start, end, length, unit direction): the planner's line
        # Segment of that move is built from it (the same floats as Segment.of's own, issue 17)
        self._gm = None
        # Windows worked out ahead by another process (hil/fit_ahead.py, decision bench B86), or None
        self.memo: FitMemo | None = None
        # What the last `feed` let through, None where it was the move alone as a line (its geometry in `geom`)
        self.out: list[tuple[Move, SplineSpan | None]] | None = None
        # A span was let through once: only then may the planner's last block be a curve a line must start on
        self.spans = False

    @property
    def geom(self) -> tuple[Move, list[float], list[float], float, list[float]] | None:
        """(move, start, end, length, unit direction) of the last eligible move `line` saw, or None."""
        return None if self._gm is None else (self._gm, self._ga, self._gb, self._gn, self._gu)

    @staticmethod
    def enabled(cfg: MotionConfig) -> bool:
        return cfg.fit_runs and (cfg.path_tolerance or 0.0) > 0.0

    # ---- the rules (plain floats: they run on every push, issue 17) ---------------------------------
    def line(self, mv: Move) -> tuple[list[float], list[float], list[float]] | None:
        """(start point, end point, unit direction) of an eligible move, else None (kept in `geom`)."""
        return (self._ga, self._gb, self._gu) if self._line(mv) else None

    @cython.locals(a0=cython.double, a1=cython.double, a2=cython.double, b0=cython.double, b1=cython.double,
                   b2=cython.double, n=cython.double)
    def _line(self, mv: Move) -> bool:
        """`line`: True, and the geometry in `geom`'s fields, where mv is eligible (compiled: no tuple made)."""
        if mv.kind != "line" or mv.per_rev or mv.exact_stop or mv.css is not None or not mv.feed \
                or "G31" in mv.tags:
            return False
        ax, ms, me = self.axes, mv.start, mv.end
        if len(ax) == 3 and type(ms) is dict and type(me) is dict:  # spelt out (once per push); float(): as
            x, y, z = ax  # Segment.of (compiled: the same double); dict.get, typed (bench B156)
            a0, a1, a2 = _get(ms, x), _get(ms, y), _get(ms, z)
            b0, b1, b2 = _get(me, x), _get(me, y), _get(me, z)
            a = [a0, a1, a2]
            b = [b0, b1, b2]
            n = _dist(a, b)
            if not 1e-6 < n <= MAX_LEN:
                return False
            u = [(b0 - a0) / n, (b1 - a1) / n, (b2 - a2) / n]
        else:
            a = [float(ms.get(x, 0.0)) for x in ax]
            b = [float(me.get(x, 0.0)) for x in ax]
            n = math.dist(a, b)
            if not 1e-6 < n <= MAX_LEN:
                return False
            u = [(q - p) / n for p, q in zip(a, b)]
        self._gm = mv
        self._ga = a
        self._gb = b
        self._gn = n
        self._gu = u
        return True

    def _vec(self, p: dict[str, float]) -> np.ndarray:
        return np.array([float(p.get(a, 0.0)) for a in self.axes])

    def _pay_step(self, feed_mm_min: float) -> float:
        """The least |Δu| whose corner pays at this feed (cached a feed): the tolerance's cap of one corner
        (decreasing in |Δu|) below PAY × the feed, or without the filter the one-cycle corner's."""
        thr = self._pay.get(feed_mm_min)
        if thr is None:
            f = PAY * feed_mm_min / 60.0
            if self.blend is None:
                thr = self.corner_j / max(f, 1e-12)
            elif self.blend.corner_tolerance(2.0, self.acc) >= f:
                thr = math.inf
            else:
                lo, hi = 0.0, 2.0
                for _ in range(40):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (lo, mid) if self.blend.corner_tolerance(mid, self.acc) < f else (mid, hi)
                thr = hi
            self._pay[feed_mm_min] = thr
        return thr

    # ---- the stream ----------------------------------------------------------------------------
    def push(self, st: Held, mv: Move) -> tuple[Held, list[tuple[Move, SplineSpan | None]]]:
        """The held state after mv, and the moves let through (with their span, None: as a line)."""
        h = self.feed(st, mv)
        out = self.out
        return h, ([(mv, None)] if out is None else out)

    @cython.locals(st=Held, h=Held, du=cython.double, thr=cython.double, exact=cython.bint)
    def feed(self, st: Held, mv: Move) -> Held:
        """`push` as the planner calls it: the held state after mv; what it let through in `out`, None where that
        is mv alone, as a line (the common case on programs not fitted: no list, no tuple made)."""
        self.out = None
        if not self._line(mv):
            st, out = self.release(st)
            self.out = out + [(mv, None)]
            return st
        a, end, u = self._ga, self._gb, self._gu
        sharp = True  # no junction with the move before, or a sharp corner: the run ends at it
        exact = False
        du = 0.0
        if st.end is not None and _joined(st.end, a):
            # |Δu|: the plain sum of squares where it is clearly below the sharp corner's (it decides nothing
            # there: math.dist's compensated sum differs from it by far less than the margin), else math.dist
            du = _step(u, st.u)
            if not du * (1.0 + 1e-9) < SHARP:
                du = _dist(u, st.u)
                exact = True
            sharp = du > SHARP
        if sharp:
            st, out = self.release(st)
            self.out = out
            return Held(moves=(mv,), end=end, u=u)  # a first move: the next junction decides
        if st.fitting:
            st = replace(st, moves=st.moves + (mv,), end=end, u=u)
            if len(st.moves) >= BATCH + AHEAD:
                st, self.out = self._fix(st, BATCH)
                return st
            self.out = []
            return st
        feed = mv.feed or 0.0
        got = self._pay.get(feed)  # _pay_step's cache read here (once per push)
        thr = got if got is not None else self._pay_step(feed)
        if not exact and not du * (1.0 + 1e-9) < thr:  # near the threshold: as math.dist has it
            du = _dist(u, st.u)
        if du > thr:
            self.out = []
            return Held(st.moves + (mv,), (), True, end=end, u=u)
        if not st.moves:  # the common case on programs not fitted: Held((), (), False, end, u) without its
            h = Held.__new__(Held)  # __init__'s arguments to parse (compiled: the type's slot, bench B156)
            h.moves = ()
            h.behind = ()
            h.fitting = False
            h.end = end
            h.u = u
            h.tail = None
            h.key = b""
            return h
        self.out = [(m, None) for m in st.moves] + [(mv, None)]
        return Held(end=end, u=u)

    def release(self, st: Held) -> tuple[Held, list[tuple[Move, SplineSpan | None]]]:
        """Everything held let through: the run fitted to its end."""
        if not st.moves:
            return NOTHING, []
        if st.fitting:
            return self._fix(st, len(st.moves))
        return NOTHING, [(m, None) for m in st.moves]

    def _fix(self, st: Held, n: int) -> tuple[Held, list[tuple[Move, SplineSpan | None]]]:
        """Fit the window (the vertices behind, the held moves) and let the first n held moves through as spans."""
        moves = st.moves
        verts = [np.array(v) for v in st.behind] or [self._vec(moves[0].start)]
        verts += [self._vec(m.end) for m in moves]
        pts = np.array(verts)
        first = len(verts) - 1 - len(moves)  # segments behind
        end = n == len(moves)
        memo, key = self.memo, b""
        if memo is None:
            cut = self._solve(st, pts, first, n, end)
        else:
            from nc.motion.fit_memo import MISSING, window_key

            key = window_key(st.key if st.tail is not None else b"", pts, first, n, end)
            cut = memo.get(key)
            if cut is MISSING:
                cut = self._solve(st, pts, first, n, end)
                memo.put(key, cut)
        if cut is None:  # no fit within the tolerance, or the joint left it: as lines, the run ends
            return NOTHING, [(m, None) for m in moves]
        self.spans = True  # (once: a line after a span may have to start on its curve, FittedRuns._from_curve)
        if end:  # the run ends on its vertex exactly (a plan's end takes seg.end)
            cut[-1].end = pts[-1].copy()
        out = [(m, sp) for i, m in enumerate(moves[:n]) for sp in cut[i * SPLIT:(i + 1) * SPLIT]]
        if end:
            return NOTHING, out
        keep = pts[max(0, first + n - BEHIND):first + n + 1]
        return Held(moves[n:], tuple(tuple(v.tolist()) for v in keep), True, st.end, st.u, cut[-1], key), out

    def _solve(self, st: Held, pts: np.ndarray, first: int, n: int, end: bool) -> list[SplineSpan] | None:
        """The window's spans, joined onto the run's last span, or None where the fit or the joint misses
        N1.053. A function of its inputs alone (nc.motion.fit_memo keys them)."""
        cut = self._spans(pts, first, n, end)
        if cut is None:
            return None
        if st.tail is not None:
            from nc.motion.spline_join import join

            cut = join(st.tail, cut)
            if not self._within(cut, pts):  # the joint's shift took the curve off the tolerance
                return None
        return cut

    def _within(self, cut: list[SplineSpan], pts: np.ndarray) -> bool:
        """The shifted spans (JoinedSpan) within N1.053 of the window's polyline (every 0.002 mm)."""
        from nc.motion.spline_join import JoinedSpan

        a, d = pts[:-1], np.diff(pts, axis=0)
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-30)
        for sp in cut:
            if not isinstance(sp, JoinedSpan):
                break
            p = sp.points(np.linspace(0.0, sp.length, max(2, int(sp.length / 0.002) + 1)))
            t = np.clip(np.einsum("pij,ij->pi", p[:, None, :] - a[None], d) / dd, 0.0, 1.0)
            dist = np.linalg.norm(p[:, None, :] - (a[None] + t[:, :, None] * d[None]), axis=2).min(axis=1)
            if dist.max() > self.tol:
                return False
        return True

    def _spans(self, pts: np.ndarray, first: int, n: int, end: bool) -> list[SplineSpan] | None:
        if len(pts) < 3:
            return None
        from nc.motion.spline_runs import FitError, fit_run, spans

        try:
            spl, cum = fit_run(pts, FIT_TOL * self.tol)
        except FitError:
            return None
        # SPLIT spans a segment, each with its own cap; spans() cuts its last span to the curve's end: one
        # more (dropped) unless the run ends here
        ends = np.stack([sp(np.array([0.0, cum[-1]])) for sp in spl], axis=1)
        if (first == 0 and np.abs(ends[0] - pts[0]).max() > PIN) or (end and np.abs(ends[1] - pts[-1]).max() > PIN):
            return None  # the pinned ends missed (the weights grown near them outweigh the pin): a step at λ = 0
        sub = cum[first:] if end else cum[first:first + n + 2]
        at = (sub[:-1, None] + np.diff(sub)[:, None] * (np.arange(SPLIT) / SPLIT)[None, :]).ravel()
        # (spans() cuts from the curve's start: the segments behind are cut too and dropped)
        return spans(spl, np.concatenate([cum[:first], at, sub[-1:]]), self.axes)[first:first + n * SPLIT]
