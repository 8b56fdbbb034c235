"""The planner's side of fitted runs (nc.motion.spline_feed, issue 18, decisions motion 56-58): moves held back
and let through as spline spans, the filter's share λ = 0 on them (share zones as for corner blends, decision
45), and the channel's ways to end a run (`closed`, `release_run`). A mixin of `Planner`."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Callable

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.motion.block import Block
from nc.motion.plan_core import PlanCore  # the planner's C fields where compiled (bench B172)
from nc.motion.path import line_segment
from nc.motion.spline_feed import NOTHING, Held, RunFeed
from nc.moves import Move

if TYPE_CHECKING:
    from nc.motion.spline_runs import SplineSpan

_span_limits: Callable | None = None  # nc.motion.spline_runs.span_limits, imported by the first span (bench B91)


def _load_span_limits() -> Callable:
    global _span_limits
    from nc.motion.spline_runs import span_limits

    _span_limits = span_limits
    return span_limits


class FittedRuns:
    """Methods of `nc.motion.planner.Planner` (its state is the planner's own: see that module's doc)."""

    _held: Held = NOTHING
    _closed: bool = False

    def _init_runs(self) -> None:
        self._runs = RunFeed(self.cfg, self.lim) if RunFeed.enabled(self.cfg) else None
        self._held = NOTHING

    @property
    @cython.locals(self=PlanCore)
    def closed(self) -> bool:
        """The channel says no move comes before the queue has run out to rest: a held run ends (is let through)."""
        return self._closed

    @closed.setter
    @cython.locals(self=PlanCore)
    def closed(self, value: bool) -> None:
        self._closed = value
        if value and self._held.moves:
            self.release_run()

    @property
    def holding(self) -> bool:
        """Moves are held back (the planner is not idle)."""
        return bool(self._held.moves)

    def release_run(self) -> None:
        """Let every held move through (the run fitted to its end): the channel reads nothing more for now."""
        if self._runs is not None and self._held.moves:
            self._held, out = self._runs.release(self._held)
            self._let_through(out)

    @cython.locals(self=PlanCore, runs=RunFeed, b=Block, out=list)
    def _feed_run(self, move: Move) -> None:
        runs = self._runs
        self._held = runs.feed(self._held, move)  # a C call where compiled (session 29, decision bench B166)
        out = runs.out
        if out is None:  # the common case on programs not fitted: the move as a line, its geometry just worked out
            # a line after spans may have to start where their curve ended (`_from_curve`): only once a span went out
            if runs.spans:
                b = self.blocks[-1] if self.blocks else None
                if b is not None and b.seg is not None and b.seg.kind == "spline":
                    self._let_through([(move, None)])
                    return
            # positional: no keywords to match (bench B156); line_segment a C call where compiled (B166)
            self._push(move, None, line_segment(self.axes, runs._ga, runs._gb, runs._gn, runs._gu))
            return
        if len(out) == 1 and out[0][1] is None:  # one move, as it is
            b = self.blocks[-1] if self.blocks else None
            if b is None or b.seg is None or b.seg.kind != "spline":
                m = out[0][0]
                self._push(m, None, line_segment(self.axes, runs._ga, runs._gb, runs._gn, runs._gu)
                           if runs._gm is m else None)
                return
        self._let_through(out)

    @cython.locals(self=PlanCore)
    def _let_through(self, out: list[tuple[Move, SplineSpan | None]]) -> None:
        spans = [sp for _, sp in out if sp is not None]
        zones = self._zones
        if spans and zones is not None:
            # λ = 0 on the spans (the fit's deviation is the only one); as for a blend, only where the zone keeps
            # clear of the filter's last corner and of the sample going out, else they run as lines
            start = self._path_s
            vtop = 1.5 * max(m.feed or 0.0 for m, sp in out if sp is not None) / 60.0
            prev = self.blocks[-1] if self.blocks else None
            if prev is not None and self.lim.junction(prev, self._span_block(*out[0])) <= 0.0:
                zones.stop(prev.s_end)  # the run begins after a stop: its zone starts there (`_corner` cuts none)
            if zones.blend_allowed(start, vtop, self._now(), abs(self.v) < 1e-12 and self.plan is None):
                zones.add_blend(start, start + sum(sp.length for sp in spans), vtop)
            else:  # as lines; what is still held starts afresh from their end (no span to join)
                out = [(m, None) for k, (m, _) in enumerate(out) if k == 0 or m is not out[k - 1][0]]  # a move once
                self._held = replace(self._held, behind=(), fitting=False, tail=None)
        for m, sp in out:
            if sp is None and m.kind == "line":
                m = self._from_curve(m)
            self._push(m, sp)

    def _from_curve(self, m: Move) -> Move:
        """A line after spans whose curve did not end on its start vertex (a window the fit or the zone refused
        after the batch before it went out): it starts where the curve ended (within N1.053 of the vertex)."""
        b = self.blocks[-1] if self.blocks else None
        if b is None or b.seg is None or b.seg.kind != "spline":
            return m
        end = b.seg.end
        if max(abs(float(m.start.get(a, 0.0)) - float(x)) for a, x in zip(self.axes, end)) <= 1e-9:
            return m
        start = dict(m.start)
        start.update({a: float(x) for a, x in zip(self.axes, end)})
        return m.replaced(start=start)

    def _span_block(self, move: Move, sp: SplineSpan) -> Block:
        lim = self.lim
        # a and j are those at the cap (they only grow below it): the cap held to the fastest the block may ever
        # run (the feed, or the dry-run feed when on, at the top override 1.5; a dry run switched on later only
        # lowers the cap), not the curve's own, so the coupling term
        # 3·v·a_t·r'' leaves a_t more (decision 58)
        top = 1.5 * (self.dry_run_feed if self.dry_run else (move.feed or 0.0) / 60.0)
        vel = np.minimum(lim.v, top * np.maximum(sp.dir_bound, 1e-12))
        # the limits travel with a span the fit-ahead child let through its own look-ahead (decision bench B99):
        # taken where they were worked out on these very inputs, else worked out here (an override, a dry run)
        known = sp.__dict__.get("_limits")
        if known is not None and known[1] == lim._acc and known[2] == lim._jerk and np.array_equal(known[0], vel):
            v, a, j = known[3]
        else:
            v, a, j = (_span_limits or _load_span_limits())(sp, vel, lim.acc, lim.jerk)
            sp.__dict__["_limits"] = (vel, lim._acc, lim._jerk, (v, a, j))
        if lim.cut_on:  # N1.034 / N1.035 (decision motion 90)
            a, j = lim.cut_caps(a, j)
        v = min(v, sp.length / (self.cfg.min_segment_cycles * self.cfg.cycle))
        return Block(move, "path", sp, sp.length, v, a, j, (move.feed or 0.0) / 60.0)

