"""One NC channel in AUTO: pulls the interpreter, feeds the planner, runs the M/S/T handshake,
and turns any alarm into a controlled stop.

The MLC side of the handshake is reached only through `pending_aux` / `finish_aux()`, so the
channel runs the same with Delta's special M/D relays behind it or with no MLC at all.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from nc.alarms import Alarm, NcAlarm, internal_error
from nc.motion.planner import Planner, Setpoint
from nc.moves import Aux, Event, Move, ProgramEnd, Sync


class RunState(Enum):
    IDLE = "idle"
    RUNNING = "running"
    WAIT_AUX = "waiting for MLC finish"
    STOPPING = "stopping"
    FINISHED = "finished"
    ALARM = "alarm"


@dataclass
class Channel:
    planner: Planner
    events: Iterator[Event] | None = None
    state: RunState = RunState.IDLE
    alarms: list[Alarm] = field(default_factory=list)
    pending_aux: Aux | None = None
    spindle_rpm: float = 0.0  # programmed S with direction, for feed per revolution
    end: ProgramEnd | None = None
    _waiting_sync: bool = False
    _aux_issued: bool = False
    _deferred_aux: Aux | None = None

    def load(self, events: Iterator[Event]) -> None:
        self.events = events
        self.state = RunState.IDLE

    def cycle_start(self) -> None:
        if self.events is not None and self.state in (RunState.IDLE,):
            self.state = RunState.RUNNING

    @property
    def busy(self) -> bool:
        return self.state in (RunState.RUNNING, RunState.WAIT_AUX, RunState.STOPPING)

    # ---- MLC side ---------------------------------------------------------------------
    def finish_aux(self) -> None:
        """The MLC's finish signal for the pending M/S/T code."""
        if self.pending_aux is not None:
            self.pending_aux = None
            if self.state is RunState.WAIT_AUX:
                self.state = RunState.RUNNING

    # ---- faults -----------------------------------------------------------------------
    def raise_alarm(self, alarm: Alarm) -> None:
        """Any alarm, from the program, a drive or the bus: controlled stop, then ALARM."""
        self.alarms.append(alarm)
        if self.state is not RunState.ALARM:
            self.planner.stop()
            self.state = RunState.STOPPING if not self.planner.idle else RunState.ALARM
            self.pending_aux = None

    def emergency_stop(self, alarm: Alarm) -> None:
        """E-stop: setpoints freeze this cycle (the drives' own quick stop does the braking)."""
        self.alarms.append(alarm)
        self.planner.queue.clear()
        self.planner.active = None
        self.state = RunState.ALARM
        self.pending_aux = None

    # ---- per cycle --------------------------------------------------------------------
    def step(self) -> Setpoint:
        if self.state is RunState.RUNNING:
            self._feed_planner()
        sp = self.planner.step()
        if self.state is RunState.STOPPING and self.planner.idle:
            self.state = RunState.ALARM
        if self.state is RunState.RUNNING and self.planner.idle and self.end is not None \
                and self.pending_aux is None:
            self.state = RunState.FINISHED
        return sp

    def _feed_planner(self) -> None:
        """Read events until the planner has work or the channel must wait."""
        while self.state is RunState.RUNNING and self.planner.idle and self.end is None:
            if self._deferred_aux is not None:
                self._issue(self._deferred_aux)
                self._deferred_aux = None
                return
            try:
                ev = next(self.events)  # type: ignore[arg-type]
            except StopIteration:
                self.end = ProgramEnd(0, "", 0)
                return
            except NcAlarm as exc:
                self.raise_alarm(exc.alarm)
                return
            except Exception as exc:  # a bug must still stop the machine with an alarm
                self.raise_alarm(internal_error(exc))
                return
            if isinstance(ev, Move):
                self.planner.push(ev)
            elif isinstance(ev, Aux):
                if ev.kind == "S":
                    self.spindle_rpm = ev.value
                self._issue(ev)
            elif isinstance(ev, ProgramEnd):
                self.end = ev
            elif isinstance(ev, Sync):
                continue  # the planner is already drained here: nothing more to wait for

    def _issue(self, aux: Aux) -> None:
        if not self.planner.idle:
            self._deferred_aux = aux
            return
        self.pending_aux = aux
        if aux.wait:
            self.state = RunState.WAIT_AUX
