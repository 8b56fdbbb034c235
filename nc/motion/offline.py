"""Run a program through the channel and planner without a bus: the setpoint stream alone.

Used by `hil motion`, the motion benchmarks and the tests that check every cycle's finite
differences against the axis limits. M/S/T codes are acknowledged on the next cycle; the spindle
runs at the programmed S unless a `spindle_rpm` callable says otherwise.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np

from nc.channel import Channel, RunState
from nc.motion.limits import MotionConfig
from nc.motion.planner import Planner
from nc.moves import Event


@dataclass
class Stream:
    positions: np.ndarray  # (cycles + 1, axes): the start position, then one row per cycle
    lines: np.ndarray
    cycle: float
    axes: tuple[str, ...]
    state: RunState
    alarms: list = field(default_factory=list)

    @property
    def time(self) -> float:
        return (len(self.positions) - 1) * self.cycle

    def derivatives(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Finite-difference velocity, acceleration and jerk per axis (as a drive sees them).

        The stream is padded with the start position before and the final position after, so
        starting and stopping are checked too.
        """
        p = np.vstack([self.positions[:1]] * 3 + [self.positions] + [self.positions[-1:]] * 3)
        T = self.cycle
        v = np.diff(p, axis=0) / T
        a = np.diff(v, axis=0) / T
        j = np.diff(a, axis=0) / T
        return v, a, j

    def peaks(self) -> dict[str, tuple[float, float, float]]:
        v, a, j = self.derivatives()
        return {ax: (float(np.abs(v[:, i]).max()), float(np.abs(a[:, i]).max()), float(np.abs(j[:, i]).max()))
                for i, ax in enumerate(self.axes)}


class _Collector:
    def __init__(self, n_axes: int, keep: bool) -> None:
        self.keep = keep
        self.chunks: list[np.ndarray] = []
        self.lines: list[int] = []
        self.count = 0
        self.last: np.ndarray | None = None


def run(events: Iterable[Event] | Iterator[Event], cfg: MotionConfig, start: dict[str, float] | None = None,
        spindle_rpm: Callable[[], float] | None = None, max_cycles: int = 10_000_000, keep: bool = True,
        on_cycle: Callable[[int, Channel], None] | None = None, fit_memo=None,
        param_groups: dict[int, MotionConfig] | None = None) -> Stream:
    """Step the channel until the program ends; `keep=False` keeps only the last position (streaming).
    `fit_memo`: where the planner's fitted runs take and leave their windows (nc.motion.fit_memo).
    `param_groups`: the settings G05 P1-P20 switch to (`cfg` is P0's; decision language L25-1)."""
    ch: Channel
    rpm_box = {"rpm": 0.0}
    planner = Planner(cfg, start, spindle_rpm=spindle_rpm or (lambda: rpm_box["rpm"]))
    if fit_memo is not None and planner._runs is not None:
        planner._runs.memo = fit_memo
    ch = Channel(planner)
    if param_groups:
        ch.param_groups = {**param_groups, 0: cfg}
    ch.load(iter(events))
    ch.cycle_start()
    rows = [planner.position.copy()]
    lines = [0]
    n = 0
    while ch.busy and n < max_cycles:
        if ch.pending_aux is not None:
            if ch.pending_aux.kind == "S":
                rpm_box["rpm"] = abs(ch.pending_aux.value)
            ch.finish_aux()
        if on_cycle is not None:
            on_cycle(n, ch)
        sp = ch.step()
        n += 1
        if keep:
            rows.append(sp.positions)
            lines.append(sp.line)
        else:
            rows[0] = sp.positions
    return Stream(np.array(rows), np.array(lines), cfg.cycle, cfg.axes, ch.state, list(ch.alarms))
