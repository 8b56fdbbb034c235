"""Real time on a field bus (EtherCAT, CANopen): the next cycle's planning that does not depend on its feedback,
worked out in the slack after the cycle before (issue 17, decision bench B60).

On the in-process bus the next cycle's feedback is computed before its tick (B21), so B46 runs its whole channel
step there. A field bus's feedback comes with the exchange after the tick, and a feed's push cannot be taken back,
so here only what can be put in place later, or thrown away, is done ahead:
- the planner's refill (block ends, the next block's solve, its samples) where the buffer runs out and the feed
  reads nothing: B21's refill (`RealTimeStretches.ahead`), kept aside and put in place by the cycle's step only
  when nothing it read changed since (the planner's fields and queue, the channel's signature: an alarm the
  feedback raised, a hold or an override the scan wrote). Spindle feedback (feed per revolution, threads) is
  never read ahead: such a refill is left to the step;
- the feed's events: where the next step's feed reads, the interpreter generates the events it will take
  (`hil.stretch_reads.Ahead.peek`, as B26/B46). They stay in the channel's event stream, handed out in order when
  the feed reads, whatever the cycle's feedback and scan did meanwhile.
The cycle itself steps as before (`Channel.step`), so its trace is stepping's by construction. Where the NC does
not run quietly (a code handed to the MLC, a hold, overrides, G96, feed per revolution, threads, G31, a fault, a
drive that is not enabled, a stop) nothing is done ahead. `DELTAHIL_STRETCH=0` turns it off (the reference).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from fieldbus.cia402 import State, Target
from fieldbus.link import SimLink
from hil.clock import RealTimeClock
from hil.stretch import ENV, MODE_CSP, MODE_CSV, Stretcher
from hil.stretch_ahead import _only_pushes, _reads
from hil.stretch_reads import ahead as events_ahead
from hil.stretch_realtime import RealTimeStretches
from hil.stretch_state import _event_due, _panel_state
from mlc.basic import BasicMlc
from mlc.machine import Mlc
from nc.channel import READS_PER_CYCLE, Channel
from nc.motion.planner import Setpoint


class BusAhead(RealTimeStretches):
    """The work ahead of one real-time run on a field bus (module doc); B21's refill on its state."""

    def __init__(self, runner: Any) -> None:
        self.r = runner
        self.paced = True
        self.drives: list = []  # no drive models: the drives are across the bus
        self.n_axes = len(runner.axes)
        self.settling = False
        self.ahead_used = 0  # refills made ahead and put in place by their cycle
        self.aheads_skipped = 0  # slacks too short for work ahead (B34's rule)
        self.peeks = 0  # feeds whose events the interpreter generated ahead

    @classmethod
    def for_runner(cls, runner: Any) -> "BusAhead | None":
        """Real time over a field bus (not the in-process one: B21/B46 there) with the basic or the Delta MLC."""
        if type(runner.clock) is not RealTimeClock or type(runner.link) is SimLink or os.environ.get(ENV) == "0":
            return None
        if type(runner.mlc) not in (Mlc, BasicMlc) or runner.channel is None:
            return None
        return cls(runner)

    def _quiet(self, r: Any, ch: Channel) -> str | None:
        """`Stretcher._quiet` without its drive-model checks: every master enabled and asked to stay so, each
        drive in the mode the cycle commands (CSP axes, CSV spindles)."""
        for i, (rx, m) in enumerate(zip(r.rx, r.masters)):
            if m.state is not State.OPERATION_ENABLED or m.target is not Target.ENABLED \
                    or rx.mode != (MODE_CSP if i < self.n_axes else MODE_CSV):
                return None
        return Stretcher._quiet(self, r, ch)  # type: ignore[arg-type]

    def step(self) -> Callable[[Channel], Setpoint] | None:
        """The next cycle's work ahead, done now (in the slack before its tick): its `step` for
        `BenchRunner._exchange`, or None (the cycle steps as usual)."""
        r = self.r
        ch: Channel | None = r.channel
        if ch is None or self.skip_ahead():
            return None
        self._peek(r, ch)
        return self.ahead()

    def _peek(self, r: Any, ch: Channel) -> None:
        """The events the next step's feed reads, generated now where it reads only plain moves' worth (B46's
        conditions on the channel; the peek stops at the first other event and keeps it, in order)."""
        pl = ch.planner
        if type(r.mlc) is not BasicMlc:  # the Delta MLC's scan may write what a peek checks (soft limits)
            return
        if r._planner_failed or r.stop_request is not None or r._braking or r._winding_down or r.result.alarms \
                or ch.pending_aux is not None or ch.emergency or not _only_pushes(ch, pl) or not _reads(ch, pl) \
                or _panel_state(r.on_cycle) is None or _event_due(r):
            return
        if events_ahead(ch).peek(READS_PER_CYCLE):
            self.peeks += 1
