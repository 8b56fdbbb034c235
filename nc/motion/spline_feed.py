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
from dataclasses import dataclass, field, fields, replace

import numpy as np

from nc.motion.limits import MotionConfig
from nc.motion.spline_runs import FitError, SplineSpan, fit_run, spans
from nc.moves import Move

AHEAD = 10  # segments known beyond a span before it is fixed (decision 51)
BEHIND = 10  # fixed segments a window refits in front of the new ones (so the joint is the same curve)
BATCH = 20  # new segments fixed per window (the fit's cost is per window: fewer windows, less refitting)
MAX_LEN = 5.0  # mm: a longer line ends the run (it needs no fit: its corners are few)
MAX_TURN = math.radians(60.0)  # a sharper vertex ends the run (and is slowed as an ordinary corner)
PAY = 2.0  # fit where a corner's own cap is below PAY x the feed
SPLIT = 4  # spans a segment (each its own speed cap: a span's cap is its slowest point's)
JOIN = 2.0  # mm of path over which a window's first spans are shifted onto the span before them
FIT_TOL = 0.985  # of N1.053: the fit's own tolerance (the joints' shifts take < 3e-4 mm)


@dataclass(frozen=True)
class Held:
    """The moves a run holds back, the vertices behind them (already let through, for the next window) and
    whether the run is being fitted (False: a first move waits for the junction that decides)."""

    moves: tuple[Move, ...] = ()
    behind: tuple[tuple[float, ...], ...] = ()
    fitting: bool = False
    last: Move | None = None  # the last eligible move let through as a line: its junction with the next decides
    tail: SplineSpan | None = None  # the last span let through (a run's next window joins it)


NOTHING = Held()


class RunFeed:
    """The fitting rules for one planner's configuration (its state is the planner's `_held`)."""

    def __init__(self, cfg: MotionConfig, lim) -> None:
        self.tol = float(cfg.path_tolerance or 0.0)
        self.axes = cfg.axes
        self.blend = lim.blend  # FilterCorners, or None without the filter
        self.acc = cfg.share_tangential * float(lim.acc.min())
        self.corner_j = cfg.share_corner * float(min(lim._corner_j))

    @staticmethod
    def enabled(cfg: MotionConfig) -> bool:
        return cfg.fit_runs and (cfg.path_tolerance or 0.0) > 0.0

    # ---- the rules -----------------------------------------------------------------------------
    def eligible(self, mv: Move) -> bool:
        if mv.kind != "line" or mv.per_rev or mv.exact_stop or mv.css is not None or "G31" in mv.tags \
                or not mv.feed:
            return False
        return 1e-6 < math.dist(self._pt(mv.start), self._pt(mv.end)) <= MAX_LEN

    def _pt(self, p: dict[str, float]) -> list[float]:
        return [float(p.get(a, 0.0)) for a in self.axes]  # plain floats: this runs on every push (issue 17)

    def _vec(self, p: dict[str, float]) -> np.ndarray:
        return np.array(self._pt(p))

    def _step(self, m1: Move, m2: Move) -> float | None:
        """|Δu| at the vertex m1 → m2, None where m2 does not continue m1 (not from its end)."""
        a, b, b2, c = self._pt(m1.start), self._pt(m1.end), self._pt(m2.start), self._pt(m2.end)
        if max(abs(x - y) for x, y in zip(b, b2)) > 1e-9:
            return None
        l1, l2 = math.dist(a, b), math.dist(b, c)
        return math.sqrt(sum(((z - y) / l2 - (y - x) / l1) ** 2 for x, y, z in zip(a, b, c)))

    def _pays(self, du: float, feed_mm_min: float) -> bool:
        f = feed_mm_min / 60.0
        if self.blend is not None:
            return self.blend.corner_tolerance(du, self.acc) < PAY * f
        return self.corner_j / max(du, 1e-12) < PAY * f

    # ---- the stream ----------------------------------------------------------------------------
    def push(self, st: Held, mv: Move) -> tuple[Held, list[tuple[Move, SplineSpan | None]]]:
        """The held state after mv, and the moves let through (with their span, None: as a line)."""
        if not self.eligible(mv):
            st, out = self.release(st)
            return st, out + [(mv, None)]
        prev = st.moves[-1] if st.moves else st.last
        du = self._step(prev, mv) if prev is not None else None
        if du is not None and du > 2.0 * math.sin(MAX_TURN / 2.0):
            du = None  # a sharp corner: the run ends at it
        if du is None:
            st, out = self.release(st)
            return Held(moves=(mv,)), out  # a first move: the next junction decides
        if st.fitting:
            st = replace(st, moves=st.moves + (mv,))
            if len(st.moves) >= BATCH + AHEAD:
                return self._fix(st, BATCH)
            return st, []
        if self._pays(du, mv.feed or 0.0):
            return Held(st.moves + (mv,), (), True), []
        out = [(m, None) for m in st.moves]
        return Held(last=mv), out + [(mv, None)]

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
        cut = self._spans(pts, first, n, end)
        if cut is None:  # no fit within the tolerance: as lines, the run ends
            return NOTHING, [(m, None) for m in moves]
        if st.tail is not None:
            cut = join(st.tail, cut)
        if end:  # the run ends on its vertex exactly (the fit pins it to ≈ 1e-8 mm; a plan's end takes seg.end)
            cut[-1].end = pts[-1].copy()
        out = [(m, sp) for i, m in enumerate(moves[:n]) for sp in cut[i * SPLIT:(i + 1) * SPLIT]]
        if end:
            return NOTHING, out
        keep = pts[max(0, first + n - BEHIND):first + n + 1]
        return Held(moves[n:], tuple(tuple(v.tolist()) for v in keep), True, tail=cut[-1]), out

    def _spans(self, pts: np.ndarray, first: int, n: int, end: bool) -> list[SplineSpan] | None:
        if len(pts) < 3:
            return None
        try:
            spl, cum = fit_run(pts, FIT_TOL * self.tol)
        except FitError:
            return None
        # SPLIT spans a segment, each with its own cap; spans() cuts its last span to the curve's end: one
        # more (dropped) unless the run ends here
        sub = cum[first:] if end else cum[first:first + n + 2]
        at = (sub[:-1, None] + np.diff(sub)[:, None] * (np.arange(SPLIT) / SPLIT)[None, :]).ravel()
        # (spans() cuts from the curve's start: the segments behind are cut too and dropped)
        return spans(spl, np.concatenate([cum[:first], at, sub[-1:]]), self.axes)[first:first + n * SPLIT]


