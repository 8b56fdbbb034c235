"""What a feature adds to every lock-step cycle, timed part by part (benchmarks/tap_interrupt.py,
benchmarks/mlc_axes.py): the shipped mill powered up through the scripting API, a best-of timer, and the report."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # this tree, not an installed one

from hil.scripting import Machine, mlc_setup  # noqa: E402
from hil.session import load_bench, make_link  # noqa: E402


def mill_machine() -> Machine:
    """benches/mill-3axis.toml with the lathe MLC module's handshakes, powered up (drives enabled)."""
    bench = load_bench(str(ROOT / "benches" / "mill-3axis.toml"), None, None)
    mlc, _, _ = mlc_setup(bench, "lathe", None, 0.5)
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    return m


def best(f: Callable[[], object], n: int = 200_000, rep: int = 7) -> float:
    """ns a call of f, the best of rep rounds of n calls."""
    out = []
    for _ in range(rep):
        t = time.perf_counter_ns()
        for _ in range(n):
            f()
        out.append((time.perf_counter_ns() - t) / n)
    return min(out)


def report(parts: dict[str, Callable[[], object]], width: int = 62) -> None:
    """Each part's ns less an empty closure's call, and their sum: what the feature adds per cycle."""
    base = best(lambda: None)
    total = 0.0
    for name, f in parts.items():
        ns = best(f) - base
        total += ns
        print(f"  {name:{width}s} {ns:6.1f} ns")
    print(f"  {'added per cycle':{width}s} {total:6.1f} ns")
