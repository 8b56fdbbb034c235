"""A 100 000-pass WHILE, then a move, over EtherCAT in lock-step against the virtual slaves (veth,
root): does the statement budget (decisions B2) keep every cycle short enough for the slaves' SM
watchdog? Prints the run's outcome and the wall-clock gaps between cycles. Measures, never asserts.

    sudo python benchmarks/bench_macro_loop_ethercat.py
"""

from __future__ import annotations

import sys
import time

from fieldbus.ethercat.link import EthercatLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from nc.program import parse_program
from virtual_bus.ethercat.veth import SimProcess, can_create

PROGRAM = "G98\n#1=0\nWHILE[#1LT100000]DO1\n#1=#1+1\nEND1\nG01 Z90. F3000\nM30\n"


def main() -> int:
    why = can_create()
    if why is not None:
        print(f"skipped: {why}")
        return 0
    bench = default_lathe()
    bench.mlc = "basic"
    gaps: list[float] = []
    last: list[float | None] = [None]

    def on_cycle(r: BenchRunner) -> None:
        now = time.perf_counter()
        if last[0] is not None and r.cycle > 10:  # after bring-up
            gaps.append(now - last[0])
        last[0] = now

    with SimProcess(tag="b") as sim:
        link = EthercatLink.for_bench(bench, sim.iface)
        r = BenchRunner(bench, link, on_cycle=on_cycle).run_program(parse_program(PROGRAM, name="while.nc"))
    gaps.sort()
    pick = lambda q: gaps[min(len(gaps) - 1, int(len(gaps) * q))] * 1e3  # noqa: E731
    print(f"completed {r.ok}  alarms {[a.code_text for a in r.alarms] or 'none'}  cycles {r.cycles}  "
          f"simulated {r.sim_time:.3f} s")
    print(f"cycle-to-cycle wall gap: p50 {pick(0.5):.3f} ms  p99 {pick(0.99):.3f} ms  max {gaps[-1] * 1e3:.2f} ms "
          "(the slaves' SM watchdog: 100 ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
