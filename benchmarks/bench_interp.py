"""Interpreter speed: `hil path` beside LinuxCNC's standalone `rs274 -g` on the same program text.

    python benchmarks/bench_interp.py [--blocks 100000] [--repeat 1] [--json]

Three generated programs, each run by both (wall clock and peak RSS of the whole command, as a
user runs it):
  cam    a CAM spiral, `G1 X Y Z F` on every line (3 decimals), --blocks lines;
  macro  WHILE loops with arithmetic and G65 macro calls (a G1 per pass);
  lathe  a lathe-cycle program run by `hil path` (G71/G70 roughing and finishing, G76 threads); rs274
         gets the same contour as plain moves (it has no Fanuc lathe cycles), so its figure is a
         reference for the line count only.
Prints seconds (wall and CPU), peak MB and the ratio rs274 time / ours (1.0 = as fast as rs274), by
wall clock and by CPU time (the steadier figure on a shared machine). Figures, never a
pass/fail. rs274 comes with the Debian package linuxcnc-uspace; without it the ratio is skipped.

  block  the interpreter's cost a block as the channel pays it (issue 17): `Interpreter.run` in process,
         Move by Move (no bulk lane), on benchmarks/bench_motion.cam_program (--per-block lines of
         `X.. Y..`, the bench_loop CAM program), CPU best of --repeat (at least 3), with the general
         path alone (`Interpreter.lean = False`) beside it; the channel's read side (the same run through
         `hil.stretch_reads.Ahead.peek` and `Channel._feed_planner` with the mill bench's soft limits, 4 moves a
         feed, into a planner stand-in that keeps the pushes); rs274 -g on the same lines, CPU / blocks.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def cam_program(n: int) -> str:
    lines = ["%", "O1000", "G21 G90 G17 G54", "G0 X0 Y0 Z5"]
    for i in range(n):
        a = i * 0.01
        r = 10.0 + i * 0.0005
        lines.append(f"G1 X{r * math.cos(a):.3f} Y{r * math.sin(a):.3f} Z{-i * 0.00001:.3f} F{1200 + i % 7}")
    lines += ["M30", "%"]
    return "\n".join(lines) + "\n"


def macro_program(passes: int) -> tuple[str, str]:
    """(deltahil text with G65 and a macro O9001, rs274 text with an o-word sub). Same arithmetic."""
    ours = ["O1001", "G21 G90 G17", "#1 = 0", f"WHILE [#1 LT {passes}] DO1",
            "#2 = #1 * 0.5", "#3 = SIN[#1] * 10 + COS[#1 * 2] * 5",
            "G65 P9001 A#2 B#3", "#1 = #1 + 1", "END1", "M30", "",
            "O9001", "#10 = #1 + #2 * 2", "G1 X#10 Y[#2 - 1] F1000", "M99"]
    theirs = ["G21 G90 G17", "o100 sub", "#<a> = #1", "#<b> = #2", "G1 X[#<a> + #<b> * 2] Y[#<b> - 1] F1000",
              "o100 endsub", "#1 = 0", f"o101 while [#1 LT {passes}]", "#2 = [#1 * 0.5]",
              "#3 = [SIN[#1] * 10 + COS[#1 * 2] * 5]", "o100 call [#2] [#3]", "#1 = [#1 + 1]",
              "o101 endwhile", "M30"]
    return "\n".join(ours) + "\n", "%\n" + "\n".join(theirs) + "\n%\n"


def lathe_program(parts: int) -> tuple[str, str]:
    """`parts` times the shipped example's part (examples/lathe_part_g71_g70_g76.nc): G71 roughing,
    G70 finishing with nose radius compensation, G76 thread. rs274 (no Fanuc lathe cycles) gets
    the finished contour and thread passes as plain moves, as many lines as our output."""
    contour = ["G01 Z0. F0.12", "X24. Z-3.", "Z-25.", "X28.", "X32. Z-35.", "G02 X38. Z-38. R3.", "G01 Z-50."]
    ours = ["O1002", "G10 L10 P1 R0.8 Q3", "G10 L10 P3 R0 Q0", "G21 G99", "G50 S2500"]
    theirs = ["G21 G18 G90"]
    for k in range(parts):
        p, q = 1000 + 2 * k, 1001 + 2 * k
        ours += ["T0101", "G96 S180 M03", "G00 X45. Z5.", "G71 U1.5 R0.5", f"G71 P{p} Q{q} U0.4 W0.1 F0.25",
                 f"N{p} G00 X18.", *contour, f"N{q} X44.", "G00 X60. Z50.", "G42 G00 X45. Z2.",
                 f"G70 P{p} Q{q}", "G40 G00 X60. Z50.", "T0303", "G97 S800 M03", "G00 X28. Z5.",
                 "G76 P011060 Q50 R0.05", "G76 X21.4 Z-22. P1300 Q400 F2.", "G00 X60. Z50."]
        theirs += [f"G1 X{20 + (j % 20)} Z{-(j % 50)} F200" for j in range(120)]
    ours += ["M05", "M30"]
    theirs += ["M30"]
    return "\n".join(ours) + "\n", "%\n" + "\n".join(theirs) + "\n%\n"


def timed(cmd: list[str], env: dict | None = None, cwd: str | None = None) -> tuple[float, float, int, float]:
    """Wall seconds, peak RSS in MB of the child, output lines, CPU seconds (user + system) of the child:
    on a shared machine the CPU time is the steadier figure."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, cwd=cwd)
    lines = sum(1 for _ in p.stdout)  # type: ignore[union-attr]
    _, status, usage = os.wait4(p.pid, 0)
    dt = time.perf_counter() - t0
    return dt, usage.ru_maxrss / 1024.0, lines, usage.ru_utime + usage.ru_stime


