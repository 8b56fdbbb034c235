"""Seeded random programs for the motion sweep (tests/test_motion_sweep.py): lines of mixed lengths (5 µm to
10 mm) turning at any angle, some arcs, with or without the position filter (N1.036/N1.037) and the path
tolerance (N1.053), feeds from F600 to F15000, and an operator who turns the feed override or presses feed hold
and Cycle Start at random cycles. What a controller engineer checks on any of them: every cycle within the
axes' velocity, acceleration and jerk, no setpoint going back along the path, and the program's end reached."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from nc.channel import Channel, RunState
from nc.motion import MotionConfig
from nc.motion.offline import Stream, run
from nc.moves import Move
from tests.motion_helpers import AX, arc, lines, mill_cfg, worst_ratio

MAX_CYCLES = 400_000
LENGTHS = ([0.005, 0.02, 0.2, 2.0], [0.01, 0.05, 0.1], [0.5, 2.0, 10.0])  # CAM-like, fine, coarse


@dataclass
class Case:
    seed: int
    moves: list[Move]
    cfg: MotionConfig
    end: np.ndarray
    ops: list[tuple[int, str, float]] = field(default_factory=list)  # (cycle, "ovr" | "hold" | "start", value)

    def describe(self) -> str:
        return (f"seed {self.seed}: {len(self.moves)} moves, filter {self.cfg.filter_time * 1000:g} ms, "
                f"N1.053 {self.cfg.path_tolerance}, F{self.moves[0].feed:g}, operator {self.ops}")


def make_case(seed: int) -> Case:
    rng = np.random.default_rng(seed)
    ms = float(rng.choice([0.0, 4.0, 8.0, 16.0, 32.0]))
    tol = [None, 0.005, 0.01, 0.02][int(rng.integers(4))]
    feed = float(rng.choice([600.0, 3000.0, 6000.0, 15000.0]))
    kw: dict = {"filter_time": ms / 1000.0, "filter_scurve": ms / 1000.0, "path_tolerance": tol}
    if ms:
        kw["min_segment_cycles"] = 0.25
    cfg = mill_cfg(**kw)
    n = int(rng.integers(20, 150))
    lens = rng.choice(LENGTHS[int(rng.integers(3))], n)
    z_share = float(rng.choice([0.0, 0.3]))
    pts = [np.zeros(3)]
    for k in range(n):
        step = rng.normal(0.0, 1.0, 3) * [1.0, 1.0, z_share]
        pts.append(pts[-1] + step / np.linalg.norm(step) * lens[k])
    moves = lines(pts, feed)
    if rng.random() < 0.3:  # some moves as XY arcs through the same end points (centre off the chord's middle)
        for k in range(len(moves)):
            s, e = pts[k], pts[k + 1]
            chord = e[:2] - s[:2]
            if rng.random() < 0.3 and np.linalg.norm(chord) > 1e-3 and abs(e[2] - s[2]) < 1e-12:
                normal = np.array([-chord[1], chord[0]])
                c = (s[:2] + e[:2]) / 2.0 + normal * float(rng.uniform(-2.0, 2.0))
                moves[k] = arc(s, e, c, str(rng.choice(["cw", "ccw"])), feed, line=moves[k].line)
    ops: list[tuple[int, str, float]] = []
    kind = int(rng.integers(4))
    if kind in (1, 3):  # the feed override turned (0 % included: the axes stand until it is turned up again)
        for _ in range(int(rng.integers(1, 5))):
            ops.append((int(rng.integers(1, 1500)), "ovr", float(rng.choice([0.0, 0.05, 0.1, 0.5, 1.0, 1.2, 1.5]))))
    if kind in (2, 3):  # feed hold, then Cycle Start
        t = int(rng.integers(1, 800))
        ops += [(t, "hold", 0.0), (t + int(rng.integers(1, 400)), "start", 0.0)]
    ops.sort(key=lambda o: o[0])
    if any(op == "ovr" for _, op, _ in ops):
        ops.append((3000, "ovr", 1.0))  # the operator turns it back to 100 % in the end
    return Case(seed, moves, cfg, pts[-1], ops)


@dataclass
class Outcome:
    stream: Stream
    ratios: dict[str, float]  # worst |v|, |a|, |j| over the limit, any axis and cycle
    back: float  # the most any cycle's setpoint went back along the path (mm), 0 where none did
    end_error: float  # distance of the last setpoint from the program's end point (mm)


def run_case(case: Case, on_cycle: Callable[[int, Channel], None] | None = None) -> Outcome:
    """The case through the channel and planner, the operator's actions at their cycles; the path position of
    every cycle (the active block's start plus the planner's s in it) is watched for a step back."""
    ops = {}
    for t, op, x in case.ops:
        ops.setdefault(t, []).append((op, x))
    last = {"s": -np.inf, "back": 0.0}

    def ctl(n: int, ch: Channel) -> None:
        for op, x in ops.get(n, ()):
            if op == "ovr":
                ch.feed_override = x
            elif op == "hold":
                ch.feed_hold()
            else:
                ch.cycle_start()
        pl = ch.planner
        if pl.blocks and pl._started:
            b = pl.blocks[0]
            s = b.s_end - b.length + pl.s
            if s < last["s"]:
                last["back"] = max(last["back"], last["s"] - s)
            last["s"] = s
        if on_cycle is not None:
            on_cycle(n, ch)

    st = run(case.moves, case.cfg, dict(zip(AX, (0.0, 0.0, 0.0))), on_cycle=ctl, max_cycles=MAX_CYCLES)
    assert st.state is RunState.FINISHED, f"{case.describe()}: {st.state.name} after {len(st.positions)} cycles"
    return Outcome(st, worst_ratio(st, case.cfg), last["back"], float(np.abs(st.positions[-1] - case.end).max()))
