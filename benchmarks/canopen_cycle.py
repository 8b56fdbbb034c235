"""Wall-clock cost of one lock-step bench cycle on canopen:virtual vs SimLink (lathe demo).

python benchmarks/canopen_cycle.py   -- prints figures, asserts nothing.
"""

from __future__ import annotations

import logging
import time

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import load_program, make_link, sim_slaves

logging.disable(logging.WARNING)
program = load_program("examples/lathe_demo.nc")
for bus in ("sim", "canopen:virtual"):
    bench = default_lathe()
    bench.bus = bus
    link = SimLink(sim_slaves(bench), bench.cycle) if bus == "sim" else make_link(bench)
    t = time.perf_counter()
    r = BenchRunner(bench, link).run_program(program)
    wall = time.perf_counter() - t
    misses = getattr(link, "tpdo_misses", {})
    print(f"{bus:16s} {r.cycles} cycles in {wall:.2f} s = {wall / r.cycles * 1e6:.0f} µs/cycle "
          f"(final {r.final}, TPDO misses {misses})")
