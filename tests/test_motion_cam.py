"""Issue 18: dense CAM paths at programmed feed on benches/mill-3axis.toml (N1.036 = N1.037 = 16 ms,
N1.053 = 0.02 mm), in simulated time: program time against the feed-limited bound (LinuxCNC's
times for the same programs are in benchmarks/bench_vs_linuxcnc.py and docs/performance/motion.md),
deviation from the programmed polyline within N1.053, every cycle within the axis limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.bench_vs_linuxcnc import START, Program, cam_polyline, cam_surface, chord_circle
from hil.bench_file import load_bench_file
from nc.motion.offline import Stream, run
from nc.moves import Move
from tests.motion_helpers import TOL, polyline_deviation, worst_ratio

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def moves(prog: Program) -> list[Move]:
    pts = [START] + prog.points
    return [Move("line", k, "", dict(zip("XYZ", pts[k - 1])), dict(zip("XYZ", pts[k])), dict(zip("XYZ", pts[k])),
                 feed=prog.feed, plane=("X", "Y")) for k in range(1, len(pts))]


def cut(prog: Program) -> tuple[Stream, float]:
    """Run offline with the bench's motion settings; returns the stream and its time over the
    feed-limited bound, after asserting the limits and the tolerance."""
    cfg = load_bench_file(BENCH).motion_config()
    st = run(moves(prog), cfg, dict(zip("XYZ", START)))
    assert st.state.value == "finished" and not st.alarms
    r = worst_ratio(st, cfg)
    assert r["v"] <= TOL and r["a"] <= TOL and r["j"] <= TOL, r
    assert polyline_deviation(st.positions, [START] + prog.points) <= cfg.path_tolerance + 1e-9
    return st, st.time / prog.feed_limited()


@pytest.mark.parametrize("radius, bound", [(10.0, 1.041), (5.0, 1.083), (2.0, 1.47)])
def test_chord_circle_keeps_its_feed_within_the_tolerance(radius, bound):
    """0.05 mm chords at F3000 with a lead-in. LinuxCNC 2.9 (G64 P0.02, no jerk limit): r10 1.483 s
    = 1.018× the bound, r5 0.755 s = 1.037×, r2 0.318 s = 1.09×. Before issue 18: 3.98 s (2.73×)
    on r10, 1.63 s (5.6×) on r2; round 1: 1.621 s (1.113×), 0.895 s (1.229×), 0.517 s (1.775×);
    round 2 (slow corners charged at their own speed, decision 37; line-only windows, decision 38)
    1.564 s (1.074×), 0.835 s (1.146×), 0.446 s (1.531×); now (the tangential jerk takes the
    corner budget the junctions leave away from corners the tolerance slows, decision 39)
    1.555 s (1.0675×: 1.049× LinuxCNC's; the bound 1.0685× is 1.05× its 1.483 s), 0.827 s
    (1.136×), 0.446 s (1.531×); with the start from rest, the speed-up out of the lead-in's corner and
    the final stop shaped by the filter (decision 52) 1.516 s (1.0407×: 1.022× LinuxCNC's), 0.788 s
    (1.082×: 1.044× LinuxCNC's 0.755 s), 0.428 s (1.469×: the ring within 1.5×)."""
    st, ratio = cut(chord_circle(radius))
    assert ratio <= bound, ratio
    # on the circle itself (the second half: past the lead-in's corner) the feed holds
    v = np.linalg.norm(np.diff(st.positions, axis=0), axis=1) / st.cycle
    half = v[len(v) // 2: -len(v) // 8]
    if radius >= 5.0:
        assert np.median(half) >= 0.98 * 50.0


@pytest.mark.parametrize("make, bound", [(cam_polyline, 1.023), (cam_surface, 1.042)])
def test_cam_polylines_with_15_degree_vertices(make, bound):
    """400 segments of about 0.78 mm turning about 15° at each vertex (F2500): random corners, and
    chords of a smooth space curve. Each vertex is a real corner at the filter's scale; the
    tolerance holds the speed there (docs/performance/motion.md). Before issue 18 the issue's
    2,000-segment polyline ran at 2.50× the bound; round 1 1.53× and 1.42×, then 1.457× and 1.414×
    (decision 39 raises no jerk near vertices the tolerance slows); blended where the filter's share
    is 0 (decision 45) 1.162× and 1.201×; the blends' jerk shared in quadrature (decision 47) 1.140× and
    1.1885×; fitted as one curve a run, four spans a segment (decisions 56-58) 1.018× and 1.037×."""
    _, ratio = cut(make(400))
    assert ratio <= bound, ratio


@pytest.mark.parametrize("points, bound", [([(20.0, 0.0, 100.0)], 0.433),
                                           ([(10.0, 0.0, 100.0), (10.0, 10.0, 100.0)], 0.460)])
def test_ramps_take_the_jerk_the_corners_leave(points, bound):
    """A 20 mm line, and a 90° corner between 10 mm lines, at F3000 (decision 39). With the
    tangential share's jerk (0.5 × 250 000 mm/s³) each ramp 0 ↔ 50 mm/s takes 40 ms: 0.470 s and
    0.507 s. Away from corners the tolerance slows the ramps take the corner and curvature shares
    too (the whole axis jerk): 28 ms, 0.460 s; the corner's own ramps keep the share, its
    speed-up from rest does not: 0.502 s. The limits, jerk included, and N1.053 hold (cut). Since
    decision 52 the filter shapes the start from rest, the speed-up out of the corner and the final
    stop: 0.433 s and 0.460 s."""
    st, _ = cut(Program("ramps", 3000.0, points))
    assert st.time <= bound + 1e-9, st.time


@pytest.mark.slow  # ≈ 11 s: CI stays under 20 min (run with -m slow; session 30)
def test_the_2000_segment_cam_polyline_keeps_the_tolerance():
    """The benchmark's whole random-corner polyline (bench_vs_linuxcnc: 2 000 segments): a raised
    jerk near the vertices the tolerance slows took two of them to 0.0202 mm (decision 39's first
    form); with none raised there every setpoint stays within N1.053 (cut), at 1.458× the bound; blended
    where the filter's share is 0 (decision 45) 1.171×; the blends' jerk shared in quadrature (decision 47)
    1.146×; fitted as one curve a run, four spans a segment (decisions 56–59) 37.570 s, 1.0099×."""
    _, ratio = cut(cam_polyline())
    assert ratio <= 1.0099 * 1.005, ratio
