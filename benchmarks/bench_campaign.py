"""Campaign throughput: cases per minute run serially in one process and on the local Dask cluster
of this machine (one worker process per core), on the same campaign, side by side.

    python benchmarks/bench_campaign.py [REPEAT]

The campaign is the test matrix (tests/data/campaign: short lathe cases, with an alarm and an
E-stop injection) at 3 × REPEAT distinct feed overrides, plus examples/lathe_demo.nc (14.5 s
simulated) at REPEAT overrides, so no case is a cached result and cluster start-up (~3 s) is
amortised as in a real campaign. Wall-clock figures: they measure, they
assert nothing. Record them in docs/performance/campaign.md.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hil.campaign import Engine, run_campaign  # noqa: E402


def main() -> None:
    repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        shutil.copytree(ROOT / "tests" / "data" / "campaign", data)
        overrides = ", ".join(str(50 + 5 * i) for i in range(3 * repeat))
        text = (data / "campaign.toml").read_text().replace("overrides = [50, 100, 150]", f"overrides = [{overrides}]")
        shutil.copy(ROOT / "examples" / "lathe_demo.nc", data / "lathe_demo.nc")
        text += "".join(f"\n[[case]]\nprogram = 'lathe_demo.nc'\nbench = 'bench.toml'\noverride = {100 - 10 * i}\n"
                        for i in range(repeat))
        (data / "campaign.toml").write_text(text)
        figures = {}
        for label, engine in (("serial (1 process)", Engine(workers=0)),
                              (f"local cluster ({os.cpu_count()} workers)", Engine())):
            t0 = time.perf_counter()
            outcome = run_campaign(data / "campaign.toml", Path(tmp) / label.split()[0], engine, rerun=True,
                                   reports=False)
            wall = time.perf_counter() - t0
            n = len(outcome.rows)
            figures[label] = n / wall * 60
            print(f"{label:<28} {n} cases in {wall:6.1f} s  = {figures[label]:6.1f} cases/min")
        s, c = figures.values()
        print(f"ratio local cluster / serial: {c / s:.2f}  (cluster start-up included)")


if __name__ == "__main__":
    main()
