"""G05 parameter groups in the channel (N§3.8.2; decision language L25-1): the planner rebuilt with a group's
settings at rest, and N1.033's limit on the programmed feed.

The planner sizes its look-ahead, filter windows, share zones and run fitting from its `MotionConfig` once, when
it is built; G05 stops preview, so when its Sync has drained the queue is empty and the filter settled, and a
planner built anew with the other settings, standing where this one stands, takes over without a seam.
"""

from __future__ import annotations

from nc.motion.limits import MotionConfig
from nc.motion.planner import Planner
from nc.moves import Move

# What a run changed on the planner that the settings do not: the operator's controls, the current line, the logs.
_KEPT = ("_feed_ovr", "_rapid_ovr", "dry_run", "dry_run_feed", "line", "thread_log", "thread_waits", "solves",
         "_sim_angle")


def rebuilt(pl: Planner, cfg: MotionConfig) -> Planner:
    """A planner with `cfg` standing where `pl` (at rest, idle) stands, the spindle sources and controls kept.
    A fit memo (nc.motion.fit_memo) is not carried over: it was worked out with `pl`'s settings."""
    new = Planner(cfg, dict(zip(pl.axes, pl.position.tolist())), spindle_rpm=pl.spindle_rpm,
                  spindle_angle=None if pl._integrate_angle else pl.spindle_angle,
                  spindle_index=pl.spindle_index, spindle_command=pl.spindle_command)
    for name in _KEPT:
        setattr(new, name, getattr(pl, name))
    return new


_CUTS = ("line", "arc")


def capped(mv: Move, cap: float) -> Move:
    """`mv` with its programmed feed limited to N1.033 `cap` (mm/min): G94 lines and arcs (G01/G02/G03, G31);
    rapids, threads, dwells and feed per revolution as they are."""
    if mv.kind in _CUTS and not mv.per_rev and mv.feed is not None and mv.feed > cap:
        return mv.replaced(feed=cap)
    return mv
