"""Bench loop figures: lock-step cycles per second (with and without a Parquet trace), the work
per cycle of a dense CAM program on the mill bench (position filter on), the issue-17 runs
(examples/lathe_demo.nc with the lathe MLC and a Parquet trace, a 5,000-block CAM program on
benches/mill-3axis.toml, and examples/lathe_part_g71_g70_g76.nc: G96, feed per revolution, G76) as simulated time / wall time with the µs per cycle of each stage, and
the real-time pacer's jitter on this machine. Prints figures, asserts nothing.

EtherCAT lock-step prints the virtual slaves' CPU per frame in-process, then (root: a veth pair and
`hil sim ethercat` in a network namespace, skipped with the reason otherwise) cycles/s of the bus alone
and of a bench program, with the CPU each side spent;
`hil run --realtime` of the lathe demo and a CAM program prints p50/p99/max cycle work at 1 ms.
The issue-17 runs' process wall as a user times it (best of 3): benchmarks/bench_wall.py, run here too.

Usage: python benchmarks/bench_loop.py [PACER_SECONDS] [--stages-only | --ethercat-only | --realtime-only [--repeat N]]
(--help lists the options and runs nothing)"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

from pathlib import Path

from hil.bench import default_lathe
from hil.bench_file import load_bench_file
from hil.clock import RealTimeClock
from hil.runner import BenchRunner
from hil.session import make_link
from hil.trace import open_trace
from nc.program import parse_program

PROGRAM = "G98\nM03 S800\nG00 X24. Z2.\nG01 Z-40. F300.\nX30.\nZ-60.\nG00 X60. Z100.\nM30\n"


def lockstep(trace: str | None) -> None:
    bench = default_lathe()
    runner = BenchRunner(bench, make_link(bench), None)
    if trace:
        runner.trace = open_trace(trace, runner.trace_columns())
    t0 = time.perf_counter()
    r = runner.run_program(parse_program(PROGRAM, name="bench.nc"))
    wall = time.perf_counter() - t0
    kind = os.path.splitext(trace)[1] if trace else "no trace"
    print(f"lock-step ({kind:8s}): {r.cycles} cycles, {r.sim_time:.2f} s simulated in {wall:.2f} s wall "
          f"= {r.cycles / wall:,.0f} cycles/s ({r.sim_time / wall:.1f}x real time)")


def cam_work(blocks: int = 3000) -> None:
    """Per-cycle work (wall clock, lock-step) of a CAM program: 0.01–0.1 mm G01 blocks at F3000 on
    benches/mill-3axis.toml, whose 16+16 ms position filter makes planning the heaviest."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from benchmarks.bench_motion import cam_program

    bench = load_bench_file(Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml")
    runner = BenchRunner(bench, make_link(bench), None)
    t0 = time.perf_counter()
    r = runner.run_program(parse_program(cam_program(blocks), name="cam.nc"))
    wall = time.perf_counter() - t0
    e = r.timing.get("exec", {})
    print(f"CAM program, {blocks} blocks on the mill bench: {r.cycles} cycles in {wall:.2f} s wall; work per cycle "
          + "  ".join(f"{k} {e[k] * 1e6:.0f} µs" for k in ("p50", "p99", "p99.9", "max") if k in e))


class _Stage:
    """CPU time of this thread spent in one callable, summed. CPU time, not wall time: on a machine
    shared with other work, wall time mostly measures the others (the wrapper costs ≈ 1 µs a call)."""

    def __init__(self, fn):
        self.fn, self.seconds = fn, 0.0

    def __call__(self, *args, **kwargs):
        t = time.thread_time()
        try:
            return self.fn(*args, **kwargs)
        finally:
            self.seconds += time.thread_time() - t


def staged(label: str, program: Path, bench_file: Path | None, trace: str | None) -> None:
    """One run made by `hil.api.run` as `hil run` makes it (the bench's MLC, the trace, the post-run
    checks), timed by stage: MLC (scan, with the NC↔MLC exchange and the drive-status bridge), NC
    (channel step: interpreter, planner, filter), bus + drives (the link's exchange; on the sim bus
    that is the drive models), trace (row write) and the rest of the cycle (runner bookkeeping,
    CiA 402 masters). Post-run checks and start-up are outside the cycle figures."""
    from hil import api
    from nc.channel import Channel

    stages: dict[str, list[_Stage]] = {"MLC": [], "NC": [], "bus + drives": [], "trace": []}
    original = BenchRunner.run_program
    holder: dict = {}

    def timed_run(runner, prog):  # benchmark only: wraps this run's parts, restored below
        for stage, obj, name in (("MLC", runner.mlc, "scan"), ("MLC", runner.mlc, "bus_feedback"),
                                 ("bus + drives", runner.link, "exchange"), ("trace", runner.trace, "write"),
                                 ("trace", runner.trace, "write_columns")):
            if obj is not None and hasattr(obj, name):
                st = _Stage(getattr(obj, name))
                setattr(obj, name, st)
                stages[stage].append(st)
        holder["runner"] = runner
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            return original(runner, prog)
        finally:
            holder["wall"], holder["cpu"] = time.perf_counter() - t0, time.thread_time() - c0

    import hil.stretch as stretch
    import hil.stretch_pass as spass
    import virtual_bus.drive_stretch as ds

    nc = _Stage(Channel.step)
    stages["NC"].append(nc)
    # a stretch's planner samples count as NC, its drive models as bus + drives (hil/stretch.py); a stretch that
    # runs the NC's steps (B27, hil/stretch_pass.py: Pass.run) counts as NC but for the drive models it steps
    sampler = _Stage(stretch.sample_stretch)
    drives = {(cls, name): _Stage(getattr(cls, name)) for cls in (ds.CspRun, ds.CsvRun)
              for name in ("__init__", "step", "finish")}
    in_pass = [0.0]
    pass_run = _Stage(spass.Pass.run)

    def timed_pass(self, n):
        before = sum(st.seconds for st in drives.values())
        try:
            return pass_run(self, n)
        finally:
            in_pass[0] += sum(st.seconds for st in drives.values()) - before

    stages["NC"] += [sampler, pass_run]
    stages["bus + drives"] += list(drives.values())
    BenchRunner.run_program = timed_run
    Channel.step = lambda self: nc(self)
    spass.Pass.run = timed_pass
    stretch.sample_stretch = sampler
    for (cls, name), st in drives.items():
        setattr(cls, name, (lambda st: lambda *a, **k: st(*a, **k))(st))
    try:
        t0 = time.perf_counter()
        res = api.run(program, str(bench_file) if bench_file else None, trace=trace)
        total = time.perf_counter() - t0
    finally:
        BenchRunner.run_program, Channel.step, spass.Pass.run = original, nc.fn, pass_run.fn
        stretch.sample_stretch = sampler.fn
        for (cls, name), st in drives.items():
            setattr(cls, name, st.fn)
    r, wall, cpu = res.run, holder["wall"], holder["cpu"]
    n = max(1, r.cycles)
    parts = {k: sum(st.seconds for st in v) for k, v in stages.items()}
    parts["NC"] -= in_pass[0]  # Pass.run's drive models, counted as bus + drives
    parts["rest"] = cpu - sum(parts.values())
    print(f"{label}: {r.cycles} cycles, {r.sim_time:.2f} s simulated; the cycles took {cpu:.2f} s CPU = "
          f"{r.sim_time / cpu:.1f}x real time ({wall:.2f} s wall = {r.sim_time / wall:.1f}x); whole run incl. "
          f"post-run checks {total:.2f} s wall ({'completed' if r.ok else 'not completed'}; "
          f"{r.stretched / n:.0%} of the cycles in stretches)")
    print("  CPU µs per cycle: " + "  ".join(f"{k} {v / n * 1e6:.1f}" for k, v in parts.items())
          + f"  | total {cpu / n * 1e6:.1f}")


def issue17(d: str) -> None:
    root = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(root))
    try:
        from virtual_bus.kernels import BUILD
    except ImportError:  # a tree from before the kernel (session 21)
        BUILD = "none (a tree without virtual_bus/kernels.py)"
    print(f"drive kernel: {BUILD}")  # virtual_bus/drive_kernel: compiled by the install, or its Python source
    from nc.motion.compiled import BUILD as PLANNER_BUILD
    print(f"planner: {PLANNER_BUILD}")  # nc/motion's hot modules (B115): compiled by the install, or their sources
    from benchmarks.bench_motion import cam_program

    staged("lathe demo, lathe MLC, Parquet trace", root / "examples" / "lathe_demo.nc", None,
           os.path.join(d, "lathe.parquet"))
    cam = Path(d) / "cam5000.nc"
    cam.write_text(cam_program(5000))
    staged("CAM 5,000 blocks, mill-3axis, Parquet trace", cam, root / "benches" / "mill-3axis.toml",
           os.path.join(d, "cam.parquet"))
    # a lathe program as turned every day: G96 with feed per revolution through G71/G70, G76 (decisions B103/B104)
    staged("lathe part G71/G70/G76 (G96, G99), lathe MLC, Parquet trace",
           root / "examples" / "lathe_part_g71_g70_g76.nc", None, os.path.join(d, "part.parquet"))


