"""Bench loop figures: lock-step cycles per second (with and without a Parquet trace), the work
per cycle of a dense CAM program on the mill bench (position filter on), and the real-time
pacer's jitter on this machine. Prints figures, asserts nothing."""

from __future__ import annotations

import os
import sys
import tempfile
import time

from pathlib import Path

from hil.bench import default_lathe
from hil.bench_file import load_bench_file
from hil.clock import RealTimeClock
from hil.runner import BenchRunner
from hil.session import make_link
from hil.trace import open_trace
from nc.program import parse_program

PROGRAM = "G98\nM03 S800\nG00 X24. Z2.\nG01 Z-40. F300.\nX30.\nZ-60.\nG00 X60. Z100.\nM30\n"


def lockstep(trace: str | None) -> None:
    bench = default_lathe()
    runner = BenchRunner(bench, make_link(bench), None)
    if trace:
        runner.trace = open_trace(trace, runner.trace_columns())
    t0 = time.perf_counter()
    r = runner.run_program(parse_program(PROGRAM, name="bench.nc"))
    wall = time.perf_counter() - t0
    kind = os.path.splitext(trace)[1] if trace else "no trace"
    print(f"lock-step ({kind:8s}): {r.cycles} cycles, {r.sim_time:.2f} s simulated in {wall:.2f} s wall "
          f"= {r.cycles / wall:,.0f} cycles/s ({r.sim_time / wall:.1f}x real time)")


def cam_work(blocks: int = 3000) -> None:
    """Per-cycle work (wall clock, lock-step) of a CAM program: 0.01–0.1 mm G01 blocks at F3000 on
    benches/mill-3axis.toml, whose 16+16 ms position filter makes planning the heaviest."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from benchmarks.bench_motion import cam_program

    bench = load_bench_file(Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml")
    runner = BenchRunner(bench, make_link(bench), None)
    t0 = time.perf_counter()
    r = runner.run_program(parse_program(cam_program(blocks), name="cam.nc"))
    wall = time.perf_counter() - t0
    e = r.timing.get("exec", {})
    print(f"CAM program, {blocks} blocks on the mill bench: {r.cycles} cycles in {wall:.2f} s wall; work per cycle "
          + "  ".join(f"{k} {e[k] * 1e6:.0f} µs" for k in ("p50", "p99", "p99.9", "max") if k in e))


def realtime(seconds: float) -> None:
    bench = default_lathe()
    clk = RealTimeClock(bench.cycle, bench.realtime)
    clk.start()
    for _ in range(int(seconds / bench.cycle)):
        clk.tick()
        clk.done()
    clk.stop()
    j, lat = clk.jitter.summary(), clk.latency.summary()
    print(f"real-time pacer, {seconds:g} s at 1 ms ({clk.granted}):")
    print("  jitter  " + "  ".join(f"{k} {j[k] * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")))
    print("  latency " + "  ".join(f"{k} {lat[k] * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")))
    print(f"  overruns {clk.overruns}")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as d:
        lockstep(None)
        lockstep(os.path.join(d, "t.csv"))
        lockstep(os.path.join(d, "t.parquet"))
    cam_work()
    realtime(float(sys.argv[1]) if len(sys.argv) > 1 else 5.0)
