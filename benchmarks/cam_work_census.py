"""Work done more than once on bench_loop's 5,000-block CAM program (mill-3axis) offline (issue 17, session 18):
how often the look-ahead's per-block work is done over a block's life in the queue, and the largest cycles.

    python benchmarks/cam_work_census.py

Prints, for one offline run (`nc.motion.offline.run`, as benchmarks/cam_planner_parts.py runs it):
  - the backward passes: how many, blocks recomputed a pass (`reach` calls), times each block is recomputed;
  - the jerk-factor scans' walk over the queue (nc.motion.shares._scan): blocks walked a scan, before the run's
    end and in the reach past it, times each block is walked, and scans whose arguments repeat the last one's;
  - the filter corners' windows (`FilterCorners.window`): the full kernel passes of `_tolerance` among them;
  - the largest cycles by thread CPU (`Channel.step`), and the pushes that dropped junctions from the
    filter corners' history (nc.motion.blending.TRIM).
Counts do not move with the load; the CPU figures do (±20 % on the shared 2-vCPU VM).
"""

from __future__ import annotations

import gc
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))  # PYTHONPATH first: a tree it names is measured

# the planner's sources, not its build (B115): the counts come from replacing module functions, which compiled modules
# calling each other directly would not see
os.environ["DELTAHIL_PYTHON_PLANNER"] = "1"
import nc.channel as channel  # noqa: E402
import nc.motion.blending as blending  # noqa: E402
import nc.motion.lookahead as lookahead  # noqa: E402
import nc.motion.planner as planner  # noqa: E402
import nc.motion.shares as shares  # noqa: E402
from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.bench_file import load_bench_file  # noqa: E402
from nc.interp import Interpreter  # noqa: E402
from nc.motion.offline import run  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402

BLOCKS = 5000


def main() -> None:
    prog = parse_program(cam_program(BLOCKS), name="cam.nc")
    motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()

    def once():
        events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog)
        return run(events, motion, {"X": 0.0, "Y": 0.0, "Z": 100.0})

    once()  # first-use imports
    gc.collect()  # the first run's cycles: not collected inside the measured one
    n = {"passes": 0, "reach": 0, "scans": 0, "pre": 0, "post": 0, "same": 0, "windows": 0, "kernel": 0}
    cycles: list[float] = []
    drops: list[int] = []
    last_args: list[tuple] = [()]
    backward, reach, scan = planner.backward, lookahead.reach, shares._scan
    window, caps, step = blending.FilterCorners.window, blending.KernelDeviation.caps, channel.Channel.step

    def counted_backward(*args, **kw):
        n["passes"] += 1
        return backward(*args, **kw)

    def counted_reach(*args):
        n["reach"] += 1
        return reach(*args)

    def counted_scan(fc, blocks, pos, run_end, reach_, closed, v_stop=-1.0):
        n["scans"] += 1
        hi, stop_s = run_end + reach_, run_end - 1e-9
        for b in blocks:  # the walk's extent, as _scan finds it
            if b.s_end - b.length > hi:
                break
            n["pre" if b.s_end < stop_s else "post"] += 1
        args = (id(blocks[0]), id(blocks[-1]), len(blocks), pos, run_end, reach_, closed, v_stop)
        n["same"] += args == last_args[0]
        last_args[0] = args
        return scan(fc, blocks, pos, run_end, reach_, closed, v_stop)

    def counted_window(fc, blocks):
        n["windows"] += 1
        seq0 = fc._seq0
        out = window(fc, blocks)
        if fc._seq0 != seq0:
            drops.append(len(cycles))
        return out

    def counted_caps(*args):
        n["kernel"] += 1
        return caps(*args)

    def timed_step(self, *args, **kw):
        t = time.thread_time()
        out = step(self, *args, **kw)
        cycles.append(time.thread_time() - t)
        return out

    planner.backward, lookahead.reach, shares._scan = counted_backward, counted_reach, counted_scan
    blending.FilterCorners.window, blending.KernelDeviation.caps = counted_window, counted_caps
    channel.Channel.step = timed_step
    try:
        st = once()
    finally:
        planner.backward, lookahead.reach, shares._scan = backward, reach, scan
        blending.FilterCorners.window, blending.KernelDeviation.caps = window, caps
        channel.Channel.step = step
    c, s = max(n["passes"], 1), max(n["scans"], 1)
    print(f"CAM {BLOCKS} blocks offline, {len(st.positions) - 1} cycles")
    print(f"backward passes {n['passes']}: {n['reach'] / c:.1f} blocks recomputed a pass, each block "
          f"{n['reach'] / BLOCKS:.1f} times (their reach calls)")
    print(f"jerk-factor scans {n['scans']}: {(n['pre'] + n['post']) / s:.1f} blocks walked a scan ({n['pre'] / s:.1f} "
          f"before the run's end, {n['post'] / s:.1f} past it), each block {(n['pre'] + n['post']) / BLOCKS:.1f} times; "
          f"{n['same']} scans repeat the last one's arguments")
    print(f"filter windows {n['windows']}: {n['kernel']} full kernel passes (_tolerance)")
    top = sorted(range(len(cycles)), key=cycles.__getitem__, reverse=True)[:5]
    print("largest cycles (thread CPU, µs): " + ", ".join(f"{i + 1}: {cycles[i] * 1e6:.0f}" for i in top)
          + f"; junctions dropped at {len(drops)} pushes" + (f" (cycles {drops[0] + 1}…{drops[-1] + 1})" if drops else ""))


if __name__ == "__main__":
    main()