def ethercat_lockstep(cycles: int = 5000) -> None:
    """Lock-step over EtherCAT: `hil sim ethercat` (the default lathe's 3 drives: X, Z, spindle) in a
    network namespace behind a veth pair, the pysoem master here. The bus alone (the link's exchange,
    drives enabled, setpoints held) under default scheduling, then placed as a user asks for it (decisions
    E21): the bench's `[realtime] lockstep = "fifo"` (priority 50) for the master, `hil sim ethercat --cpu N
    --priority 50` for the slaves; then the bench program run by BenchRunner over that bus with the bench's
    lock-step clock (hil/placement.py, as `hil run` makes it; MLC, NC, trace off). Each line says what was
    granted. Needs root; prints why it is skipped otherwise. First, without root, the slaves' own work per
    frame in-process (benchmarks/bench_ecat_slaves.py)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from dataclasses import replace

    from benchmarks import bench_ecat_slaves
    from fieldbus.ethercat.link import EthercatLink
    from hil.placement import PREFIX, Placed, lockstep_clock, placement_cpu
    from virtual_bus.ethercat.veth import SimProcess, can_create

    bench_ecat_slaves.main([])
    why = can_create()
    if why is not None:
        print(f"EtherCAT lock-step: skipped ({why})")
        return
    bench = default_lathe()
    bench.realtime = replace(bench.realtime, lockstep="fifo", priority=50)
    placed_sim = ("--cpu", str(placement_cpu(bench.realtime)), "--priority", str(bench.realtime.priority))
    for sim_args in ((), placed_sim):
        with SimProcess(*sim_args, tag="ecat9") as sim:
            slaves_placed = sim.banner.partition("; ")[2] or "default scheduling"
            if sim_args:
                master = Placed()
                label = f"master {master.apply(bench.realtime.priority, placement_cpu(bench.realtime)).what}; slaves {slaves_placed}"
            else:
                master, label = None, "default scheduling"
            try:
                _bus_alone(bench, sim, cycles, label)
            finally:
                if master is not None:
                    master.restore()
            if not sim_args:
                continue
            runner = BenchRunner(bench, EthercatLink.for_bench(bench, sim.iface), None,
                                 clock=lockstep_clock(bench.cycle, bench.realtime))
            t0, c0, s0 = time.perf_counter(), time.thread_time(), _cpu_of(sim.proc.pid)
            r = runner.run_program(parse_program(PROGRAM, name="bench.nc"))
            wall, cpu, slaves = time.perf_counter() - t0, time.thread_time() - c0, _cpu_of(sim.proc.pid) - s0
            print(f"EtherCAT lock-step, bench program ({len(bench.axes) + len(bench.spindles)} drives; master {r.granted.removeprefix(PREFIX)}; "
                  f"slaves {slaves_placed}; bring-up included): {r.cycles} cycles, "
                  f"{r.sim_time:.2f} s simulated in {wall:.2f} s wall = {r.cycles / wall:,.0f} cycles/s ({r.sim_time / wall:.1f}x "
                  f"real time, {'completed' if r.ok else 'alarm ' + ', '.join(a.code_text for a in r.alarms)}); CPU per "
                  f"cycle: master {cpu / r.cycles * 1e6:.0f} µs, slaves {slaves / r.cycles * 1e6:.0f} µs")


def _bus_alone(bench, sim, cycles: int, label: str) -> None:
    """The link's exchange alone: every drive enabled, then `cycles` exchanges holding the position."""
    from fieldbus.cia402 import Cia402Master, Target
    from fieldbus.ethercat.link import EthercatLink
    from fieldbus.pdo import RxPdo

    link = EthercatLink.for_bench(bench, sim.iface)
    link.open()
    try:
        n = len(link.drives)
        masters = [Cia402Master() for _ in range(n)]
        rx = [RxPdo(mode=8) for _ in range(n - len(bench.spindles))] + [RxPdo(mode=9) for _ in bench.spindles]
        tx = link.exchange(rx)
        for m in masters:
            m.request(Target.ENABLED)
        for _ in range(200):  # enable every drive, then hold the position each reports
            for m, r, t in zip(masters, rx, tx):
                r.controlword = m.step(t.statusword)
                r.target_position = t.position_actual
            tx = link.exchange(rx)
        enabled = sum(m.enabled for m in masters)
        t0, c0, s0 = time.perf_counter(), time.thread_time(), _cpu_of(sim.proc.pid)
        for _ in range(cycles):
            for m, r, t in zip(masters, rx, tx):
                r.controlword = m.step(t.statusword)
            tx = link.exchange(rx)
        wall, cpu, slaves = time.perf_counter() - t0, time.thread_time() - c0, _cpu_of(sim.proc.pid) - s0
    finally:
        link.close()
    print(f"EtherCAT lock-step, bus alone ({n} drives, {enabled} enabled, veth + hil sim ethercat, {label}): "
          f"{cycles} cycles in {wall:.2f} s wall = {cycles / wall:,.0f} cycles/s; CPU per cycle: master "
          f"{cpu / cycles * 1e6:.0f} µs, slaves {slaves / cycles * 1e6:.0f} µs, so "
          f"{cycles / (cpu + slaves):,.0f} cycles/s when the two take turns on an otherwise idle machine "
          f"(load {os.getloadavg()[0]:.1f})")


