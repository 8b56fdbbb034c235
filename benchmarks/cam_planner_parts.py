"""The CAM program's NC work offline (issue 17): bench_loop's 5,000-block program on benches/mill-3axis.toml
through the interpreter, channel and planner (`nc.motion.offline.run`), no bus. Prints the CPU a cycle of the
whole run, of `Planner.push` a block and of the jerk-factor scans (`shares._scan`) a block, best of 3,
and a digest of the setpoints (equal digests: the same setpoints bit for bit).

    python benchmarks/cam_planner_parts.py            # the figures
    python benchmarks/cam_planner_parts.py --profile  # cProfile of one run, by own time
    python benchmarks/cam_planner_parts.py --opcodes [N]  # Python opcodes a block, first N blocks (1500)

`--opcodes` counts the bytecode instructions the interpreter executes (sys.settrace with per-opcode
events), in `Planner.push` and its callees and in the whole run: a figure that does not move with the
machine's load (CPU time on the shared 2-vCPU VM moves by ±20 %), though it does not see the cost of
one instruction (numpy calls, cache misses).
"""

from __future__ import annotations

import cProfile
import hashlib
import pstats
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))  # PYTHONPATH first: a tree it names is measured

import nc.motion.planner as planner_mod  # noqa: E402
import nc.motion.shares as shares  # noqa: E402
from nc.motion.compiled import BUILD  # noqa: E402
from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.bench_file import load_bench_file  # noqa: E402
from nc.interp import Interpreter  # noqa: E402
from nc.motion.offline import Stream, run  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402

BLOCKS = 5000
_spent = {"push": 0.0, "jf": 0.0}


def _wrap() -> None:
    """CPU time spent in Planner.push and in the jerk-factor scans (≈ 1 µs a call of wrapper). The scans through
    `shares.CHECK`: the planner calls jerk_factor, and it the scan, in C where compiled (decision bench B164)."""
    clock = time.process_time
    push, scan = planner_mod.Planner.push, shares._scan

    def timed_push(self, move):
        t = clock()
        push(self, move)
        _spent["push"] += clock() - t

    def timed_scan(*args):
        t = clock()
        out = scan(*args)
        _spent["jf"] += clock() - t
        return out

    planner_mod.Planner.push = timed_push
    shares.CHECK = timed_scan


def opcodes(n: int) -> None:
    """Python opcodes a block of one offline run of the program's first n blocks."""
    prog = parse_program(cam_program(n), name="cam.nc")
    motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog)
    push_code = planner_mod.Planner.push.__code__
    count = {"all": 0, "push": 0}
    depth = [0]  # Planner.push frames open (its callees' opcodes count as the push's)

    def tracer(frame, event, arg):
        frame.f_trace_opcodes = True
        if event == "opcode":
            count["all"] += 1
            if depth[0]:
                count["push"] += 1
        elif frame.f_code is push_code:
            depth[0] += 1 if event == "call" else -1 if event == "return" else 0
        return tracer

    sys.settrace(tracer)
    try:
        st = run(events, motion, {"X": 0.0, "Y": 0.0, "Z": 100.0})
    finally:
        sys.settrace(None)
    digest = hashlib.sha1(st.positions.tobytes()).hexdigest()[:12]
    print(f"CAM {n} blocks offline, {len(st.positions) - 1} cycles: Python opcodes a block: Planner.push "
          f"{count['push'] / n:.0f}, the whole run {count['all'] / n:.0f}; setpoints {digest}; planner {BUILD} (compiled "
          "modules run no opcodes: DELTAHIL_PYTHON_PLANNER=1 counts the sources)")


def main() -> None:
    if "--opcodes" in sys.argv:
        i = sys.argv.index("--opcodes")
        opcodes(int(sys.argv[i + 1]) if len(sys.argv) > i + 1 else 1500)
        return
    prog = parse_program(cam_program(BLOCKS), name="cam.nc")
    motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()

    def once() -> Stream:
        events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog)
        return run(events, motion, {"X": 0.0, "Y": 0.0, "Z": 100.0})

    once()  # first-use imports and calculators
    if "--profile" in sys.argv:
        prof = cProfile.Profile()
        prof.enable()
        once()
        prof.disable()
        pstats.Stats(prof).sort_stats("tottime").print_stats(30)
        return
    _wrap()
    best = None
    for _ in range(3):
        _spent["push"] = _spent["jf"] = 0.0
        t = time.process_time()
        st = once()
        got = (time.process_time() - t, _spent["push"], _spent["jf"])
        best = got if best is None or got[0] < best[0] else best
    cycles = len(st.positions) - 1
    digest = hashlib.sha1(st.positions.tobytes()).hexdigest()[:12]
    print(f"CAM {BLOCKS} blocks offline, {cycles} cycles: run {best[0] / cycles * 1e6:.1f} µs a cycle, "
          f"Planner.push {best[1] / BLOCKS * 1e6:.1f} µs a block, jerk-factor scans {best[2] / BLOCKS * 1e6:.1f} µs "
          f"a block (CPU, best of 3); setpoints {digest}; planner {BUILD}")


if __name__ == "__main__":
    main()