def _motion_cam(n: int) -> tuple[str, str]:
    from bench_motion import cam_program as motion_cam  # the bench_loop CAM program (this folder)

    text = motion_cam(n)
    return text, "%\n" + text + "%\n"


# The child that times `Interpreter.run` in the tree under test (PYTHONPATH): µs a block, CPU, best of N;
# the general path alone too where the tree has the lean lane. Prints "lean general" (general: nan).
_PER_BLOCK = """
import sys, time
from nc.interp import Interpreter
from nc.profiles import make_profile
from nc.program.blocks import parse_program
text, repeat = open(sys.argv[1]).read(), int(sys.argv[2])
prog = parse_program(text)
n = len(prog.blocks)
def best(lean):
    out = []
    for _ in range(repeat):
        ip = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
        if lean is not None:
            ip.lean = lean
        t0 = time.process_time()
        for ev in ip.run(prog):
            pass
        out.append(time.process_time() - t0)
    return min(out) / n * 1e6
def feed():
    # the channel's read side a move: the same run through hil.stretch_reads.Ahead's peek (soft limits of
    # benches/mill-3axis.toml, the statement budget) and Channel._feed_planner, 4 moves a feed as a stretch
    # reads them, into a planner stand-in that only keeps the pushes (Planner.push is the planner's cost)
    try:
        from hil.bench_file import load_bench_file
        from hil.stretch_reads import ahead
    except ImportError:
        return float("nan")
    from nc.budget import StatementBudget
    from nc.channel import Channel, RunState
    from nc.softlimits import SoftLimits
    from nc.motion.limits import MotionConfig
    class Taker:
        closed = idle = True
        held = False
        cfg = MotionConfig()
        threads_queued = 0
        def __init__(self):
            self.blocks = []
        @property
        def full(self):
            return len(self.blocks) >= 8
        def push(self, move):
            self.blocks.append(move)
        def release_run(self):
            pass
    bench = load_bench_file("benches/mill-3axis.toml")
    out = []
    for _ in range(repeat):
        profile = make_profile(bench.profile, bench_axes, bench.params)
        ip = Interpreter(profile)
        ip.budget = StatementBudget.for_profile(profile)
        ch = Channel(Taker())
        ch.soft_limits, ch.statement_budget = SoftLimits.for_bench(bench, profile), ip.budget
        ch.load(ip.run(prog))
        ch.cycle_start()
        src = ahead(ch)
        t0 = time.process_time()
        while ch.end is None and ch.state is RunState.RUNNING:
            del ch.planner.blocks[:4]
            src.peek(4)
            ch._feed_planner()
        out.append(time.process_time() - t0)
    return min(out) / n * 1e6
bench_axes = ("X", "Y", "Z")
lean = hasattr(Interpreter, "lean")
print(best(None), best(False) if lean else float("nan"), feed())
"""


def per_block(path: Path, tree: str, env: dict, repeat: int) -> tuple[float, float, float]:
    """µs a block of `Interpreter.run` on the program at `path` in `tree` (lean lane, general path), and of the
    channel's read side (the run through `Ahead.peek` and `Channel._feed_planner`, up to `Planner.push`)."""
    out = subprocess.run([sys.executable, "-c", _PER_BLOCK, str(path), str(max(3, repeat))], env=env, cwd=tree,
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), float(out[1]), float(out[2])


def write_case(name: str, folder: str, blocks: int, passes: int, parts: int) -> None:
    """The case's two program files, ours (.nc) and rs274's (.ngc), in `folder`."""
    ours, theirs = {"cam": lambda: (cam_program(blocks),) * 2, "macro": lambda: macro_program(passes),
                    "lathe": lambda: lathe_program(parts), "block": lambda: _motion_cam(blocks)}[name]()
    (Path(folder) / f"{name}.nc").write_text(ours)
    (Path(folder) / f"{name}.ngc").write_text(theirs)


