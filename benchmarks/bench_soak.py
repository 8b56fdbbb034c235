"""Soak: a looping program (moves and macro statements) on the sim bus in lock-step for ≥ 30 min of
simulated time, through `hil.api.run`. Prints the process RSS every simulated minute and the RSS
slope in MB per simulated minute (least squares over the samples after the first fifth).
Prints figures, asserts nothing (issue 15 item 10, docs/performance/reliability.md).

    python benchmarks/bench_soak.py [--minutes 30] [--preview-log 1000]

`--preview-log -1` keeps every statement in the preview log, as before decisions B3 (the "before"
figure); the default is the profile's bound.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from hil import api

ROOT = Path(__file__).resolve().parents[1]

# One pass: an inner loop of 50 iterations (4 statements each) and two feed moves of 0.2 s each.
PROGRAM = """%
#100=0
#110=0
WHILE[#100LT#101]DO1
#102=0
WHILE[#102LT50]DO2
#102=#102+1
#110=#110+SIN[#102]
END2
G01 X10. F3000
G01 X0.
#100=#100+1
END1
M30
"""


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


class Sampler:
    """`progress` hook of the runner: one RSS sample per simulated minute."""

    def __init__(self, every_s: float = 60.0) -> None:
        self.every = every_s
        self.next = 0.0
        self.samples: list[tuple[float, float]] = []  # (simulated min, RSS MB)
        self.t0 = time.perf_counter()

    def update(self, runner) -> None:
        if runner.time >= self.next:
            self.next += self.every
            mb = rss_mb()
            self.samples.append((runner.time / 60.0, mb))
            print(f"  t = {runner.time / 60.0:5.1f} min simulated  RSS {mb:7.1f} MB  "
                  f"({time.perf_counter() - self.t0:6.0f} s wall)", flush=True)

    def close(self) -> None:
        pass


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--minutes", type=float, default=30.0, help="simulated minutes (default 30)")
    ap.add_argument("--preview-log", type=int, default=None,
                    help='the "preview log" parameter (-1: keep every statement, the old behaviour)')
    a = ap.parse_args()
    passes = int(a.minutes * 60 / 0.4) + 10  # ~0.4 s a pass: the program outlasts the soak
    bench_text = (ROOT / "benches" / "mill-3axis.toml").read_text().split("[checks]")[0]
    bench_text = bench_text.replace("cycle_ms", f"max_time = {a.minutes * 60:g}\ncycle_ms", 1)
    params = {'"max blocks"': 100_000_000}
    if a.preview_log is not None:
        params['"preview log"'] = a.preview_log
    bench_text += "\n[params]\n" + "".join(f"{k} = {v}\n" for k, v in params.items())
    with tempfile.TemporaryDirectory() as tmp:
        bench = Path(tmp) / "soak.toml"
        bench.write_text(bench_text)
        prog = Path(tmp) / "soak.nc"
        prog.write_text(PROGRAM.replace("#101", str(passes)))
        sampler = Sampler()
        print(f"soak: {a.minutes:g} min simulated, mill-3axis on the sim bus, lock-step, "
              f"preview log = {a.preview_log if a.preview_log is not None else 'default'}")
        t0 = time.perf_counter()
        r = api.run(prog, bench, check=False, progress=sampler)
        wall = time.perf_counter() - t0
    s = np.array(sampler.samples)
    tail = s[len(s) // 5:]
    slope = float(np.polyfit(tail[:, 0], tail[:, 1], 1)[0]) if len(tail) >= 2 else float("nan")
    ended = "max_time" if any("max_time" in al.message for al in r.alarms) else (r.alarms or "completed")
    print(f"soak: {r.run.cycles} cycles, {r.run.sim_time / 60:.1f} min simulated in {wall:.0f} s wall "
          f"(ended by {ended}); RSS {s[0, 1]:.1f} -> {s[-1, 1]:.1f} MB; "
          f"slope {slope:+.3f} MB/min over the last {len(tail)} samples")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
