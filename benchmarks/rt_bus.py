"""Real time on the field buses (issue 17, session 16; decisions E24–E26): `hil run` of the lathe demo against
virtual slaves in another process, printing the summary's cycle work split into bus wait and master work.

    sudo python benchmarks/rt_bus.py [--rounds N] [--only ethercat|canopen] [--lockstep] [--tree DIR]
                                     [--program lathe|cam] [--blocks N] [--tag NAME]

- ethercat: the guide's bench (docs/guide/ethercat-virtual.md): `hil sim ethercat` on a fresh veth pair per run
  (fresh slaves: each run from power-on), `hil run --realtime --trace` at 1 ms;
- canopen: the CANopen guide's 4 ms bench, `hil sim canopen` over udp_multicast in a loopback-only namespace;
- --lockstep: the EtherCAT run without --realtime as well (cycles/s by the wall, master work).
Each run is its own `hil run` process (mlockall and SCHED_FIFO stay in it), whose CPU time and voluntary context
switches (all its threads: python-can's receive thread too) are printed per cycle. `--tree DIR`: run another
checkout's `hil` (before/after pairs). `--program cam`: benchmarks/bench_motion.py's CAM program (`--blocks`, 1,500)
on benches/mill-3axis.toml (the basic MLC) instead of the lathe demo. `--tag`: in the network namespaces' names (a
helper's name: its own to remove). Needs root; measures, never asserts.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from virtual_bus.ethercat.veth import SimProcess  # noqa: E402

BENCH = ROOT / "benches" / "lathe-2axis.toml"
PROGRAM = ROOT / "examples" / "lathe_demo.nc"
TAG = "rtb"
TREE = ROOT  # the checkout whose `hil` runs (--tree)
# `hil run` with its own rusage printed at the end (CPU of all its threads, voluntary context switches)
WRAP = ("import resource, sys\nfrom hil.cli import main\ntry:\n    main(sys.argv[1:])\nfinally:\n"
        "    r = resource.getrusage(resource.RUSAGE_SELF)\n"
        "    print(f'rusage {r.ru_utime + r.ru_stime} {r.ru_nvcsw}', file=sys.stderr)\n")
KEYS = ("cycles", "result", "cycle work", "bus wait", "master work", "between cycles", "cycle jitter")


def _hil(prefix: list[str], bus: str, bench: Path, realtime: bool, trace: Path) -> tuple[dict[str, str], float]:
    prog = PROGRAM if PROGRAM.parent != ROOT / "examples" else TREE / "examples" / PROGRAM.name
    cmd = [*prefix, sys.executable, "-c", WRAP, "run", str(prog), "--bench", str(bench),
           "--bus", bus, "--no-check", "--trace", str(trace)] + (["--realtime"] if realtime else [])
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=TREE, env=dict(os.environ, PYTHONPATH=str(TREE)))
    wall = time.perf_counter() - t0
    lines = {ln[:15].strip(): ln[15:].strip() for ln in (p.stdout + p.stderr).splitlines() if len(ln) > 15}
    got = {k: lines.get(k, "") for k in KEYS} | {"overruns": lines.get("overruns", "0")}
    cycles = int(got["cycles"].split()[0]) if got["cycles"] else 0
    use = re.search(r"rusage ([\d.]+) (\d+)", p.stderr)
    got["rusage"] = (f"CPU {float(use.group(1)) / cycles * 1e6:.0f} µs, {int(use.group(2)) / cycles:.1f} voluntary "
                     "switches a cycle") if use and cycles else "rusage n/a"
    return got, wall


def _p(text: str, key: str) -> float:
    m = re.search(rf"{key} ([\d.]+) µs", text)
    return float(m.group(1)) if m else float("nan")


def ethercat(rounds: int, lockstep: bool, tmp: Path) -> None:
    for i in range(rounds):
        for realtime in ((True, False) if lockstep else (True,)):
            with SimProcess("--bench", str(BENCH), "--io", "1", tag=TAG) as sim:
                got, wall = _hil([], f"ethercat:{sim.iface}", BENCH, realtime, tmp / "ec.parquet")
            cycles = int(got["cycles"].split()[0]) if got["cycles"] else 0
            mode = "realtime" if realtime else f"lock-step {cycles / wall:,.0f} cycles/s by the process wall"
            print(f"ethercat {mode}: {got['result']}; cycle work {got['cycle work']}; bus wait {got['bus wait']}; "
                  f"master work {got['master work']}; overruns {got['overruns'].split()[0]}; {got['rusage']}", flush=True)


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, text=True)


def canopen(rounds: int, tmp: Path) -> None:
    bench = tmp / f"{BENCH.stem}-4ms.toml"  # the CANopen guide's 4 ms bench
    bench.write_text(BENCH.read_text().replace("cycle_ms = 1.0", "cycle_ms = 4.0")
                     .replace("max_following_error = { X = 0.1, Z = 0.1 }", "max_following_error = { X = 0.3, Z = 0.3 }")
                     .replace("max_following_error = 0.1", "max_following_error = 0.3"))
    ns = f"{TAG}-co-{uuid.uuid4().hex[:6]}"
    _ip("netns", "add", ns)
    try:
        for cmd in (("link", "set", "lo", "up"), ("link", "set", "lo", "multicast", "on"),
                    ("route", "add", "224.0.0.0/4", "dev", "lo")):
            _ip("-n", ns, *cmd)
        prefix = ["ip", "netns", "exec", ns]
        for i in range(rounds):
            group = f"239.74.163.{40 + i}"
            sim = subprocess.Popen([*prefix, sys.executable, "-m", "hil.cli", "sim", "canopen", "--bus",
                                    f"canopen:udp_multicast:{group}", "--bench", str(bench)],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                                   env=dict(os.environ, PYTHONPATH=str(ROOT)))
            sim.stdout.readline()  # the nodes are on the bus
            try:
                got, _ = _hil(prefix, f"canopen:udp_multicast:{group}", bench, True, tmp / "co.parquet")
            finally:
                sim.terminate()
                sim.communicate(timeout=10)
            print(f"canopen realtime 4 ms: {got['result']}; cycle work {got['cycle work']}; bus wait {got['bus wait']}; "
                  f"master work {got['master work']}; overruns {got['overruns'].split()[0]}; {got['rusage']}", flush=True)
    finally:
        subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", choices=("ethercat", "canopen"))
    ap.add_argument("--lockstep", action="store_true", help="EtherCAT lock-step runs too")
    ap.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose hil runs (default: this one)")
    ap.add_argument("--program", choices=("lathe", "cam"), default="lathe")
    ap.add_argument("--blocks", type=int, default=1500, help="--program cam: its blocks")
    ap.add_argument("--tag", default="rtb", help="in the network namespaces' names")
    a = ap.parse_args()
    global TREE, BENCH, PROGRAM, TAG
    TREE, TAG = a.tree.resolve(), a.tag
    tmpdir = tempfile.TemporaryDirectory()
    if a.program == "cam":  # the CAM program on the mill bench (the basic MLC)
        from benchmarks.bench_motion import cam_program
        BENCH = ROOT / "benches" / "mill-3axis.toml"
        PROGRAM = Path(tmpdir.name) / "cam.nc"
        PROGRAM.write_text(cam_program(a.blocks) + "\n")
    if os.geteuid() != 0:
        print("rt_bus: needs root (network namespaces, veth pairs, raw sockets)", file=sys.stderr)
        return 2
    print(f"load {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} CPUs", flush=True)
    with tempfile.TemporaryDirectory() as d:
        if a.only in (None, "ethercat"):
            ethercat(a.rounds, a.lockstep, Path(d))
        if a.only in (None, "canopen"):
            canopen(a.rounds, Path(d))
    return 0


if __name__ == "__main__":
    sys.exit(main())
