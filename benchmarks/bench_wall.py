"""The user's `hil run` process wall (issue 17): what a user times, the whole command from exec to exit.

    python benchmarks/bench_wall.py [--repeat N] [--blocks N] [--tree DIR ...] [--json]

Runs, as a user types them, in a subprocess of this interpreter (sys.executable, not the pyenv shim):
  lathe  `hil run examples/lathe_demo.nc --trace t.parquet` (the lathe bench and its MLC)
  cam    `hil run cam.nc --bench benches/mill-3axis.toml --trace cam.parquet`, a 5,000-block CAM program
         (benchmarks/bench_motion.cam_program)
and prints per case: simulated time, process wall (best and median of N, rounds interleaved over cases and trees),
the child's CPU (user + system; on a shared machine the steadier figure), ×real time by the wall (simulated / best
wall), the imports of the run (`-X importtime` of one more run: the top-level modules' cumulative time, lazy imports
inside the run included, and the module count), and beside it LinuxCNC's `rs274 -g` interpreting the same program
file (its whole process wall; skipped with rs274's reason where it cannot read the program, or absent). Also the
bare interpreter (`python -c pass`: start-up and site, the floor under every figure). Asserts nothing.

--tree DIR (repeatable): run `hil` from that source tree (PYTHONPATH, cwd), e.g. a checkout of another commit, for
interleaved before/after figures. The child's environment drops PYTHONDONTWRITEBYTECODE and PYTHONUNBUFFERED, as an
installed package runs (compiled modules, buffered output); one unmeasured run per tree first compiles them.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from statistics import median

ROOT = Path(__file__).resolve().parent.parent


@dataclass
class Case:
    name: str
    label: str
    program: Path
    extra: list[str]  # hil run options after the program (bench, trace)
    walls: dict[str, list[float]] = field(default_factory=dict)  # tree → process walls, s
    cpus: dict[str, list[float]] = field(default_factory=dict)  # tree → child CPU, s
    sim: dict[str, float] = field(default_factory=dict)  # tree → simulated s (from the run's summary)


def timed(cmd: list[str], env: dict | None = None, cwd: str | None = None) -> tuple[float, float, str, int]:
    """(wall s, CPU s of the child, its stdout + stderr, exit code): wall from the fork to the reaped exit."""
    import time

    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, cwd=cwd)
    out = p.stdout.read()  # type: ignore[union-attr]
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    return wall, usage.ru_utime + usage.ru_stime, out.decode(errors="replace"), os.waitstatus_to_exitcode(status)


def user_env(tree: str) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=tree)
    for k in ("PYTHONDONTWRITEBYTECODE", "PYTHONUNBUFFERED"):  # as an installed package runs
        env.pop(k, None)
    return env


def simulated(out: str) -> float:
    m = re.search(r"^cycles\s+\d+\s+\([^,]*,\s*([0-9.]+) s simulated\)", out, re.M)
    if not m:
        raise SystemExit(f"no 'cycles … s simulated' line in hil's output:\n{out[-2000:]}")
    return float(m.group(1))


def import_time(cmd: list[str], env: dict, cwd: str) -> tuple[float, int]:
    """(s, modules) of the run's imports: `-X importtime`'s top-level entries (cumulative µs), one run."""
    p = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], env=env, cwd=cwd, capture_output=True, text=True)
    rows = [ln.split("|") for ln in p.stderr.splitlines() if ln.startswith("import time:") and "cumulative" not in ln]
    top = sum(int(r[1]) for r in rows if len(r) == 3 and not r[2].startswith("  ") and r[2].strip())
    return top / 1e6, len(rows)


def rs274(program: Path, repeat: int) -> tuple[float | None, str]:
    """(best process wall of `rs274 -g program`, note): None and the reason where it does not run it."""
    exe = shutil.which("rs274")
    if not exe:
        return None, "skipped: rs274 not installed (apt-get install linuxcnc-uspace)"
    runs = [timed([exe, "-g", str(program)]) for _ in range(repeat)]
    wall, _, out, rc = min(runs, key=lambda r: r[0])
    if rc != 0:  # its message, then the block it stopped at, among the canonical calls ("  12 N..... …")
        lines = [ln.strip() for ln in out.splitlines()]
        errors = [(m, b) for m, b in zip(lines, lines[1:]) if m and "N....." not in m and m != "executing"]
        why = f"{errors[0][0]} at '{errors[0][1].split('(')[0].strip()}'" if errors else f"exit {rc}"
        return None, f"skipped: rs274 stops ({why})"
    return wall, f"{len(out.splitlines())} canonical calls"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="rounds (best and median of N; default 5)")
    ap.add_argument("--blocks", type=int, default=5000, help="CAM program blocks (default 5000)")
    ap.add_argument("--tree", action="append", help="source tree(s) to run hil from (default: this one)")
    ap.add_argument("--only", choices=("lathe", "cam"), action="append")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    trees = [str(Path(t).resolve()) for t in (args.tree or [str(ROOT)])]
    sys.path.insert(0, str(ROOT))
    from benchmarks.bench_motion import cam_program

    py = sys.executable
    with tempfile.TemporaryDirectory() as d:
        cam = Path(d) / f"cam{args.blocks}.nc"
        cam.write_text(cam_program(args.blocks))
        cases = [Case("lathe", "lathe demo, lathe MLC, --trace t.parquet", ROOT / "examples" / "lathe_demo.nc",
                      ["--trace", str(Path(d) / "t.parquet")]),
                 Case("cam", f"CAM {args.blocks:,} blocks, mill-3axis, --trace", cam,
                      ["--bench", str(ROOT / "benches" / "mill-3axis.toml"), "--trace", str(Path(d) / "cam.parquet")])]
        cases = [c for c in cases if not args.only or c.name in args.only]

        def command(c: Case) -> list[str]:
            return [py, "-m", "hil.cli", "run", str(c.program), *c.extra]

        for tree in trees:  # unmeasured: compiles the tree's modules, warms the page cache
            for c in cases:
                _, _, out, rc = timed(command(c), user_env(tree), tree)
                if rc != 0:
                    print(f"{c.label} in {tree}: exit {rc}\n{out[-2000:]}", file=sys.stderr)
                    return 1
                c.sim[tree] = simulated(out)
        bare = []
        for _ in range(args.repeat):
            for tree in trees:
                for c in cases:
                    wall, cpu, _, _ = timed(command(c), user_env(tree), tree)
                    c.walls.setdefault(tree, []).append(wall)
                    c.cpus.setdefault(tree, []).append(cpu)
            bare.append(timed([py, "-c", "pass"], user_env(trees[0]))[0])
        imports = {(c.name, t): import_time(command(c), user_env(t), t) for c in cases for t in trees}
        refs = {c.name: rs274(c.program, args.repeat) for c in cases}
    rows = []
    for c in cases:
        for t in trees:
            w, cpu = c.walls[t], c.cpus[t]
            rows.append({"case": c.name, "label": c.label, "tree": t, "simulated_s": c.sim[t],
                         "wall_best_s": round(min(w), 3), "wall_median_s": round(median(w), 3),
                         "cpu_best_s": round(min(cpu), 3), "cpu_median_s": round(median(cpu), 3),
                         "x_real_wall": round(c.sim[t] / min(w), 1),
                         "x_real_wall_median": round(c.sim[t] / median(w), 1),
                         "imports_s": round(imports[c.name, t][0], 3), "modules": imports[c.name, t][1],
                         "rs274_wall_s": None if refs[c.name][0] is None else round(refs[c.name][0], 3),
                         "rs274_note": refs[c.name][1]})
    load = os.getloadavg()
    if args.json:
        print(json.dumps({"rows": rows, "python_pass_s": round(min(bare), 3), "repeat": args.repeat,
                          "load": [round(x, 2) for x in load]}, indent=1))
        return 0
    print(f"the user's `hil run` process wall: best / median of {args.repeat} interleaved rounds, {py}")
    print(f"{'case':44s} {'sim s':>7s} {'wall best':>9s} {'median':>7s} {'CPU best':>8s} {'x real':>7s} "
          f"{'imports':>8s} {'modules':>7s}  rs274 -g")
    for r in rows:
        tree = "" if len(trees) == 1 else f"  [{r['tree']}]"
        ref = (f"{r['rs274_wall_s']:.3f} s ({r['rs274_note']})" if r["rs274_wall_s"] is not None else r["rs274_note"])
        print(f"{r['label']:44s} {r['simulated_s']:7.3f} {r['wall_best_s']:9.3f} {r['wall_median_s']:7.3f} "
              f"{r['cpu_best_s']:8.3f} {r['x_real_wall']:6.1f}x {r['imports_s']:8.3f} {r['modules']:7d}  {ref}{tree}")
    print(f"bare interpreter (python -c pass): best {min(bare):.3f} s wall; 30x real time by the wall needs "
          + ", ".join(f"{c.name} <= {c.sim[trees[0]] / 30:.3f} s" for c in cases))
    print(f"(load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}: imports by -X importtime, one run each)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
