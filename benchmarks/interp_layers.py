"""Instructions a CAM block of each layer of the interpreter's read side, counted by callgrind only while they run.

The program is benchmarks/bench_motion.cam_program (`X.. Y..` lines, the bench_loop CAM program) on the nc5-mill
profile. A child imports, parses and warms up (a 10-block program first: imports, the lean lane's shapes), then runs
one of these through `functools.reduce`, and callgrind counts only inside `functools_reduce`
(`--collect-atstart=no --toggle-collect=functools_reduce`): no baseline child to subtract, so a figure repeats to the
instruction for the same tree (interp_instructions.py's difference of two children moves by a few hundred a block):

- `line`: the lean lane's line runner alone (`<lean line XY>`'s `run`), called on each line of the program;
- `raw`: the interpreter's generator (`Interpreter._guarded`: `_run` since B173, its guard and the lean lane's runs in it), every event taken;
- `stream`: `Interpreter.run` (+ the corner and compensation stages and the preview window), as the channel reads it;
- `check`: `stream` and `SoftLimits.check` of each move (a bench's 1st segments), as hil's stretch reads do;
- `peek`: `check`'s events read as hil's stretches read them (hil/stretch_reads.py `Ahead.peek`, 4 at a time, with a
  statement budget and the soft limits, on a stand-in channel holding them), each peeked move then dropped;
- `parse`: `parse_program` of the program's text.

Prints instructions a block per layer (a later layer includes the earlier ones but `line` and `parse`; `peek`
includes `stream`). Asserts nothing; without valgrind it says so (decision bench B167).

Usage: python benchmarks/interp_layers.py [--tree DIR] [--against DIR] [--blocks N] [--layers raw,check,...]
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from benchmarks.interp_instructions import collected  # noqa: E402  (the tree's, run as a script)

LAYERS = ("line", "raw", "stream", "check", "peek", "parse")

CHILD = """
import functools, gc, operator, sys
sys.path.insert(0, sys.argv[1])
from benchmarks.bench_motion import cam_program
from nc.interp.interpreter import Interpreter
from nc.interp.records import Frame
from nc.moves import Move
from nc.profiles import make_profile
from nc.program import parse_program
from nc.softlimits import SoftLimits
blocks, layer = int(sys.argv[2]), sys.argv[3]
text = cam_program(blocks)
program = parse_program(text)
warm = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
for ev in warm.run(parse_program(cam_program(10))):
    pass
ip = Interpreter(make_profile("nc5-mill", ("X", "Y", "Z")))
limits = SoftLimits({"X": (-500.0, 500.0), "Y": (-500.0, 500.0), "Z": (-300.0, 300.0)}, ip.profile.params)
for _ in range(2):  # the axes' names and the box found
    limits.check(Move("line", 1, "", {"X": 0.0, "Y": 0.0, "Z": 0.0}, {"X": 1.0, "Y": 0.0, "Z": 0.0}, {}))
gc.collect()
reduce = functools.reduce
if layer == "line":
    lane = warm._lean
    run, frame = lane.last.run, Frame(program)
    warm._lean_origin = lane.origin()
    lines = text.split("\\n")[1:blocks + 1]
    reduce(lambda _, raw: run(lane, warm, frame, 5, raw, 10 ** 9, 7), lines, None)
elif layer == "raw":
    reduce(operator.is_, ip._guarded(program), None)
elif layer == "stream":
    reduce(operator.is_, ip.run(program), None)
elif layer == "check":
    check = limits.check
    def checked(_, ev):
        if type(ev) is Move:
            check(ev)
    reduce(checked, ip.run(program), None)
elif layer == "peek":
    import types
    from hil.stretch_reads import Ahead
    from nc.budget import StatementBudget
    ch = types.SimpleNamespace(statement_budget=StatementBudget(), soft_limits=limits, _checked=None)
    ahead = Ahead(ip.run(program), ch)
    def peeked(_, __):
        plain = ahead.plain
        while ahead.peek(4):
            plain.clear()
    reduce(peeked, [None], None)
elif layer == "parse":
    reduce(lambda _, t: parse_program(t), [text], None)
"""


def count(tree: str, blocks: int, layer: str) -> int:
    return collected(["--callgrind-out-file=/dev/null", "--collect-atstart=no", "--toggle-collect=functools_reduce"],
                     [CHILD, tree, str(blocks), layer])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tree", default=str(ROOT))
    ap.add_argument("--against", default=None, help="a second tree, counted the same way")
    ap.add_argument("--blocks", type=int, default=2000)
    ap.add_argument("--layers", default=",".join(LAYERS), help=f"some of {', '.join(LAYERS)}")
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        print("valgrind is not installed: no figures")
        return
    layers = [x for x in args.layers.split(",") if x]
    unknown = [x for x in layers if x not in LAYERS]
    if unknown:
        raise SystemExit(f"--layers: unknown {', '.join(unknown)} (known: {', '.join(LAYERS)})")
    for tree in [args.tree] + ([args.against] if args.against else []):
        figures = [f"{layer} {count(tree, args.blocks, layer) / args.blocks:,.0f}" for layer in layers]
        print(f"{tree}: CAM {args.blocks:,} blocks, instructions a block: " + ", ".join(figures))


if __name__ == "__main__":
    main()
