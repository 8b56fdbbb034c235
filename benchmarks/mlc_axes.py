"""MLC axes (decisions mlc M26-20 … M26-27): what NC / MLC axis switching adds to every lock-step cycle when no
axis is the MLC's (a plain G01 active on benches/mill-3axis.toml), each part timed alone, and the wall time of a
short run whose X is switched to the MLC and moved, stepped. Prints, asserts nothing.

    python benchmarks/mlc_axes.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # this tree, not an installed one

from hil.scripting import Machine, mlc_setup  # noqa: E402
from hil.session import load_bench, make_link  # noqa: E402


def machine() -> Machine:
    bench = load_bench(str(ROOT / "benches" / "mill-3axis.toml"), None, None)
    mlc, _, _ = mlc_setup(bench, "lathe", None, 0.5)
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    return m


def best(f, n: int = 200_000, rep: int = 7) -> float:
    out = []
    for _ in range(rep):
        t = time.perf_counter_ns()
        for _ in range(n):
            f()
        out.append((time.perf_counter_ns() - t) / n)
    return min(out)


def per_cycle_cost() -> None:
    m = machine()
    m.start_program("G90 G01 X100. F60.\nM30\n")
    m.wait_until(lambda: m.command("X") > 0.5, 5.0)
    link, mem, b2 = m.mlc.link, m.mlc.mem.m, 20000 + 1000 * m.x
    r, n = m.runner, len(link.axes)
    levels = link._mlc_levels

    base = best(lambda: None)
    parts = {
        "M2x432+i levels: slice and compare (ChannelLink.nc_inputs)": lambda: mem[b2 + 432:b2 + 432 + n] != levels,
        "ChannelLink._manual: link.mlc_axes": lambda: link.mlc_axes,
        "BenchRunner._cycle: link.mlc_axes or _mlc_axes": lambda: link is not None and (link.mlc_axes or r._mlc_axes),
        "stretch _quiet: r._mlc_axes": lambda: r._mlc_axes,
    }
    total = 0.0
    for name, f in parts.items():
        ns = best(f) - base
        total += ns
        print(f"  {name:62s} {ns:6.1f} ns")
    print(f"  {'added per cycle':62s} {total:6.1f} ns")
    m.close()


if __name__ == "__main__":
    print("per cycle, no MLC axis, a plain G01 active (best of 7 x 200k, a closure's call subtracted):")
    per_cycle_cost()
