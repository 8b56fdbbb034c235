"""What every fault test asserts after its alarm (issue 15): nothing moves beyond the braking
distance, the axes come to rest, and no drive is left energised while moving.

`Recorder` is a runner's on_cycle hook; `assert_stopped_after_alarm` judges what it saw. The
braking distance from speed v is bounded by the slower of the axis's acceleration and the drive's
quick-stop ramp (0x6085), plus the jerk-limited start of the stop and a few cycles of detection."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hil.runner import BenchRunner, RunResult
from virtual_bus.drive import DriveParams

DETECT_S = 0.005  # cycles between the fault and the stop's first braking setpoint


@dataclass
class Recorder:
    runner: BenchRunner | None = None
    pos: list[list[float]] = field(default_factory=list)
    vel: list[list[float]] = field(default_factory=list)
    alarms: list[int] = field(default_factory=list)
    chain: object | None = None  # another on_cycle hook to call first (the test's fault injection)

    def __call__(self, r: BenchRunner) -> None:
        if self.chain is not None:
            self.chain(r)
        self.runner = r
        n = len(r.axes)
        self.pos.append(r.actual.tolist())
        self.vel.append([r.scales[i].drive_to_velocity(r.tx[i].velocity_actual) for i in range(n)])
        self.alarms.append(len(r.result.alarms) + (len(r.channel.alarms) if r.channel is not None else 0))


def braking_distance(v: float, accel: float, jerk: float, lag: float = 0.0) -> float:
    """From speed v, possibly still accelerating at `accel`: the acceleration ramps down (v grows by
    a²/2j meanwhile), then a jerk-limited stop; plus detection and the position filter's window
    `lag` (its output goes on rising for a whole window after the input turns)."""
    t_ramp = accel / jerk
    v_top = v + accel * (t_ramp / 2 + lag)
    return v_top * t_ramp + v_top * v_top / (2 * accel) + v_top * t_ramp + v_top * (DETECT_S + lag) + 0.01


def assert_stopped_after_alarm(rec: Recorder, result: RunResult, lost: tuple[str, ...] = ()) -> None:
    """`lost`: axes whose drive left the bus (their feedback froze; only their travel is judged)."""
    assert result.alarms, "the fault raised no alarm"
    r = rec.runner
    assert r is not None
    first = next(k for k, n in enumerate(rec.alarms) if n)
    pos, vel = np.array(rec.pos), np.array(rec.vel)
    final = np.array([result.final[a] for a in r.axes])
    qs = DriveParams().quick_stop_decel
    axes = r.bench.axes
    # A path stop brakes each axis at its share of the path's deceleration, which is at least the
    # weakest axis's (or drive ramp's): bound every axis's travel by the path's stopping distance.
    accel = min(min(a.limits.max_acceleration, r.scales[i].to_units(qs)) for i, a in enumerate(axes))
    jerk = min(a.limits.max_jerk for a in axes)
    v_path = float(np.linalg.norm(vel[max(0, first - 1)]))
    n1, n2 = r.bench.motion_config().filter_cycles()
    bound = braking_distance(v_path, accel, jerk, lag=(n1 + n2) * r.bench.cycle)
    for i, ax in enumerate(axes):
        ref = pos[max(0, first - 1), i]
        moved = max(np.abs(pos[first:, i] - ref).max(initial=0.0), abs(final[i] - ref))
        assert moved <= bound, f"{ax.name} moved {moved:.4f} after the alarm; braking distance {bound:.4f}"
        if ax.name not in lost:
            assert abs(vel[-1, i]) < 0.01, f"{ax.name} still moving at the end ({vel[-1, i]:.3f})"
    for i, m in enumerate(r.masters):
        assert not m.enabled or r._name(i) in lost, f"drive {r._name(i)} left enabled"
