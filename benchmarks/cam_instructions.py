"""Instructions of the issue-17 CAM run, in total and per compiled function, counted by valgrind's callgrind.

The run is bench_loop's CAM line: 5,000 blocks of benchmarks/bench_motion.cam_program on benches/mill-3axis.toml
with a Parquet trace, through hil's BenchRunner in lock-step. Wall time on a shared 2-core machine moves by 10-20 %
from one run to the next (session 25 read a 10 % regression into such noise); an instruction count hardly moves for
the same build and inputs whatever else the machine does (the child runs with PYTHONHASHSEED=0: string hashes
move dict and set work between runs): the same build counted twice stays within ≈ 0.3 % of a run (perf28b saw 1.8k
a block), so compare the functions a change touches, not only the totals. It prints:

- the instructions of one run (a child that runs the program, less one that only imports and loads the bench),
  per block and per cycle;
- the inclusive instructions (less those of the set-up) of the compiled functions (the planner's Cython modules, the drive kernel: the
  `__pyx_pw_*` entry points, names decoded) and of pyarrow's Parquet writer, per block, largest first.

What is not compiled (the channel, the interpreter, hil's stretch loop) shows only in the total. Under callgrind a
run takes ~50x its time: about 2 minutes here. Prints figures, asserts nothing; without valgrind it says so.

Usage: python benchmarks/cam_instructions.py [--tree DIR] [--against DIR] [--blocks N] [--top K]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The child: import, load the bench and build the program; then run it `runs` times (0: the baseline).
CHILD = """
import os, sys, tempfile
sys.path.insert(0, sys.argv[1])
from pathlib import Path
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from hil.runner import BenchRunner
from hil.session import make_link
from hil.trace import open_trace
from nc.program import parse_program
import hil.trace_parquet as tp
tp.FLUSH_S = 1e9  # one part, as a run at full speed writes it: under callgrind a run is ~50x slower (B152)
bench = load_bench_file(Path(sys.argv[1]) / "benches" / "mill-3axis.toml")
text = cam_program(int(sys.argv[3]))
for _ in range(int(sys.argv[2])):
    runner = BenchRunner(bench, make_link(bench), None)
    runner.trace = open_trace(os.path.join(tempfile.mkdtemp(), "cam.parquet"), runner.trace_columns())
    r = runner.run_program(parse_program(text, name="cam.nc"))
    print(r.cycles)
"""

_ENTRY = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(\S+?):(\S+)")


def decode(symbol: str) -> str | None:
    """`__pyx_pw_2nc_6motion_7planner_7Planner_3push` -> `nc.motion.planner.Planner.push` (Cython's length-prefixed
    names, the last part a counter then the name); None for what is not a Python-visible compiled function."""
    m = re.search(r"__pyx_pw_(\d\w*?)(?:P7_object\w*)?$", symbol)
    if not m:
        return None
    rest, parts = m.group(1), []
    while True:
        n = re.match(r"\d+", rest)
        if not n:
            return None
        size, body = int(n.group(0)), rest[len(n.group(0)):]
        # a part of exactly `size` characters, then the next (which starts with its own length or counter); else
        # the last: `3few_rows` is the counter 3 and `few_rows`, not the part `few`
        if size < len(body) and body[size] == "_" and body[size + 1:size + 2].isdigit():
            parts.append(body[:size])
            rest = body[size + 1:]
            continue
        parts.append(body)  # the last: the counter was `size`, the rest is the name (`push`, `_refill`)
        return ".".join(parts)


def count(tree: Path, runs: int, blocks: int, out: Path) -> tuple[int, int]:
    """(total instructions, cycles of one run) of the child under callgrind."""
    python = os.path.realpath(sys.executable)  # the interpreter itself: valgrind follows no pyenv shim
    child = out.with_suffix(".py")
    child.write_text(CHILD)
    res = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", python, str(child),
                          str(tree), str(runs), str(blocks)], capture_output=True, text=True, cwd=tempfile.gettempdir(),
                         env={**os.environ, "PYTHONHASHSEED": "0"})  # str hashes, dict and set order: as each run
    if res.returncode != 0:
        raise RuntimeError(f"the child failed under valgrind: {res.stderr[-2000:]}")
    total = 0
    for line in out.read_text(errors="replace").splitlines():
        if line.startswith(("summary:", "totals:")):
            total = int(line.split()[1])
            break
    cycles = int(res.stdout.split()[-1]) if runs else 0
    return total, cycles


def functions(out: Path) -> dict[str, int]:
    """Inclusive instructions of the compiled entry points and of the Parquet writer, by decoded name."""
    res = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)],
                         capture_output=True, text=True)
    found: dict[str, int] = {}
    for line in res.stdout.splitlines():
        m = _ENTRY.match(line)
        if not m:
            continue
        ir, symbol = int(m.group(1).replace(",", "")), m.group(3).split("(")[0]
        name = decode(symbol)
        if name is None and "ParquetWriter" in symbol and "write_table" in symbol:
            name = "pyarrow ParquetWriter.write_table"
        if name is not None and ir > found.get(name, 0):
            found[name] = ir
    return found


def measure(tree: Path, blocks: int) -> tuple[int, int, int, dict[str, int]]:
    """(instructions of one run, its cycles, those of the set-up, inclusive instructions by function) of a tree."""
    with tempfile.TemporaryDirectory() as d:
        base, _ = count(tree, 0, blocks, Path(d) / "base.out")
        one, cycles = count(tree, 1, blocks, Path(d) / "one.out")
        before = functions(Path(d) / "base.out")  # what set-up ran of them (the program's text: numpy's random)
        diff = {k: v - before.get(k, 0) for k, v in functions(Path(d) / "one.out").items()}
    return one - base, cycles, base, {k: v for k, v in diff.items() if v > 0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", type=Path, default=ROOT, help="the checkout to measure (default: this one)")
    ap.add_argument("--against", type=Path, help="a second checkout (built), printed beside the first")
    ap.add_argument("--blocks", type=int, default=5000)
    ap.add_argument("--top", type=int, default=30, help="functions listed")
    args = ap.parse_args(argv)
    if shutil.which("valgrind") is None or shutil.which("callgrind_annotate") is None:
        print("valgrind is not installed (Debian: apt-get install valgrind): nothing measured")
        return
    trees = [args.tree] + ([args.against] if args.against else [])
    got = []
    for tree in trees:
        state = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv[1]); "
                                "from nc.motion.compiled import BUILD; print(BUILD)", str(tree)],
                               capture_output=True, text=True).stdout.strip()
        run, cycles, base, funcs = measure(tree, args.blocks)
        got.append((run, funcs))
        print(f"{tree} (planner {state}): CAM {args.blocks:,} blocks, {cycles} cycles: {run:,} instructions a run = "
              f"{run / args.blocks:,.0f} a block, {run / max(cycles, 1):,.0f} a cycle (set-up, not counted: {base:,})")
    run, funcs = got[0]
    rows = sorted(funcs.items(), key=lambda kv: -kv[1])[:args.top]
    head = "  ".join(f"{'a block, ' + Path(t).name:>22}" for t in trees)
    print(f"{head}  {'% of the run':>12}  function (inclusive)")
    for name, ir in rows:
        cols = "  ".join(f"{g[1].get(name, 0) / args.blocks:>22,.0f}" for g in got)
        print(f"{cols}  {100.0 * ir / run:>11.1f}%  {name}")


if __name__ == "__main__":
    main()
