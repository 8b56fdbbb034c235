"""What a block end's stepped cycle costs warm and with cold caches (issue 17).

Usage: python benchmarks/rt_block_ends.py [PROGRAM] [--runs N] [--sweep MB]

A lock-step run (DELTAHIL_STRETCH=0: every cycle through `BenchRunner._cycle`) of the lathe demo with a Parquet
trace; a block end is a cycle after which the planner's first block is another one. Each such cycle's thread CPU
(`time.thread_time_ns`) is taken as it runs (warm: the cycle before it ran the same code), then again in runs
that touch `--sweep` MB of memory right before each block end (every 64th byte: the caches hold other data, as
after a real-time stretch's hundreds of paced cycles). Figures, not a test. The same cycles in a `--realtime` run
are `rt_census.py`'s `stepped: too short` classes.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ["DELTAHIL_STRETCH"] = "0"

import hil.runner as R  # noqa: E402

CYCLES: list[tuple[int, int, bool]] = []  # (cycle, thread CPU ns, a block end)
SWEEP_AT: set[int] = set()


def install(junk: np.ndarray) -> None:
    cycle = R.BenchRunner._cycle

    def _cycle(self, tx, step=None):
        ch = self.channel
        pl = ch.planner if ch is not None else None
        first = pl.blocks[0] if pl is not None and pl.blocks else None
        n = self.cycle + 1
        if n in SWEEP_AT:
            junk[::64] += 1
        t = time.thread_time_ns()
        cycle(self, tx, step)
        dt = time.thread_time_ns() - t
        now = pl.blocks[0] if pl is not None and pl.blocks else None
        CYCLES.append((n, dt, first is not None and now is not first))

    R.BenchRunner._cycle = _cycle


def run(program: str) -> list[tuple[int, int, bool]]:
    from hil import api

    CYCLES.clear()
    with tempfile.TemporaryDirectory() as d:
        api.run(program, None, trace=os.path.join(d, "t.parquet"), check=False)
    return list(CYCLES)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("program", nargs="?", default=str(ROOT / "examples" / "lathe_demo.nc"))
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--sweep", type=int, default=64, help="MB touched before each block end in the cold runs")
    args = ap.parse_args()
    install(np.ones(args.sweep << 20, dtype=np.uint8))
    for k in range(args.runs):
        for cold in (False, True):
            cycles = run(args.program)  # the cold run sweeps before the block ends the warm run found
            SWEEP_AT.clear()
            if not cold:
                SWEEP_AT.update(c for c, _, end in cycles if end)
            ends = np.array([ns for _, ns, end in cycles if end]) / 1e3
            rest = np.array([ns for _, ns, end in cycles if not end]) / 1e3
            print(f"run {k + 1} {'cold' if cold else 'warm'}: {len(cycles)} cycles, {len(ends)} block ends: p50 "
                  f"{np.percentile(ends, 50):.0f} µs, p90 {np.percentile(ends, 90):.0f} µs, max {ends.max():.0f} µs; "
                  f"other cycles p50 {np.percentile(rest, 50):.0f} µs")

if __name__ == "__main__":
    main()