def _cpu_of(pid: int) -> float:
    """User + system CPU seconds of another process (/proc/PID/stat), 0 where /proc cannot say."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


_MODES = {"0": "every cycle stepped", "1": "stretches, B21", "ahead": "stepped, refill and bus ahead"}


def realtime_runs(d: str, cam_blocks: int = 1500, cam: bool = True, modes: tuple[str, ...] = ("0", "1")) -> None:
    """`hil run --realtime` at the bench's 1 ms cycle, as a user runs it (hil.api.run: the bench's MLC,
    a Parquet trace): cycle work p50/p99/max for the lathe demo (lathe MLC) and a CAM program on
    benches/mill-3axis.toml. Figures, not a test: the machine's other load sets the tail."""
    from hil import api

    root = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(root))
    from benchmarks.bench_motion import cam_program

    programs = [("lathe demo, lathe MLC", root / "examples" / "lathe_demo.nc", None)]
    if cam:
        path = Path(d) / f"cam{cam_blocks}.nc"
        path.write_text(cam_program(cam_blocks))
        programs.append((f"CAM {cam_blocks:,} blocks, mill-3axis", path, root / "benches" / "mill-3axis.toml"))
    runs = [(label + how, program, bench, on)
            for label, program, bench in programs
            for how, on in (((f" (DELTAHIL_STRETCH={m}: {_MODES[m]})" if m in _MODES else f" ({m})"), m)
                            for m in modes)]
    saved = os.environ.get("DELTAHIL_STRETCH")
    for label, program, bench, on in runs:
        if on == "default":
            os.environ.pop("DELTAHIL_STRETCH", None)
        else:
            os.environ["DELTAHIL_STRETCH"] = on
        try:
            res = api.run(program, str(bench) if bench else None, trace=os.path.join(d, "rt.parquet"), realtime=True,
                          check=False)
        finally:
            if saved is None:
                os.environ.pop("DELTAHIL_STRETCH", None)
            else:
                os.environ["DELTAHIL_STRETCH"] = saved
        r = res.run
        e, j, b = r.timing.get("exec", {}), r.timing.get("jitter", {}), r.timing.get("between", {})
        print(f"real time, {label}, 1 ms ({r.granted}): {r.cycles} cycles ({r.stretched / max(1, r.cycles):.0%} in "
              f"stretches), {r.overruns} overruns; cycle work (wake-up to outputs written) "
              + "  ".join(f"{k} {e[k] * 1e6:.0f} µs" for k in ("p50", "p99", "p99.9", "max") if k in e)
              + "; between cycles (ahead work, in the slack) "
              + "  ".join(f"{k} {b[k] * 1e6:.0f} µs" for k in ("p50", "p99", "p99.9", "max") if k in b)
              + "; jitter " + "  ".join(f"{k} {j[k] * 1e6:.1f} µs" for k in ("p50", "p99", "max") if k in j)
              + ("" if r.ok else "  (" + ", ".join(a.code_text for a in r.alarms) + ")"))


