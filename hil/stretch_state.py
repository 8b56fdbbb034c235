"""The stretch runner's saved states and its reading of the channel (decisions B20, B21, B25): a planner saved
and restored around a stretch, a refill worked out ahead, and what the channel, the panel and scripted events
show; plain functions the `hil.stretch.Stretcher` and its real-time part share."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from nc.channel import Channel
from nc.motion.planner import Planner
from nc.motion.stretch import Samples, sample_stretch, stand_stretch


class _NotAhead(Exception):
    pass


def _not_ahead(*args: Any, **kwargs: Any) -> None:
    raise _NotAhead


def _signature(ch: Channel) -> tuple:
    """What the channel reads from the MLC exchange and the runner, as far as a stretch depends on it."""
    pl = ch.planner
    return (ch.state, ch.pending_aux, pl.feed_override, pl.rapid_override, ch.spindle_override, pl.dry_run,
            ch.single_block, ch.emergency, len(ch.alarms), pl.held, ch._interrupt, ch.skip_armed, ch.end,
            ch.css_rpm, ch.spindle_max)


class _NoPlayer:
    """Stands for `EventPlayer` while hil.run_events is not imported: hil.api.run imports it for --at/--events only."""


_HOOKS: list = []  # [EventPlayer, OperatorPanel], looked up once, not imported a call (they import the runner; B36)


def _hooks() -> list:
    if not _HOOKS:
        from hil.scripting import OperatorPanel

        _HOOKS[:] = [_NoPlayer, OperatorPanel]
    if _HOOKS[0] is _NoPlayer and "hil.run_events" in sys.modules:  # an EventPlayer can exist from now on
        _HOOKS[0] = sys.modules["hil.run_events"].EventPlayer
    return _HOOKS


def _panel_state(on_cycle: Any) -> tuple | None:
    """The on_cycle hook's state while it writes nothing (None: a hook a stretch cannot see into)."""
    if on_cycle is None:
        return ()
    EventPlayer, OperatorPanel = _hooks()
    if isinstance(on_cycle, OperatorPanel):
        return None if on_cycle._pressed else (False,)
    if isinstance(on_cycle, EventPlayer):
        inner = _panel_state(on_cycle.inner)
        if inner is None or on_cycle._release:
            return None
        return (inner, sum(e.fired_cycle is not None for e in on_cycle.events))
    return None


def _event_due(r: Any) -> bool:
    """An `--at` event fired at the end of the last cycle: the scan of this one sees its write."""
    oc = r.on_cycle  # (the class looked up once, not imported a call: ≈ 15 µs of a real-time start, B36)
    return oc is not None and isinstance(oc, _hooks()[0]) and any(e.fired_cycle == r.cycle + 1 for e in oc.events)


def _across(ch: Channel, pl: Planner, n: int) -> int:
    """How many of the next n cycles a stretch across a cruise's blocks may take: its rows, up to the first
    cycle whose feed would read the program again (its queue below the planner's depth; it stays full up to
    there, `Planner.full`); none reads once the program's end, a barrier or a limit alarm was read."""
    i = pl._buf_i
    n = min(n, len(pl._buf_pos) - i)
    if ch.end is not None or ch._deferred is not None or ch._limit_alarm is not None \
            or (ch.single_block and ch._block_moves):
        return n
    left, blk, popped, depth = len(pl.blocks), pl._buf_blk, pl._buf_popped, pl.depth
    for c in range(1, n):  # cycle c's feed sees the queue its cycle c - 1 left
        if left - (blk[i + c - 1] - popped) < depth:
            return c
    return n


def _stand_queued(pl: Planner, n: int) -> Samples | None:
    return stand_stretch(pl, n, queued=True)


def _sample_across(pl: Planner, n: int) -> Samples | None:
    return sample_stretch(pl, n, across=True)


def _save_planner(pl: Planner, filt: bool = True) -> dict:
    """What sample_stretch changes: the planner's own fields, its position filter's state and share zones (and
    its queue, of which a stretch across a cruise's blocks finishes some). `filt` False: not the filter's state
    (a step that does not filter: hil/stretch_pass.py)."""
    saved: dict[str, Any] = {"pl": pl.state()}  # its C fields too (nc.motion.plan_core, B172)
    if pl._buf_blk is not None:
        saved["blocks"] = list(pl.blocks)
    if pl._zones is not None:  # the filter's share zones: sampling drops those it passed (ShareZones.lam)
        saved["zones"] = list(pl._zones.zones)
    f = pl.filter
    if f is not None and filt:  # (one copy of the filter's buffer of doubles, decision bench B141)
        saved["f"] = f.snapshot()
    return saved


def _refilled(fill: tuple) -> Callable[[Planner, int], Samples | None]:
    """sample_stretch after the refill `Stretcher._refill_ahead` worked out (the planner stands where it did)."""
    p, _, s1, p1, *_ = fill

    def sampler(pl: Planner, n: int) -> Samples | None:
        pl.update_state(s1)
        p.__dict__.update(p1)
        return sample_stretch(pl, n)

    return sampler


def _restore_planner(pl: Planner, saved: dict) -> None:
    pl.restore(saved["pl"])
    if "blocks" in saved:  # the same deque (the channel's view of the planner holds it)
        pl.blocks.clear()
        pl.blocks.extend(saved["blocks"])
    if "plan" in saved:  # a refill ahead sampled the plan (Stretcher._refill_ahead): its fields as before
        p, fields = saved["plan"]
        p.__dict__.clear()
        p.__dict__.update(fields)
    if "zones" in saved:  # the same deque, as it was
        zones = pl._zones.zones
        zones.clear()
        zones.extend(saved["zones"])
    if "f" in saved:
        pl.filter.restore(saved["f"])


# Planner methods a refill calls when it ends a block or the plan, re-plans or stalls: a refill ahead stops there
_NOT_AHEAD = ("_finish_block", "_end_plan", "_replan", "_start_plan", "_no_progress")
# The planner's spindle feedback callbacks: this cycle's feedback, not there yet ahead of it
_SPINDLE_FEEDBACK = ("spindle_rpm", "spindle_angle", "spindle_index", "spindle_command")
