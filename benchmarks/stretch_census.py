"""How much of a run could go in stretches (issue 17's "run in stretches between events"), measured on
today's cycle-by-cycle run: a cycle is *quiet* when nothing event-like is pending in it (the channel
runs a plain planned move: no M/S/T handshake, hold, dwell, thread, feed per revolution, G96, G31;
every drive enabled in CSP/CSV; no alarm; the MLC user scan skipped by its on-change gate; no `--at`
event), and a stretch is a run of quiet cycles within one buffer of planned samples (the planner's
`_buf_pos`, re-solved at its end). Prints the share of quiet cycles and the stretch lengths, and what
speed a stretch design would reach for a given cost per stretched cycle.

    python benchmarks/stretch_census.py [--stretch-us 20]
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ["DELTAHIL_STRETCH"] = "0"  # the census looks at every cycle of a stepped run (hil/stretch.py)
ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))

from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.api import run  # noqa: E402
from hil.runner import BenchRunner  # noqa: E402
from nc.channel import RunState  # noqa: E402


def census(program: str, **kw) -> tuple[np.ndarray, float, int]:
    """Per cycle: 1 quiet / 0 not, and the planner buffer index it was in; CPU s of the run's cycles."""
    quiet: list[int] = []
    buf: list[int] = []
    orig = BenchRunner._exchange
    cpu = [0.0]

    def exchange(self: BenchRunner) -> None:
        t = time.thread_time()
        skipped = getattr(getattr(self.mlc, "gate", None), "skipped", None)
        orig(self)
        cpu[0] += time.thread_time() - t
        ch = self.channel
        gate = getattr(self.mlc, "gate", None)
        ok = ch is not None and ch.state is RunState.RUNNING and ch.pending_aux is None
        if ok:
            pl = ch.planner
            mv = pl.blocks[0].move if pl.blocks else None
            ok = (not pl.held and pl._thread is None and pl.threads_queued == 0 and not ch.skip_armed
                  and ch.css_rpm is None and pl.plan is not None and pl.plan.kind != "dwell"
                  and mv is not None and not mv.per_rev and not self._braking
                  and all(m.enabled for m in self.masters) and not self.result.alarms and not ch.alarms
                  and gate is not None and skipped is not None and gate.skipped == skipped + 1)
        quiet.append(1 if ok else 0)
        buf.append(id(ch.planner._buf_pos) if ch is not None else 0)

    BenchRunner._exchange = exchange  # type: ignore[method-assign]
    try:
        r = run(program, check=False, **kw)
    finally:
        BenchRunner._exchange = orig  # type: ignore[method-assign]
    q, b = np.array(quiet), np.array(buf)
    return np.stack([q, b]), cpu[0], r.run.cycles


def stretches(qb: np.ndarray) -> list[int]:
    q, b = qb
    out, n = [], 0
    for k in range(len(q)):
        if q[k] and (n == 0 or b[k] == b[k - 1]):
            n += 1
            continue
        if n:
            out.append(n)
        n = 1 if q[k] else 0
    if n:
        out.append(n)
    return out


def main(argv: list[str]) -> None:
    per = float(argv[argv.index("--stretch-us") + 1]) if "--stretch-us" in argv else 20.0
    with tempfile.TemporaryDirectory() as d:
        cam = Path(d) / "cam5000.nc"
        cam.write_text(cam_program(5000))
        for name, program, kw in (("lathe demo (lathe MLC)", str(ROOT / "examples" / "lathe_demo.nc"), {"mlc": "lathe"}),
                                  ("CAM 5,000 blocks, mill-3axis (lathe MLC)", str(cam),
                                   {"bench": str(ROOT / "benches" / "mill-3axis.toml"), "mlc": "lathe"})):
            qb, cpu, cycles = census(program, **kw)
            lengths = np.array(stretches(qb) or [0])
            quiet = int(qb[0].sum())
            long = int(lengths[lengths >= 10].sum())
            us = cpu / cycles * 1e6
            # in stretches of >= 10 cycles the cycle would cost `per` µs; every other cycle what it costs now
            ideal = (long * per + (cycles - long) * us) / cycles
            print(f"{name}: {cycles} cycles, {us:.0f} CPU µs a cycle now; quiet {quiet} ({quiet / cycles:.0%}); "
                  f"{len(lengths)} stretches, median {int(np.median(lengths))}, p90 {int(np.percentile(lengths, 90))}, "
                  f"max {int(lengths.max())} cycles; in stretches of >= 10: {long} ({long / cycles:.0%}) -> at {per:g} µs "
                  f"a stretched cycle: {ideal:.0f} µs a cycle = {1e6 * 0.001 / ideal:.1f}x real time (1 ms cycle)")


if __name__ == "__main__":
    main(sys.argv[1:])
