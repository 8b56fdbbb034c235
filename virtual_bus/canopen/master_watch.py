"""A virtual CANopen drive's watch on its master (decision E34): the CiA 301 heartbeat consumer of 0x1016 and
what a real drive does when the master's heartbeat stops — a master killed, crashed or unplugged sends neither
heartbeat nor SYNC again.

Delta's ASDA-A3 CANopen manual: with the consumer heartbeat time (OD 1016h) set, a drive that receives no
heartbeat from the controller within it triggers the heartbeat event, AL180. Here the drive then faults with
AL180 (EMCY 0x8130 "life guard or heartbeat error", Delta number 0x180 in the manufacturer bytes) and, since no
SYNC will step it any more, brakes on its fault reaction (the quick-stop ramp) in its own time to standstill,
where its power stage goes off. Only in `hil sim canopen` (its own process on a real transport): in lock-step the
nodes share the master's process and its simulated time, so the master cannot go silent without them.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from fieldbus.canopen.emcy import emcy_for_delta
from fieldbus.cia402 import State

if TYPE_CHECKING:
    from virtual_bus.canopen.node import Cia402Slave

AL_HEARTBEAT = 0x0180  # ASDA-A3: heartbeat event (no heartbeat within the consumer time of 0x1016)
MAX_COAST_STEPS = 60_000  # interpolation periods one check may run a braking drive on (a minute at 1 ms)
_ENERGISED = (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE)


class MasterWatch:
    """Heartbeat consumer and fault reaction of one `Cia402Slave`. `check` runs every few ms from the serving
    thread (virtual_bus/canopen/nodes.py `serve`) under the bus lock; it returns lines for `--verbose`."""

    def __init__(self, slave: "Cia402Slave") -> None:
        self.s = slave
        self.seen: float | None = None  # when the configured producer's heartbeat came last (None: not armed)
        self.coasting = False
        self.stepped = time.monotonic()  # the drive's model time, on the clock: a SYNC or `check` stepped it
        self._v0 = 0.0
        self._t = 0.0
        self._armed = False

    def subscribe(self) -> None:
        net = self.s.network
        assert net is not None
        for node_id in range(1, 128):  # any producer 0x1016 may name; the callback keeps the configured one
            if node_id != self.s.node_id:
                net.subscribe(0x700 + node_id, self._on_heartbeat)

    def consumer(self) -> tuple[int, float]:
        """(producer node ID, consumer time in s) from 0x1016:1; (0, 0.0) when not set (or no such object)."""
        try:
            raw = self.s._value(0x1016, 1)
        except (KeyError, AttributeError, TypeError):
            return 0, 0.0
        return (raw >> 16) & 0x7F, (raw & 0xFFFF) / 1000.0

    def _on_heartbeat(self, can_id: int, data: bytes, timestamp: float) -> None:
        producer, _ = self.consumer()
        if producer and can_id - 0x700 == producer:
            if self.seen is None:
                self._armed = True  # for the log: the consumer runs from this first heartbeat (CiA 301)
            self.seen = time.monotonic()

    def synced(self) -> None:
        """A SYNC stepped the drive: the master is there (a stalled one that came back steps it again)."""
        self.stepped = time.monotonic()

    def check(self, now: float) -> list[str]:
        s, d = self.s, self.s.drive
        out: list[str] = []
        producer, window = self.consumer()
        if self._armed:
            self._armed = False
            out.append(f"watching the heartbeat of node {producer} (consumer time {window * 1000:.0f} ms)")
        if (self.seen is not None and producer and window > 0.0 and now - self.seen > window
                and s.nmt_state == "OPERATIONAL" and d.state in _ENERGISED):
            self.seen = None  # the event is taken once; the next heartbeat arms the consumer again
            self._v0, self._t, self.coasting = d.velocity, 0.0, True
            d.fault(AL_HEARTBEAT)
            s.report_fault(emcy_for_delta(AL_HEARTBEAT))
            out.append(f"no heartbeat from node {producer} for {window * 1000:.0f} ms: AL180 (heartbeat event), "
                       "EMCY 0x8130")
        if self.coasting:
            out += self._coast(now)
        return out

    def _coast(self, now: float) -> list[str]:
        """Step the braking drive by the time no SYNC stepped it, an interpolation period at a time."""
        d, dt = self.s.drive, self.s.interpolation_period
        steps = min(int((now - self.stepped) / dt), MAX_COAST_STEPS) if dt > 0.0 else 0
        for _ in range(steps):
            if d.state is not State.FAULT_REACTION_ACTIVE:
                break
            d.step(dt)
            self._t += dt
        if steps:
            self.stepped = now
        if d.state is State.FAULT_REACTION_ACTIVE:
            return []
        self.coasting = False
        how = (f"braked from {self._v0:.0f} counts/s to standstill in {self._t:.3f} s"
               if abs(self._v0) >= 1.0 else "at standstill")
        return [f"drive {how} on its fault reaction, at {round(d.position)} counts; FAULT 0x{d.error_code:04X}, "
                "power stage off"]
