"""The motion sweep's last seeds over a limit (decisions motion 83 (c) and 84), each its program cut to the
shortest start that still went over a limit before the fix (the sweep's program for the seed, tests/motion_sweep.py,
its operator included, its first k moves run to their end), and the CAM program's speed-up past its feed that the
same fix ends. A drive must see every cycle within the axes' velocity, acceleration and jerk, no setpoint going back
along the path, and the end reached; the programmed feed is the path's top speed."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_motion import cam_program
from tests.conftest import ROOT
from tests.test_fit26_fitted_runs import check, first_moves


def test_a_missed_re_solve_keeps_the_profile_it_was_following():
    """Solved again at a block boundary from a state on its own profile, ruckig missed the same target (0.6 µm
    past it, back at −1.1 mm/s); the fallback ramp then crossed a stop between two fitted runs at 0.55 mm/s
    (before: jerk 3.32x the limit; seed 360 whole: the miss is at its last moves, every shorter start passes)."""
    check(first_moves(360, 134))


@pytest.mark.parametrize("seed, k", [(1, 20), (498, 4)])
def test_a_resume_near_a_sharp_corner_crosses_it_within_its_budget(seed, k):
    """A feed hold stood a few µm before a sharp corner (Δu 1.64 and 1.88); the resume could not reach the
    corner's junction speed there, so the run went through it accelerating at ≈ 900 mm/s²: the acceleration step
    a·Δu the corner makes per axis added to its velocity step (before: jerk 1.108x and 1.107x)."""
    check(first_moves(seed, k))


def test_the_cam_program_never_runs_faster_than_its_feed(hil, tmp_path):
    """F3000 (50 mm/s) over 300 CAM chords on the mill: where ruckig missed a re-solve in the first speed-up,
    the fallback ramp accelerated past the feed (53.3 mm/s through the filter, cycles 47–60) before the next
    block's solve brought it back. The commanded path speed stays within the feed on every cycle."""
    import pyarrow.parquet as pq

    prog = tmp_path / "cam.nc"
    prog.write_text(cam_program(300))
    trace = tmp_path / "t.parquet"
    res = hil("run", str(prog), "--bench", str(ROOT / "benches" / "mill-3axis.toml"), "--trace", str(trace), "--no-check")
    assert res.code == 0, res.out + res.err
    t = pq.read_table(trace)
    pos = np.array([t.column(f"{a}_cmd").to_pylist() for a in "XY"]).T
    speed = np.linalg.norm(np.diff(pos, axis=0), axis=1) / 0.001  # chord per 1 ms cycle: at most the path speed
    assert speed.max() <= 50.0 * (1.0 + 1e-6), f"{speed.max():.3f} mm/s at cycle {int(np.argmax(speed)) + 1}"
    last = cam_program(300).splitlines()[-2]  # "X… Y…", the last move before M30
    x, y = (float(w[1:]) for w in last.split())
    assert abs(pos[-1][0] - x) < 1e-5 and abs(pos[-1][1] - y) < 1e-5  # (the trace holds drive counts)
