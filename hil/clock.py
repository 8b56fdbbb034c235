"""Cycle pacers: lock-step virtual time and paced real time, and per-cycle timing statistics.

The runner calls `tick()` at the start of every cycle and `done()` when the cycle's work is over.
`tick()` returns the cycle's timing: the period since the previous cycle started and how late the
cycle started against its deadline. In lock-step mode both are virtual (period = cycle, late = 0),
so traces stay reproducible; in real-time mode they are measured on CLOCK_MONOTONIC.

Real time: sleep until shortly before the deadline, then spin on the clock for the last stretch
(`busy_wait`), because a sleeping thread wakes tens of microseconds late on a stock kernel while
spinning is exact to the clock's resolution. SCHED_FIFO, CPU pinning and mlockall are requested
and whatever the system refuses is reported, never fatal. On EtherCAT the link may expose
`dc_time() -> int` (ns of the reference clock); the pacer then steers its deadlines so the frame
leaves at a fixed phase to SYNC0, like a DC master must.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hil.bench import RealtimeConfig


@dataclass(frozen=True, slots=True)
class CycleTiming:
    period: float  # s since the previous cycle started
    late: float  # s the cycle started after its deadline
    overrun: bool = False  # the previous cycle's work ran past this cycle's deadline


class TimingStats:
    """Streaming distribution of a non-negative duration: a 100 ns histogram up to 50 ms plus the
    exact maximum, so percentiles of hours-long runs need fixed memory (4 MB)."""

    BIN = 1e-7
    NBINS = 500_000

    def __init__(self) -> None:
        self.hist = np.zeros(self.NBINS + 1, dtype=np.int64)
        self.count = 0
        self.max = 0.0
        self.max_at = 0  # cycle number of the maximum

    def add(self, value: float, cycle: int = 0) -> None:
        v = abs(value)
        self.hist[min(int(v / self.BIN), self.NBINS)] += 1
        self.count += 1
        if v > self.max:
            self.max, self.max_at = v, cycle

    def add_repeated(self, value: float, count: int, first_cycle: int = 1) -> None:
        """add(value) `count` times (a stretch's cycles, hil/stretch_bulk.py)."""
        if count <= 0:
            return
        v = abs(value)
        self.hist[min(int(v / self.BIN), self.NBINS)] += count
        self.count += count
        if v > self.max:
            self.max, self.max_at = v, first_cycle

    def add_many(self, values: np.ndarray, first_cycle: int = 1) -> None:
        v = np.abs(np.asarray(values, dtype=float))
        if v.size == 0:
            return
        idx = np.minimum((v / self.BIN).astype(np.int64), self.NBINS)
        bins, counts = np.unique(idx, return_counts=True)  # not a bincount: a 4 MB array for a stretch's 64 values
        self.hist[bins] += counts
        self.count += int(v.size)
        i = int(np.argmax(v))
        if v[i] > self.max:
            self.max, self.max_at = float(v[i]), first_cycle + i

    def percentile(self, q: float, nz: tuple[np.ndarray, np.ndarray] | None = None) -> float:
        """`nz`: the histogram's non-empty bins and their cumulative counts (`_nonzero`), when the caller asks for
        several: the first bin whose cumulative count reaches the rank is one of them (a bin adds to the sum only
        where it holds something), and a cumulative sum over all 500,001 bins costs milliseconds."""
        if self.count == 0:
            return 0.0
        bins, cum = self._nonzero() if nz is None else nz
        k = int(bins[int(np.searchsorted(cum, q / 100.0 * self.count, side="left"))]) if q > 0 else 0
        return min((k + 0.5) * self.BIN, self.max) if k < self.NBINS else self.max

    def _nonzero(self) -> tuple[np.ndarray, np.ndarray]:
        bins = np.flatnonzero(self.hist)
        return bins, np.cumsum(self.hist[bins])

    def summary(self) -> dict[str, float]:
        nz = self._nonzero() if self.count else None
        return {"p50": self.percentile(50, nz), "p99": self.percentile(99, nz), "p99.9": self.percentile(99.9, nz),
                "max": self.max, "count": float(self.count)}


@dataclass
class Granted:
    """What the system granted the real-time loop (reported, never required)."""

    sched: str = "SCHED_OTHER"
    priority: int = 0
    cpus: str = ""
    memory_locked: bool = False
    dc_aligned: bool = False
    notes: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        parts = [f"{self.sched}" + (f" prio {self.priority}" if self.priority else ""),
                 f"cpus {self.cpus}" if self.cpus else "cpus any",
                 "memory locked" if self.memory_locked else "memory not locked",
                 "aligned to DC SYNC0" if self.dc_aligned else "free-running"]
        return ", ".join(parts) + "".join(f"; {n}" for n in self.notes)


class LockStepClock:
    """Virtual time: every cycle is exactly one period long; nothing waits."""

    realtime = False

    def __init__(self, cycle: float) -> None:
        self.cycle = cycle
        self.exec = TimingStats()  # wall-clock work per cycle, for the summary only (not the trace)
        self.jitter = TimingStats()
        self.overruns = 0
        self.granted = Granted(notes=["lock-step virtual time"])
        self._t0 = 0
        self._n = 0

    def prepare(self) -> None:
        pass

    def start(self, link: object | None = None) -> None:
        pass

    def tick(self) -> CycleTiming:
        self._t0 = time.perf_counter_ns()
        self._n += 1
        self.jitter.add(0.0, self._n)
        return CycleTiming(self.cycle, 0.0)

    def written(self) -> None:
        pass  # lock-step: the work per cycle is taken at done() (stretch_bulk adds its cycles' share there)

    def done(self) -> None:
        self.exec.add((time.perf_counter_ns() - self._t0) * 1e-9, self._n)

    def stop(self) -> None:
        pass


# B98: the idle work stops with this much of the period left: the clock's own spin (busy_wait, 200 µs by default),
# B43's warm-up before it (60 µs) and a part's own length (a fitted span's unpickling, 20-45 µs paced)
IDLE_LEFT_NS = 400_000


class RealTimeClock:
    """Holds the cycle period on CLOCK_MONOTONIC, optionally phase-locked to EtherCAT DC."""

    realtime = True

    def __init__(self, cycle: float, config: RealtimeConfig | None = None,
                 now_ns: Callable[[], int] = time.monotonic_ns, sleep: Callable[[float], None] = time.sleep,
                 dc_offset: float = 0.5) -> None:
        self.cycle = cycle
        self.config = config or RealtimeConfig()
        self.period_ns = int(round(cycle * 1e9))
        self.now_ns = now_ns
        self.sleep = sleep
        self.dc_offset_ns = int(dc_offset * self.period_ns)  # where in the SYNC0 period the frame should go
        self.exec = TimingStats()
        self.jitter = TimingStats()  # |period - cycle|
        self.latency = TimingStats()  # wake-up lateness against the deadline
        # Work between one cycle's done() and the next tick() (decision B21): a stretch's planner samples and
        # drive models computed ahead, the runner's loop; it runs in the period's slack, so a period holds
        # its cycle's work plus this
        self.between = TimingStats()
        self._done_ns: int | None = None
        self._written = False
        self._late_period = (0.0, 0.0)  # this cycle's, added to the statistics once its outputs are written
        self.overruns = 0
        self.first_overrun: int | None = None
        self.granted = Granted()
        self._deadline = 0
        self._last_start: int | None = None
        self._start_ns = 0
        self._n = 0
        self._dc: Callable[[], int] | None = None
        self._integral = 0.0
        self._saved_affinity: set[int] | None = None
        self._saved_sched: tuple[int, int] | None = None
        self._acquired = False
        # B98: work of the lowest rank, done a small part at a time in the slack while more than IDLE_LEFT_NS of the
        # period is left (fitted windows decoded ahead: nc.motion.fit_memo); a part returns False when none is left
        self.idle_work: Callable[[], bool] | None = None

    # ---- setup ------------------------------------------------------------------------------
    def prepare(self) -> None:
        """Ask for SCHED_FIFO, the CPU and mlockall before the bus is opened (decisions E23): mlockall takes
        ≈ 0.1 s on a process of this size, and a bus in OP whose process data stops for that long trips its
        slaves' watchdog (an ESC's SM watchdog is 100 ms by default: AL status 0x001B)."""
        if not self._acquired:
            self.granted = acquire_realtime(self.config, self)
            self._acquired = True

    def start(self, link: object | None = None) -> None:
        self.prepare()  # (a no-op where the runner prepared before opening the bus)
        dc = getattr(link, "dc_time", None)
        if callable(dc):
            self._dc = dc
            self.granted.dc_aligned = True
        self._deadline = self.now_ns() + self.period_ns

    def stop(self) -> None:
        release_realtime(self)
        self._acquired = False

    # ---- the cycle ----------------------------------------------------------------------------
    def idle(self) -> None:
        """The idle work's parts while the next deadline is more than IDLE_LEFT_NS away (B98): each part is small
        (tens of µs), so the work stops before the deadline and goes on in a later slack."""
        work = self.idle_work
        if work is not None:
            while self._deadline - self.now_ns() > IDLE_LEFT_NS and work():
                pass

    def tick(self) -> CycleTiming:
        self.idle()
        now = self.now_ns()
        if self._done_ns is not None:
            self.between.add((now - self._done_ns) * 1e-9, self._n + 1)
        overrun = now > self._deadline
        if overrun:
            self.overruns += 1
            if self.first_overrun is None:
                self.first_overrun = self._n + 1
            # Skip the missed deadlines: keep the phase, never try to catch up with a burst.
            missed = (now - self._deadline) // self.period_ns + 1
            self._deadline += missed * self.period_ns
        self._wait_until(self._deadline)
        start = self.now_ns()
        self._n += 1
        late = (start - self._deadline) * 1e-9
        period = (start - self._last_start) * 1e-9 if self._last_start is not None else self.cycle
        self._last_start = start
        self._start_ns = start
        self._written = False
        self._late_period = (late, period)
        self._deadline += self.period_ns + self._dc_correction()
        return CycleTiming(period, late, overrun)

    def written(self) -> None:
        """The cycle's outputs are written (the setpoints the next exchange sends): its work ends here (decision
        B21); what follows (trace row, panel, progress, statistics) counts as work between cycles."""
        self._done_ns = now = self.now_ns()
        self._written = True
        self.exec.add((now - self._start_ns) * 1e-9, self._n)
        late, period = self._late_period
        self.latency.add(late, self._n)
        self.jitter.add(period - self.cycle, self._n)

    def done(self) -> None:
        if not self._written:
            self.written()

    def slack_ns(self) -> int:
        """ns since this cycle's outputs were written: the work done so far in its slack (decision B33)."""
        return self.now_ns() - self._done_ns if self._done_ns is not None else 0

    def work_ns(self) -> int:
        """ns from this cycle's tick to its outputs written (0 before they are): its own work (decision B34)."""
        return self._done_ns - self._start_ns if self._written and self._done_ns is not None else 0

    def left_ns(self) -> int:
        """ns until the next cycle's deadline (negative: it is missed); work in the slack asks before it starts."""
        return self._deadline - self.now_ns()

    def _wait_until(self, deadline: int) -> None:
        spin_ns = int(self.config.busy_wait * 1e9)
        remaining = deadline - self.now_ns()
        if remaining > spin_ns:
            self.sleep((remaining - spin_ns) * 1e-9)
        while self.now_ns() < deadline:
            pass

    def _dc_correction(self) -> int:
        """PI steering of the next deadline so DC time modulo the period sits at the target offset."""
        if self._dc is None:
            return 0
        try:
            t = int(self._dc())
        except Exception:  # a link without a DC reading this cycle: free-run for one period
            return 0
        if t <= 0:
            return 0
        err = (t - self.dc_offset_ns) % self.period_ns
        if err > self.period_ns // 2:
            err -= self.period_ns
        self._integral += err
        # Gains small against the period: the loop settles in ~100 cycles and never jumps.
        corr = -(0.1 * err + 0.005 * self._integral)
        limit = self.period_ns * 0.05
        return int(max(-limit, min(limit, corr)))


# ---- system real-time requests ------------------------------------------------------------------
def acquire_realtime(config: RealtimeConfig, owner: RealTimeClock) -> Granted:
    g = Granted()
    try:
        owner._saved_sched = (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(config.priority))
        g.sched, g.priority = "SCHED_FIFO", config.priority
    except (OSError, AttributeError) as exc:
        owner._saved_sched = None
        g.notes.append(f"SCHED_FIFO refused ({getattr(exc, 'strerror', None) or exc})")
    if config.cpu is not None:
        try:
            owner._saved_affinity = os.sched_getaffinity(0)
            os.sched_setaffinity(0, {config.cpu})
        except (OSError, AttributeError) as exc:
            owner._saved_affinity = None
            g.notes.append(f"CPU {config.cpu} pinning refused ({getattr(exc, 'strerror', None) or exc})")
    try:
        g.cpus = ",".join(str(c) for c in sorted(os.sched_getaffinity(0)))
    except (OSError, AttributeError):
        g.cpus = ""
    if config.lock_memory:
        g.memory_locked = _mlockall(g)
    return g


def release_realtime(owner: RealTimeClock) -> None:
    if owner._saved_sched is not None:
        try:
            policy, prio = owner._saved_sched
            os.sched_setscheduler(0, policy, os.sched_param(prio))
        except OSError:
            pass
        owner._saved_sched = None
    if owner._saved_affinity is not None:
        try:
            os.sched_setaffinity(0, owner._saved_affinity)
        except OSError:
            pass
        owner._saved_affinity = None


def _mlockall(g: Granted) -> bool:
    import ctypes  # (and ctypes.util's subprocess: a real-time run's, not every run's import, bench B91)
    import ctypes.util

    name = ctypes.util.find_library("c")
    if not name:
        g.notes.append("mlockall unavailable")
        return False
    libc = ctypes.CDLL(name, use_errno=True)
    MCL_CURRENT, MCL_FUTURE = 1, 2
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
        g.notes.append(f"mlockall refused ({os.strerror(ctypes.get_errno())})")
        return False
    return True


def make_clock(cycle: float, realtime: bool, config: RealtimeConfig | None = None) -> LockStepClock | RealTimeClock:
    return RealTimeClock(cycle, config) if realtime else LockStepClock(cycle)
