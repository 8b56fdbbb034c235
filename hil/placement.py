"""Lock-step placement (decisions E21): SCHED_FIFO on one CPU for a lock-step run and its virtual slaves.

Lock-step over a veth pair is a ping-pong: exactly one of `hil run` and `hil sim ethercat` has work at any
time. Under default scheduling each wake-up waits behind other jobs' time slices; on two CPUs each pays a
cross-CPU wake-up. Both SCHED_FIFO on the same CPU take turns at the CPU cost of an idle machine (E20).
A bench asks for it with `[realtime] lockstep = "fifo"` (its `priority` and `cpu`); `hil run` places the
cycle thread for the run (PlacedLockStepClock: placed at start, restored at stop, which the runner's
`finally` reaches on alarms and signals too) and `hil sim ethercat --bench` its slaves. Never required:
what was refused is said in the run summary, the run goes on under default scheduling.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass

from hil.bench import RealtimeConfig
from hil.clock import Granted, LockStepClock, acquire_realtime, release_realtime

PREFIX = "lock-step placement: "  # how a placed run's `granted` starts (hil/commands/run.py prints it)


def placement_cpu(config: RealtimeConfig) -> int | None:
    """The CPU both sides use: the bench's `cpu`, else the highest CPU this process may run on (the same
    for `hil run` and `hil sim ethercat` started from one shell: they inherit one affinity mask)."""
    if config.cpu is not None:
        return config.cpu
    try:
        return max(os.sched_getaffinity(0))
    except (OSError, AttributeError, ValueError):
        return None


@dataclass
class LockstepGranted(Granted):
    """What the lock-step placement got; printed in the run summary."""

    @property
    def what(self) -> str:
        where = f"CPU {self.cpus}" if self.cpus else "any CPU"
        head = f"SCHED_FIFO prio {self.priority} on {where}" if self.sched == "SCHED_FIFO" else \
            f"default scheduling on {where}"
        return head + "".join(f"; {n}" for n in self.notes)

    def __str__(self) -> str:
        return PREFIX + self.what


class Placed:
    """This thread's scheduling while placed, and what it had before (`restore` gives it back)."""

    def __init__(self) -> None:
        self._saved_sched: tuple[int, int] | None = None
        self._saved_affinity: set[int] | None = None

    def apply(self, priority: int, cpu: int | None) -> LockstepGranted:
        g = acquire_realtime(RealtimeConfig(priority=priority, cpu=cpu, lock_memory=False), self)  # type: ignore[arg-type]
        g.notes = [n[:-1] + ": needs root or CAP_SYS_NICE)" if n.startswith("SCHED_FIFO refused") else n for n in g.notes]
        return LockstepGranted(**asdict(g))

    def restore(self) -> None:
        release_realtime(self)  # type: ignore[arg-type]


class PlacedLockStepClock(LockStepClock):
    """Virtual time, with the cycle thread placed per the bench's [realtime] for the run."""

    def __init__(self, cycle: float, config: RealtimeConfig) -> None:
        super().__init__(cycle)
        self.config = config
        self._placed = Placed()

    def start(self, link: object | None = None) -> None:
        self.granted = self._placed.apply(self.config.priority, placement_cpu(self.config))

    def stop(self) -> None:
        self._placed.restore()


def lockstep_clock(cycle: float, config: RealtimeConfig) -> LockStepClock:
    """The lock-step clock a bench asks for: placed when its [realtime] lockstep is "fifo"."""
    return PlacedLockStepClock(cycle, config) if config.lockstep == "fifo" else LockStepClock(cycle)