def main() -> int:
    if sys.argv[1:2] == ["--write"]:  # the generator process (see below)
        name, folder, blocks, passes, parts = sys.argv[2:7]
        write_case(name, folder, int(blocks), int(passes), int(parts))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blocks", type=int, default=100_000, help="CAM program length (default 100000)")
    ap.add_argument("--passes", type=int, default=5000, help="macro WHILE passes (default 5000)")
    ap.add_argument("--parts", type=int, default=200, help="lathe parts, each G71/G70/G76 (default 200)")
    ap.add_argument("--repeat", type=int, default=1, help="best of N runs")
    ap.add_argument("--per-block", type=int, default=5000, help="lines of the per-block case (default 5000)")
    ap.add_argument("--only", choices=("cam", "macro", "lathe", "block"), action="append")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--tree", default=str(ROOT), help="run `hil` from this source tree (e.g. another checkout, "
                                                      "for before/after figures)")
    args = ap.parse_args()
    rs274 = shutil.which("rs274")
    env = dict(os.environ, PYTHONPATH=args.tree)
    env.pop("PYTHONUNBUFFERED", None)  # as a user runs it: a syscall per output line is not the interpreter's cost
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # and with the compiled modules an installed package has
    hil = [sys.executable, "-m", "hil.cli", "path", "--json"]  # run in --tree (cwd below)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        profiles = {"cam": "nc5-mill", "macro": "nc5-mill", "lathe": "nc5-lathe-a"}
        for name in ("cam", "macro", "lathe", "block"):
            if args.only and name not in args.only:
                continue
            # written by another process: a child's peak RSS (wait4) counts the pages its parent had at
            # the fork, and a parent that had built a 1M-block text would add ~150 MB to both columns
            subprocess.run([sys.executable, __file__, "--write", name, d,
                            str(args.per_block if name == "block" else args.blocks), str(args.passes),
                            str(args.parts)], check=True)
            if name == "block":
                lean, general, read = per_block(Path(d) / "block.nc", args.tree, env, args.repeat)
                row = {"case": name, "blocks": args.per_block, "interp_us_block": round(lean, 2),
                       "general_us_block": round(general, 2), "read_side_us_block": round(read, 2)}
                if rs274:
                    ref = min((timed([rs274, "-g", str(Path(d) / "block.ngc")]) for _ in range(max(3, args.repeat))),
                              key=lambda r: r[3])
                    row["rs274_us_block"] = round(ref[3] / args.per_block * 1e6, 2)
                rows.append(row)
                continue
            # more blocks than the endless-loop guard allows (decisions P5: "max blocks", 1,000,000 executed
            # blocks) need the guard raised, as a user running such a program does
            guard = ["--param", f"max blocks={2 * args.blocks}"] if name == "cam" and args.blocks > 900_000 else []
            best = min((timed(hil + guard + ["--profile", profiles[name], str(Path(d) / f"{name}.nc")], env, args.tree)
                        for _ in range(args.repeat)), key=lambda r: r[0])
            row = {"case": name, "hil_s": round(best[0], 3), "hil_cpu_s": round(best[3], 3),
                   "hil_peak_mb": round(best[1], 1), "hil_lines": best[2]}
            if rs274:
                ref = min((timed([rs274, "-g", str(Path(d) / f"{name}.ngc")]) for _ in range(args.repeat)),
                          key=lambda r: r[0])
                row.update(rs274_s=round(ref[0], 3), rs274_cpu_s=round(ref[3], 3), rs274_peak_mb=round(ref[1], 1),
                           rs274_lines=ref[2], ratio=round(ref[0] / best[0], 3),
                           cpu_ratio=round(ref[3] / best[3], 3) if best[3] else None)
            rows.append(row)
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    if not rs274:
        print("rs274 not found (apt-get install linuxcnc-uspace): deltahil figures only", file=sys.stderr)
    nan = float("nan")
    print(f"{'case':6s} {'hil path s':>10s} {'cpu s':>6s} {'peak MB':>8s} {'rs274 -g s':>10s} {'cpu s':>6s} "
          f"{'peak MB':>8s} {'rs274/ours':>10s} {'(cpu)':>6s}")
    for r in rows:
        if r["case"] == "block":
            print(f"block  {r['blocks']} `X Y` lines (bench_motion.cam_program), CPU µs a block: Interpreter.run "
                  f"{r['interp_us_block']:.2f} (general path alone {r['general_us_block']:.2f}), the channel's read "
                  f"side {r['read_side_us_block']:.2f} (Ahead.peek, Channel._feed_planner: up to Planner.push); rs274 -g "
                  f"{r.get('rs274_us_block', nan):.2f} (whole command)")
            continue
        print(f"{r['case']:6s} {r['hil_s']:10.2f} {r['hil_cpu_s']:6.2f} {r['hil_peak_mb']:8.0f} "
              f"{r.get('rs274_s', nan):10.2f} {r.get('rs274_cpu_s', nan):6.2f} {r.get('rs274_peak_mb', nan):8.0f} "
              f"{r.get('ratio', nan):10.3f} {r.get('cpu_ratio', nan) or nan:6.3f}")
    print(f"(load average {os.getloadavg()[0]:.1f}: figures on a shared machine)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
