"""Bench loop figures: lock-step cycles per second (with and without a Parquet trace), the work
per cycle of a dense CAM program on the mill bench (position filter on), the issue-17 runs
(examples/lathe_demo.nc with the lathe MLC and a Parquet trace, a 5,000-block CAM program on
benches/mill-3axis.toml) as simulated time / wall time with the µs per cycle of each stage, and
the real-time pacer's jitter on this machine. Prints figures, asserts nothing.

Usage: python benchmarks/bench_loop.py [PACER_SECONDS] [--stages-only]"""

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


class _Stage:
    """CPU time of this thread spent in one callable, summed. CPU time, not wall time: on a machine
    shared with other work, wall time mostly measures the others (the wrapper costs ≈ 1 µs a call)."""

    def __init__(self, fn):
        self.fn, self.seconds = fn, 0.0

    def __call__(self, *args, **kwargs):
        t = time.thread_time()
        try:
            return self.fn(*args, **kwargs)
        finally:
            self.seconds += time.thread_time() - t


def staged(label: str, program: Path, bench_file: Path | None, trace: str | None) -> None:
    """One run made by `hil.api.run` as `hil run` makes it (the bench's MLC, the trace, the post-run
    checks), timed by stage: MLC (scan, with the NC↔MLC exchange and the drive-status bridge), NC
    (channel step: interpreter, planner, filter), bus + drives (the link's exchange; on the sim bus
    that is the drive models), trace (row write) and the rest of the cycle (runner bookkeeping,
    CiA 402 masters). Post-run checks and start-up are outside the cycle figures."""
    from hil import api
    from nc.channel import Channel

    stages: dict[str, list[_Stage]] = {"MLC": [], "NC": [], "bus + drives": [], "trace": []}
    original = BenchRunner.run_program
    holder: dict = {}

    def timed_run(runner, prog):  # benchmark only: wraps this run's parts, restored below
        for stage, obj, name in (("MLC", runner.mlc, "scan"), ("MLC", runner.mlc, "bus_feedback"),
                                 ("bus + drives", runner.link, "exchange"), ("trace", runner.trace, "write")):
            if obj is not None and hasattr(obj, name):
                st = _Stage(getattr(obj, name))
                setattr(obj, name, st)
                stages[stage].append(st)
        holder["runner"] = runner
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            return original(runner, prog)
        finally:
            holder["wall"], holder["cpu"] = time.perf_counter() - t0, time.thread_time() - c0

    nc = _Stage(Channel.step)
    stages["NC"].append(nc)
    BenchRunner.run_program = timed_run
    Channel.step = lambda self: nc(self)
    try:
        t0 = time.perf_counter()
        res = api.run(program, str(bench_file) if bench_file else None, trace=trace)
        total = time.perf_counter() - t0
    finally:
        BenchRunner.run_program, Channel.step = original, nc.fn
    r, wall, cpu = res.run, holder["wall"], holder["cpu"]
    n = max(1, r.cycles)
    parts = {k: sum(st.seconds for st in v) for k, v in stages.items()}
    parts["rest"] = cpu - sum(parts.values())
    print(f"{label}: {r.cycles} cycles, {r.sim_time:.2f} s simulated; the cycles took {cpu:.2f} s CPU = "
          f"{r.sim_time / cpu:.1f}x real time ({wall:.2f} s wall = {r.sim_time / wall:.1f}x); whole run incl. "
          f"post-run checks {total:.2f} s wall ({'completed' if r.ok else 'not completed'})")
    print("  CPU µs per cycle: " + "  ".join(f"{k} {v / n * 1e6:.1f}" for k, v in parts.items())
          + f"  | total {cpu / n * 1e6:.1f}")


def issue17(d: str) -> None:
    root = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(root))
    from benchmarks.bench_motion import cam_program

    staged("lathe demo, lathe MLC, Parquet trace", root / "examples" / "lathe_demo.nc", None,
           os.path.join(d, "lathe.parquet"))
    cam = Path(d) / "cam5000.nc"
    cam.write_text(cam_program(5000))
    staged("CAM 5,000 blocks, mill-3axis, Parquet trace", cam, root / "benches" / "mill-3axis.toml",
           os.path.join(d, "cam.parquet"))


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
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    with tempfile.TemporaryDirectory() as d:
        issue17(d)
        if "--stages-only" in sys.argv:
            sys.exit(0)
        lockstep(None)
        lockstep(os.path.join(d, "t.csv"))
        lockstep(os.path.join(d, "t.parquet"))
    cam_work()
    realtime(float(args[0]) if args else 5.0)
