"""Motion benchmarks: print figures, assert nothing.  Run: python benchmarks/bench_motion.py"""

from __future__ import annotations

import math
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from hil.bench import FILTER_MS, PATH_DEVIATION  # noqa: E402
from nc.interp import Interpreter  # noqa: E402
from nc.motion.offline import run  # noqa: E402
from nc.motion.planner import Planner  # noqa: E402
from nc.moves import Move  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402
from tests.motion_helpers import AX, arc, circle_chords, lines, mill_cfg  # noqa: E402


def cam_moves(n: int, seed: int = 3):
    """A stream (generator) of n segments 0.01–0.1 mm on a smooth curve."""
    rng = np.random.default_rng(seed)
    x, prev = 0.0, {"X": 0.0, "Y": 0.0, "Z": 0.0}
    for k in range(n):
        x += float(rng.uniform(0.01, 0.1))
        e = {"X": x, "Y": 20.0 * math.sin(x / 40.0), "Z": 0.0}
        yield Move("line", k + 1, "", prev, e, e, feed=3000.0, plane=("X", "Y"))
        prev = e


def plan_only(pl: Planner, moves) -> None:
    """Plan without executing: push; whenever the queue is full, do what starting the head block
    does first (the look-ahead's backward pass) and drop that block as if it had run."""
    for mv in moves:
        pl.push(mv)
        while pl.full:
            pl.lookahead()
            pl.blocks.popleft()


def bench_a2() -> None:
    cfg = mill_cfg()
    moves = []
    for i in range(20):
        moves += lines([(0, 0, 0), (40, 0, -1), (40, 30, -1)], 6000)
        moves.append(arc((40, 30, -1), (0, 30, -1), (20, 30), "ccw", 6000))
        moves += lines([(0, 30, -1), (0, 0, 0)], 6000)
    t = time.perf_counter()
    st = run(moves, cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
    w = time.perf_counter() - t
    cycles = len(st.positions) - 1
    print(f"(a) 3-axis offline setpoints: {cycles} cycles in {w:.3f} s = {cycles / w:,.0f} cycles/s, "
          f"{st.time / w:.0f}x real time at 1 ms")


class _Clock:
    """Wall time and this process's CPU time: on a shared machine the CPU-time rate is the
    stable figure (wall time also counts the cycles other processes took)."""

    def __enter__(self) -> "_Clock":
        self.w0, self.c0 = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.w0
        self.cpu = max(time.process_time() - self.c0, 1e-9)

    def rate(self, n: int) -> str:
        return f"{n / self.wall:,.0f} blocks/s ({n / self.cpu:,.0f} per CPU-second)"


def bench_b(n: int = 100_000) -> None:
    cfg = mill_cfg()
    pl = Planner(cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
    moves = cam_moves(n)
    with _Clock() as c:
        plan_only(pl, moves)
    print(f"(b) look-ahead planning (push + junction + backward pass) of {n} CAM segments: {c.rate(n)}")
    cycles = [0]
    with _Clock() as c:
        run(cam_moves(20_000), cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0}, keep=False,
            on_cycle=lambda k, ch: cycles.__setitem__(0, k + 1))
    print(f"(b') full execution incl. per-block ruckig and sampling, 20000 CAM segments: {c.rate(20_000)}, "
          f"{cycles[0] * cfg.cycle:.2f} s simulated")


def cam_program(n: int, seed: int = 3) -> str:
    """The same CAM curve as cam_moves, as an NC program of n G01 blocks."""
    rng = np.random.default_rng(seed)
    x, out = 0.0, ["G90 G17 G94 G01 F3000"]
    for _ in range(n):
        x += float(rng.uniform(0.01, 0.1))
        out.append(f"X{x:.4f} Y{20.0 * math.sin(x / 40.0):.4f}")
    out.append("M30")
    return "\n".join(out) + "\n"


def bench_b_interp(n: int = 100_000) -> None:
    cfg = mill_cfg()
    text = cam_program(n)
    with _Clock() as cp:
        prog = parse_program(text)
    with _Clock() as ci:
        for ev in Interpreter(make_profile("nc5-mill", AX)).run(prog):
            pass
    pl = Planner(cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
    moves = 0
    with _Clock() as c:
        for ev in Interpreter(make_profile("nc5-mill", AX)).run(prog):
            if isinstance(ev, Move):
                plan_only(pl, (ev,))
                moves += 1
    both = _Clock()
    both.wall, both.cpu = c.wall + cp.wall, c.cpu + cp.cpu
    print(f"(b) interpreter + look-ahead planning of a {n}-block CAM program: {c.rate(moves)}")
    print(f"(b) ... parsing the text alone: {cp.rate(n)}; interpreting alone: {ci.rate(moves)}; "
          f"parse + interpret + plan: {both.rate(moves)}")
    # The same with a bench's default position filter (N1.036/N1.037) and N1.053 tolerance, whose
    # windowed corner budgets the planner keeps per junction (hil.bench.Bench.motion_config).
    filt = FILTER_MS / 1000.0
    cfg = mill_cfg(filter_time=filt, filter_scurve=filt, path_tolerance=PATH_DEVIATION, min_segment_cycles=0.25)
    pl = Planner(cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
    with _Clock() as c:
        for ev in Interpreter(make_profile("nc5-mill", AX)).run(prog):
            if isinstance(ev, Move):
                plan_only(pl, (ev,))
    both.wall, both.cpu = c.wall + cp.wall, c.cpu + cp.cpu
    print(f"(b) ... with a bench's default filter {FILTER_MS:g}+{FILTER_MS:g} ms and {PATH_DEVIATION} mm tolerance: "
          f"interpreter + planning {c.rate(moves)}; parse + interpret + plan {both.rate(moves)}")


def bench_c() -> None:
    cfg = mill_cfg()
    pts = circle_chords(100.0, 0.05)
    t = time.perf_counter()
    st = run(lines(pts, 3000), cfg, dict(zip(AX, pts[0])))
    w = time.perf_counter() - t
    ideal = 2 * math.pi * 100.0 / 50.0
    print(f"(c) circle R100 of 0.05 mm chords at F3000: {st.time:.3f} s vs feed-limited {ideal:.3f} s "
          f"(+{100 * (st.time / ideal - 1):.1f} %), wall {w:.2f} s ({(len(st.positions) - 1) / w:,.0f} cycles/s)")
    sq = lines([(0, 0, 0), (100, 0, 0)], 6000)
    st = run(sq, cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
    print(f"(c) single 100 mm line at F6000: {st.time:.3f} s vs lower bound (v={100:.0f} mm/s, half-budget a/j) "
          f"{100 / 100:.3f} s + ramps")


def bench_d() -> None:
    cfg = mill_cfg()
    for n in (2_000, 20_000):
        tracemalloc.start()
        run(cam_moves(n), cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0}, keep=False)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        print(f"(d) peak traced memory, {n} streamed segments: {peak / 1e6:.2f} MB")


if __name__ == "__main__":
    bench_a2()
    bench_b()
    bench_b_interp()
    bench_c()
    bench_d()
