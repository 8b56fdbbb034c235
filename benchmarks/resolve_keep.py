"""What keeping a plan across a block boundary does to the CAM program (issue 17, session 12: the brief's step 1, not
landed). An oracle: every re-solve at a block boundary after a path plan emitted samples (`nc.motion.sample_rows`)
still runs, and where the new plan ends where the old one does (duration and run end within 1e-12) and its
positions at 50 times along it lie within `--tol` mm of the old plan continued, the old plan is kept instead (its
base moved to the next block). That is the most any check made instead of the solve could keep. Offline run of
bench_loop's 5,000-block program on benches/mill-3axis.toml against the same run without the oracle: how many
plans were kept, the cycles, the largest setpoint difference and the first cycle it passes 1e-9 mm. Changes nothing.

    python benchmarks/resolve_keep.py [--tol 1e-15] [--blocks 5000]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))  # PYTHONPATH first: a tree it names is measured

import nc.motion.planner as planner_mod  # noqa: E402
from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.bench_file import load_bench_file  # noqa: E402
from nc.interp import Interpreter  # noqa: E402
from nc.motion.offline import run  # noqa: E402
from nc.motion.plan_state import _Plan  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402


def setpoints(blocks: int) -> np.ndarray:
    prog = parse_program(cam_program(blocks), name="cam.nc")
    motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()
    events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog)
    return run(events, motion, {"X": 0.0, "Y": 0.0, "Z": 100.0}).positions


def kept_run(blocks: int, tol: float) -> tuple[np.ndarray, int, int]:
    """Setpoints with the oracle on; (setpoints, boundary re-solves after a path plan, plans kept)."""
    pending: dict = {}
    count = [0, 0]
    few_rows, plan_path = planner_mod.few_rows, planner_mod.Planner._plan_path

    def watched_rows(pl, p, n):  # benchmark only: sees the re-solve at the block boundary
        t_next, base, length, emitted = p.t_next, p.base, pl.blocks[0].length, p.emitted
        done = few_rows(pl, p, n)
        if done and pl.plan is None and p.kind == "path" and emitted:
            pending["old"] = (p, t_next, base, length)
        return done

    def watched_plan(self, b, t0):
        old = pending.pop("old", None)
        new = plan_path(self, b, t0)
        T = self.cfg.cycle
        if old is None or new is None or new.kind != "path" or t0 != T:
            return new
        p, t_next, base, length = old
        count[0] += 1
        if abs(new.duration - (p.duration - (t_next - T))) > 1e-12 or abs(new.target - (p.target - length)) > 1e-12:
            return new
        t = np.linspace(0.0, new.duration, 50)
        if np.max(np.abs(new.pw.sample(t)[0] - (p.pw.sample(t_next - T + t)[0] - base - length))) > tol:
            return new
        count[1] += 1
        return _Plan("path", p.pw, p.duration, t_next, base=base + length, target=p.target - length, rpm=p.rpm,
                     settled=p.settled, emitted=True, open=new.open, queued=new.queued)

    planner_mod.few_rows, planner_mod.Planner._plan_path = watched_rows, watched_plan
    try:
        return setpoints(blocks), count[0], count[1]
    finally:
        planner_mod.few_rows, planner_mod.Planner._plan_path = few_rows, plan_path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tol", type=float, default=1e-15, help="mm: how close the new plan must follow the old")
    ap.add_argument("--blocks", type=int, default=5000)
    a = ap.parse_args()
    ref = setpoints(a.blocks)
    got, cand, kept = kept_run(a.blocks, a.tol)
    n = min(len(ref), len(got))
    d = np.max(np.abs(ref[:n] - got[:n]), axis=1)
    first = int(np.argmax(d > 1e-9)) if np.any(d > 1e-9) else None
    print(f"CAM {a.blocks:,} blocks: {kept} of {cand} boundary re-solves after a path plan kept (within {a.tol:g} mm)")
    print(f"  cycles {len(ref)} -> {len(got)}; largest |Δ setpoint| over the common cycles {d.max():.3g} mm; "
          f"first cycle over 1e-9 mm: {first}")


if __name__ == "__main__":
    main()
