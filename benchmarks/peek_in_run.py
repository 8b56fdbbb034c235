"""Instructions of `Ahead.peek` (hil/stretch_reads.py: the interpreter's stream, the preview window, the soft-limit
test, as hil's stretches read the program) inside the issue-17 CAM run itself, a block (decision bench B193).

The whole run's count (cam_instructions.py) moves by ≈ 0.7k a block between two counts of one tree, more than a
change of the read side saves; this counts peek alone. A child runs the CAM program (benchmarks/bench_motion
.cam_program on benches/mill-3axis.toml, Parquet trace, hil's BenchRunner) once to warm up (imports, the lean lane's
shapes), then again, with the garbage collector off and `Ahead.peek` called through `functools.reduce`: callgrind
counts only inside it (`--collect-atstart=no --toggle-collect=functools_reduce`, PYTHONHASHSEED=0). Under callgrind
a 5,000-block run takes ≈ 5 minutes (two runs). Prints figures, asserts nothing; without valgrind it says so.

Usage: python benchmarks/peek_in_run.py [--tree DIR] [--against DIR] [--blocks N]
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from benchmarks.interp_instructions import collected  # noqa: E402  (the tree's, run as a script)

CHILD = r'''
import functools, gc, os, sys, tempfile
sys.path.insert(0, sys.argv[1])
from pathlib import Path
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from hil.runner import BenchRunner
from hil.session import make_link
from hil.trace import open_trace
from nc.program import parse_program
import hil.stretch_reads as reads
import hil.trace_parquet as tp
tp.FLUSH_S = 1e9  # one part, as cam_instructions.py writes it
bench = load_bench_file(Path(sys.argv[1]) / "benches" / "mill-3axis.toml")
text = cam_program(int(sys.argv[2]))
def run():
    runner = BenchRunner(bench, make_link(bench), None)
    runner.trace = open_trace(os.path.join(tempfile.mkdtemp(), "cam.parquet"), runner.trace_columns())
    runner.run_program(parse_program(text, name="cam.nc"))
run()  # warm up
peek, reduce, one = reads.Ahead.peek, functools.reduce, [None]
reads.Ahead.peek = lambda self, k: reduce(lambda _, __: peek(self, k), one, None)
gc.collect()
gc.disable()
run()
'''


def count(tree: str, blocks: int) -> int:
    """Instructions callgrind counts inside `Ahead.peek` over the second run (interp_instructions.collected)."""
    return collected(["--callgrind-out-file=/dev/null", "--collect-atstart=no", "--toggle-collect=functools_reduce"],
                     [CHILD, tree, str(blocks)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tree", default=str(ROOT))
    ap.add_argument("--against", default=None, help="a second tree, counted the same way")
    ap.add_argument("--blocks", type=int, default=5000)
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        print("valgrind is not installed: no figures")
        return
    for tree in [args.tree] + ([args.against] if args.against else []):
        print(f"{tree}: CAM {args.blocks:,} blocks, Ahead.peek inclusive: {count(tree, args.blocks) / args.blocks:,.0f} "
              "instructions a block")


if __name__ == "__main__":
    main()
