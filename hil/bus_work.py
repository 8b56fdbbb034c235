"""A field bus's share of the cycle work: the wait for the bus and the master's own work (decisions E25).

On EtherCAT and CANopen the summary's `cycle work` (tick to outputs written) holds the link's exchange: the
frame's send and receive on EtherCAT, the SYNC and the wait for every node's TPDOs on CANopen. Against virtual
slaves in another process that wait is their Python answering (≈ 160 µs a cycle on EtherCAT), where a real line
answers within the frame's time on the wire; so the summary splits it out, per cycle:

    bus wait     the link's `wait_ns` of the cycle's exchange (send, the answer, and on CANopen the SYNC
                 producer's hold in lock-step)
    master work  the cycle's work less that wait: what a real line's cycle would cost the master

The sim bus has no link wait (its slaves are the cycle's own work) and keeps its summary as it was.
"""

from __future__ import annotations

from time import perf_counter_ns
from typing import Any

import numpy as np

from hil.clock import TimingStats

FLUSH = 1024  # cycles collected as plain ints before they go into the histograms at once (E26)


class BusWork:
    """Per-cycle wait and master work of a link that reports `wait_ns` (EthercatLink, CanopenLink)."""

    def __init__(self, link: Any, realtime: bool) -> None:
        self.link = link
        self.realtime = realtime  # the cycle work ends at the outputs written (real time) or at done (lock-step)
        self.wait = TimingStats()
        self.master = TimingStats()
        self._t0 = 0
        # a cycle's two figures appended as ints (≈ 0.1 µs), not added to a histogram each (≈ 0.75 µs apiece)
        self._waits: list[int] = []
        self._masters: list[int] = []
        self._first = 0  # the cycle of the first figure collected

    @classmethod
    def for_link(cls, link: Any, realtime: bool) -> "BusWork | None":
        """None for a link without a wait of its own (the sim bus). A CANopen link is told whether a real-time
        clock paces its caller: then it sends the SYNC when asked instead of holding the cycle itself (E24)."""
        if not hasattr(link, "wait_ns"):
            return None
        if hasattr(link, "paced"):
            link.paced = realtime
        return cls(link, realtime)

    def tick(self) -> None:
        """The cycle's wake-up (right after the clock's tick: the same start as its cycle work)."""
        self._t0 = perf_counter_ns()

    def written(self, cycle: int) -> None:
        """The cycle's outputs are written (where the clock ends its cycle work)."""
        wait = self.link.wait_ns
        waits = self._waits
        if not waits:
            self._first = cycle
        waits.append(wait)
        self._masters.append(perf_counter_ns() - self._t0 - wait)
        if len(waits) >= FLUSH:  # (after the outputs are written: in the slack in real time)
            self.flush()

    def flush(self) -> None:
        if self._waits:  # the cycles are consecutive: one per `_cycle`
            self.wait.add_many(np.array(self._waits, dtype=float) * 1e-9, self._first)
            self.master.add_many(np.maximum(np.array(self._masters, dtype=float), 0.0) * 1e-9, self._first)
            self._waits.clear()
            self._masters.clear()

    def summary(self) -> dict[str, dict[str, float]]:
        self.flush()
        return {"bus_wait": self.wait.summary(), "master": self.master.summary()} if self.wait.count else {}
