"""How far the CAM program's re-solves at a block boundary land from the plan they replace (issue 17, the brief's
step 2: a solved plan sampled across blocks, re-solved only where the answer could differ). Offline run of
bench_loop's 5,000-block program on benches/mill-3axis.toml (`nc.motion.offline.run`); for each path plan that
emitted samples and is re-solved where its next sample falls into the next block (`nc.motion.sample_rows`), the
new plan's first ≤ 8 samples against the old plan continued at the same times, and whether the new run ends where
the old one did. Prints counts by the largest position difference; changes nothing.

    python benchmarks/resolve_gap.py
"""

from __future__ import annotations

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
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402


def main() -> None:
    pending: dict = {}
    gaps: list[tuple[float, bool]] = []
    few_rows, plan_path = planner_mod.few_rows, planner_mod.Planner._plan_path

    def watched_rows(pl, p, n):  # benchmark only: sees the re-solve at the block boundary
        t_next, base, length, emitted = p.t_next, p.base, pl.blocks[0].length, p.emitted
        done = few_rows(pl, p, n)
        if done and pl.plan is None and p.kind == "path" and emitted:
            pending["old"] = (p.pw, t_next, base, length, p.target)
        return done

    def watched_plan(self, b, t0):
        old = pending.pop("old", None)
        new = plan_path(self, b, t0)
        if old is not None and new is not None and new.kind == "path" and t0 == self.cfg.cycle:
            pw, t_next, base, length, target = old
            T = self.cfg.cycle
            t = T * np.arange(1, max(1, min(8, int(new.duration / T))) + 1)
            s_new = new.pw.sample(t)[0]  # the new plan starts at the last emitted sample, one cycle back
            s_old = pw.sample(t_next + t - T)[0] - base - length
            gaps.append((float(np.max(np.abs(s_new - s_old))), abs(new.target - (target - length)) < 1e-12))
        return new

    planner_mod.few_rows, planner_mod.Planner._plan_path = watched_rows, watched_plan
    try:
        prog = parse_program(cam_program(5000), name="cam.nc")
        motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()
        events = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog)
        run(events, motion, {"X": 0.0, "Y": 0.0, "Z": 100.0})
    finally:
        planner_mod.few_rows, planner_mod.Planner._plan_path = few_rows, plan_path
    g = np.array([x[0] for x in gaps])
    same = np.array([x[1] for x in gaps])
    print(f"CAM 5,000 blocks: {len(g)} re-solves at a block boundary after emitted samples, {int(same.sum())} "
          "with the run ending where the old one did")
    for lim in (0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-4):
        print(f"  largest |Δs| of the next ≤ 8 samples ≤ {lim:g} mm: {int((g <= lim).sum())} "
              f"(same run end: {int(((g <= lim) & same).sum())})")
    print(f"  largest: {g.max():.3g} mm")


if __name__ == "__main__":
    main()
