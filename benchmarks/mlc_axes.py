"""MLC axes (decisions mlc M26-20 … M26-27): what NC / MLC axis switching adds to every lock-step cycle when no
axis is the MLC's (a plain G01 active on benches/mill-3axis.toml), each part timed alone. Prints, asserts nothing.

    python benchmarks/mlc_axes.py
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this tree, not an installed one

from benchmarks.cycle_parts import mill_machine as machine, report  # noqa: E402


def per_cycle_cost() -> None:
    m = machine()
    m.start_program("G90 G01 X100. F60.\nM30\n")
    m.wait_until(lambda: m.command("X") > 0.5, 5.0)
    link, mem, b2 = m.mlc.link, m.mlc.mem.m, 20000 + 1000 * m.x
    r, n = m.runner, len(link.axes)
    levels = link._mlc_levels

    report({
        "M2x432+i levels: slice and compare (ChannelLink.nc_inputs)": lambda: mem[b2 + 432:b2 + 432 + n] != levels,
        "ChannelLink._manual: link.mlc_axes": lambda: link.mlc_axes,
        "BenchRunner._cycle: link.mlc_axes or _mlc_axes": lambda: link is not None and (link.mlc_axes or r._mlc_axes),
        "stretch _quiet: r._mlc_axes": lambda: r._mlc_axes,
    })
    m.close()


if __name__ == "__main__":
    print("per cycle, no MLC axis, a plain G01 active (best of 7 x 200k, a closure's call subtracted):")
    per_cycle_cost()
