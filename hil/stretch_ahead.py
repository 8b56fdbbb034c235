"""Real time with the basic MLC: a stepped cycle's whole channel step (feed and planner step) worked out in the
slack before its tick (issue 17, decision bench B46).

The CAM program in real time stepped ≈ 55 % of its cycles (rt_census, session 15): its feed reads the program every
cycle or two (4 blocks, ≈ 30 µs of `Planner.push` each) and its blocks end every cycle or two (a solve, 90-300 µs),
so those cycles worked 300-1,000 µs after their tick. B21/B31 moved only the bus exchange and a refill that reads
nothing the scan changes into the slack; the feed stayed in the cycle: its push cannot be taken back.

Here it need not be. With the basic MLC (`mlc.basic.BasicMlc`) what runs in a stepped cycle between its tick and
its channel step reads none of what that step changes, and changes none of what it reads, when:
- `feedback()` raises no alarm and steps no master: every drive enabled and asked to stay so, its feedback (the bus
  exchange ahead, B21) enabled, no axis over its overspeed limit or on a limit switch;
- the scan does only its cycle count: no M/S/T code pending (`pending_aux`), no G96 speed (`css_rpm`), the MLC's
  overrides 100 % (else it writes them every scan);
- the channel runs and its feed only reads and pushes plain moves (where it reads, the next `READS_PER_CYCLE` events
  peeked ahead are plain moves, as B26's feeds inside a stretch) or reads nothing (the program's end, a code or a
  limit alarm read and waiting for a planner that is not idle yet): no code issued, no interrupt, skip, hold, thread
  or single block; no stop asked, no operator-panel press or `--at` event due.
The spindle feedback the planner's step reads (`BenchRunner.tx`) is this cycle's, from the exchange ahead. A G96
speed the step itself starts (`Channel._update_css`) is kept from the scan until the step's place in the cycle.
The step's setpoint is then handed to the cycle (`BenchRunner._cycle`'s `step`), which does the rest as stepping.
Otherwise the cycle steps as before, with B21's refill ahead where that applies (`Stretcher.ahead`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fieldbus.cia402 import STATES_BY_BITS, SW_INTERNAL_LIMIT, State, Target
from hil.stretch_pass import _feed_due
from hil.stretch_reads import ahead as events_ahead
from hil.stretch_state import _event_due, _panel_state
from mlc.basic import BasicMlc
from nc.channel import READS_PER_CYCLE, Channel, RunState
from nc.motion.planner import Setpoint

_ENABLED, _KEEP = State.OPERATION_ENABLED, Target.ENABLED
_FULL = (1.0, 1.0, 1.0)


def wanted(r: Any) -> bool:
    """The run's stepped cycles may take their channel step ahead: paced on the in-process bus (its exchange ahead)
    with the basic MLC."""
    return r._bus_ahead and type(r.mlc) is BasicMlc


def step_ahead(st: Any, tx: list) -> Callable[[Channel], Setpoint] | None:
    """This cycle's channel step made now, before its tick, where nothing the cycle does before its step can tell
    (module doc): the step for `BenchRunner._cycle`, handing out its setpoint; else B21's refill ahead or None."""
    r = st.r
    ch: Channel | None = r.channel
    if ch is None or r._planner_failed or r.stop_request is not None or r._braking or r._winding_down \
            or r._alarmed_drives or r._at_limit or r.result.alarms:
        return st.ahead()
    pl = ch.planner
    if ch.pending_aux is not None or ch.css_rpm is not None or ch.emergency or r.mlc.overrides != _FULL \
            or not _only_pushes(ch, pl) or _panel_state(r.on_cycle) is None or _event_due(r):
        return st.ahead()
    n_axes, overspeed = st.n_axes, r._overspeed
    for i, (m, t) in enumerate(zip(r.masters, tx)):  # feedback() steps no master and raises nothing
        sw = t.statusword
        if m.state is not _ENABLED or m.target is not _KEEP or STATES_BY_BITS[sw & 0x7F] is not _ENABLED \
                or sw & SW_INTERNAL_LIMIT or (i < n_axes and abs(t.velocity_actual) > overspeed[i]):
            return st.ahead()
    if _reads(ch, pl) and not events_ahead(ch).peek(READS_PER_CYCLE):
        return st.ahead()  # the feed would read something but plain moves
    last, r.tx = r.tx, tx  # the planner's spindle feedback: this cycle's
    try:
        sp = ch.step()
    finally:
        r.tx = last
    css, ch.css_rpm = ch.css_rpm, None  # (a G96 move the step started: the scan before its place must not see it)
    st.steps_ahead += 1

    def step(channel: Channel) -> Setpoint:
        channel.css_rpm = css
        return sp

    return step


def _only_pushes(ch: Channel, pl: Any) -> bool:
    """The channel's step issues no code and starts no interrupt, skip or thread: it runs, and its feed (as
    `Channel._feed_planner`) either reads (only plain moves: `_reads`, peeked by the caller) or finds nothing to do,
    also where the program's end, a code or a limit alarm waits for the moves before it to run out (not yet: the
    planner is not idle before the step, so the feed leaves them waiting)."""
    if ch.state is not RunState.RUNNING or ch._interrupt is not None or ch.single_block or ch.alarms \
            or ch.skip_armed or ch._skip_move is not None or pl.held or pl.threads_queued or pl._thread is not None:
        return False
    budget = ch.statement_budget
    if budget is not None and budget.spent:
        return False
    if ch._fed or ch.end is not None:
        return True
    if ch._deferred is not None or ch._limit_alarm is not None:
        return not pl.idle
    return ch.events is not None


def _reads(ch: Channel, pl: Any) -> bool:
    """The step's feed reads the program (Channel._feed_planner: not fed ahead, the queue not full, nothing waits)."""
    return not ch._fed and ch.end is None and ch._deferred is None and ch._limit_alarm is None and _feed_due(pl)
