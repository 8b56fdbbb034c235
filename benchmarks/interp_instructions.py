"""Instructions the interpreter and the parser spend a block of the issue-17 CAM program, counted by callgrind.

The program is benchmarks/bench_motion.cam_program (`X.. Y..` lines, the bench_loop CAM program). A child imports,
parses the program and runs a 10-block one first (imports, the lean lane's shapes), then, or not (the baseline):

- `run`: `Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(program)` to its end, Move by Move as the channel
  reads it (preview window, corner and compensation stages included);
- `parse`: `parse_program(text)` once more.

A figure is (the child's instructions − the baseline's) / blocks, with PYTHONHASHSEED=0 and a full collection
before the measured part in both; the same build counted twice agrees within a few instructions a block. It is the interpreter's own cost, without the channel and planner that
`benchmarks/cam_instructions.py` counts around it (decision bench B138). Prints figures, asserts nothing.

Usage: python benchmarks/interp_instructions.py [--tree DIR] [--against DIR] [--blocks N]
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

CHILD = """
import gc, sys
sys.path.insert(0, sys.argv[1])
from benchmarks.bench_motion import cam_program
from nc.interp.interpreter import Interpreter
from nc.profiles import make_profile
from nc.program import parse_program
blocks, mode, go = int(sys.argv[2]), sys.argv[3], sys.argv[4] == "1"
text = cam_program(blocks)
program = parse_program(text)
for ev in Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(parse_program(cam_program(10))):
    pass
ip = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
gc.collect()  # the measured part starts from the same collector state in both children (a full collection
# falling inside one of them moved a figure by thousands of instructions a block)
if go and mode == "run":
    for ev in ip.run(program):
        pass
elif go:
    parse_program(text)
"""


def collected(valgrind_args: list[str], child_args: list[str]) -> int:
    """Instructions callgrind counts running CHILD-like code (`child_args` after the interpreter), with PYTHONHASHSEED=0
    (benchmarks/interp_layers.py counts through it too)."""
    out = subprocess.run(["valgrind", "--tool=callgrind", *valgrind_args, sys.executable, "-c", *child_args],
                         capture_output=True, text=True, env=dict(os.environ, PYTHONHASHSEED="0"), check=True)
    m = re.search(r"Collected : (\d+)", out.stderr)
    if m is None:
        raise SystemExit(f"callgrind printed no count for {child_args[1:2]}:\n{out.stderr[-2000:]}")
    return int(m.group(1))


def count(tree: str, blocks: int, mode: str, go: bool) -> int:
    with tempfile.TemporaryDirectory() as d:
        return collected([f"--callgrind-out-file={d}/cg.out"], [CHILD, tree, str(blocks), mode, "1" if go else "0"])


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
        figures = []
        for mode in ("run", "parse"):
            base = count(tree, args.blocks, mode, False)
            figures.append(f"{mode} {(count(tree, args.blocks, mode, True) - base) / args.blocks:,.0f}")
        print(f"{tree}: CAM {args.blocks:,} blocks, instructions a block: " + ", ".join(figures))


if __name__ == "__main__":
    main()