def _fade(x: np.ndarray, d: int) -> np.ndarray:
    """d-th derivative of q(x) = 1 - smoothstep5(x) on [0, 1] (0 beyond): 1 at 0, 0 at 1, C2 at both ends."""
    x = np.clip(x, 0.0, 1.0)
    c = np.array([1.0, 0.0, 0.0, -10.0, 15.0, -6.0])
    for _ in range(d):
        c = np.polynomial.polynomial.polyder(c)
    return np.polynomial.polynomial.polyval(x, c)


@dataclass
class JoinedSpan(SplineSpan):
    """A span near the joint of two windows, shifted onto the span before it (decision motion 57): the two fits
    differ there by up to 2e-4 mm, a step one cycle turns into 2x the axis jerk. Shift(σ) = (dp + dv·σ)·q(σ/JOIN),
    σ the path length from the joint (`s0` at this span's start): position and direction meet the span before,
    and the shift fades out C2 within JOIN mm (its curvature about 3e-4 /mm, its third derivative about
    1e-3 /mm², within the span's 1 % bounds margin)."""

    dp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dv: np.ndarray = field(default_factory=lambda: np.zeros(0))
    s0: float = 0.0

    def _shift(self, s: np.ndarray, d: int) -> np.ndarray:
        sig = self.s0 + np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        x = sig / JOIN
        p = self.dp[None, :] + sig[:, None] * self.dv[None, :]
        out = p * (_fade(x, d) / JOIN ** d)[:, None]
        if d:  # Leibniz: p' = dv, p'' = 0
            out = out + d * self.dv[None, :] * (_fade(x, d - 1) / JOIN ** (d - 1))[:, None]
        return np.where((sig < JOIN)[:, None], out, 0.0)

    def points(self, s: np.ndarray) -> np.ndarray:
        return SplineSpan.points(self, s) + self._shift(s, 0)

    def derivatives(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r = SplineSpan.derivatives(self, s)
        return tuple(x + self._shift(s, d) for d, x in enumerate(r))  # type: ignore[return-value]


def join(tail: SplineSpan, cut: list[SplineSpan]) -> list[SplineSpan]:
    """The spans of a new window, the first of them shifted onto `tail` (the last span of the window before)."""
    a = tail.derivatives(np.array([tail.length]))
    b = cut[0].derivatives(np.array([0.0]))
    dp, dv = a[0][0] - b[0][0], a[1][0] - b[1][0]
    out, s0 = [], 0.0
    for sp in cut:
        if s0 < JOIN:
            sp = JoinedSpan(**{f.name: getattr(sp, f.name) for f in fields(sp)}, dp=dp, dv=dv, s0=s0)
            ends = sp.points(np.array([0.0, sp.length]))
            sp.start, sp.end = ends[0], ends[1]
        out.append(sp)
        s0 += sp.length
    return out