def realtime(seconds: float) -> None:
    bench = default_lathe()
    clk = RealTimeClock(bench.cycle, bench.realtime)
    clk.start()
    for _ in range(int(seconds / bench.cycle)):
        clk.tick()
        clk.done()
    clk.stop()
    j, lat = clk.jitter.summary(), clk.latency.summary()
    print(f"real-time pacer, {seconds:g} s at 1 ms ({clk.granted}):")
    print("  jitter  " + "  ".join(f"{k} {j[k] * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")))
    print("  latency " + "  ".join(f"{k} {lat[k] * 1e6:.1f} µs" for k in ("p50", "p99", "p99.9", "max")))
    print(f"  overruns {clk.overruns}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("pacer_seconds", nargs="?", type=float, default=5.0,
                        help="seconds of the bare real-time pacer run at the end (default 5)")
    only = parser.add_mutually_exclusive_group()
    only.add_argument("--stages-only", action="store_true", help="only the issue-17 stage split (lathe demo, CAM, lathe part program)")
    only.add_argument("--ethercat-only", action="store_true", help="only EtherCAT lock-step (root: veth + hil sim)")
    only.add_argument("--realtime-only", action="store_true",
                      help="only `hil run --realtime` of the lathe demo and the CAM program, stepped and stretched")
    parser.add_argument("--repeat", type=int, default=1, metavar="N",
                        help="with --realtime-only: N alternating rounds of the runs (overruns move with the load)")
    parser.add_argument("--lathe-only", action="store_true", help="with --realtime-only: the lathe demo only")
    parser.add_argument("--modes", default="0,1", metavar="M,M",
                        help="with --realtime-only: the DELTAHIL_STRETCH values run in turn (default 0,1; 'ahead': "
                             "stepped with the refill and the bus exchange in the slack)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        if args.ethercat_only:
            ethercat_lockstep()
            return
        if args.realtime_only:
            for _ in range(args.repeat):
                realtime_runs(d, cam=not args.lathe_only, modes=tuple(args.modes.split(",")))
            return
        issue17(d)
        if args.stages_only:
            return
        from benchmarks.bench_wall import main as wall  # the same runs as a user times them: the whole process

        wall(["--repeat", "3"])
        ethercat_lockstep()
        realtime_runs(d)
        lockstep(None)
        lockstep(os.path.join(d, "t.csv"))
        lockstep(os.path.join(d, "t.parquet"))
    cam_work()
    realtime(args.pacer_seconds)


if __name__ == "__main__":
    main()
