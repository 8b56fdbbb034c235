"""Which cycles of a real-time run are stepped, why, and what each costs (issue 17, decision bench B38).

Usage: python benchmarks/rt_census.py [PROGRAM [BENCH]] [--runs N] [--list N]   (DELTAHIL_STRETCH as for `hil run`;
default the lathe demo with the lathe MLC and a Parquet trace, 1 ms, stretches on)

Then every late tick (an overrun: a period without a fresh setpoint on a real bus) is put down to one cause (decision
bench B98): the host (the run queue, steal or a late wake-up; RT throttling), the Parquet writer thread holding the GIL,
a garbage collection, page faults, or the piece of our own work (in the cycle or in its slack, by exclusive thread
CPU) that took the period past its deadline; `--list N` prints the N latest with what their period spent.

Every cycle's work (tick to outputs written, the figure `hil run --realtime` reports as cycle work) is put in one
class: `paced` (a stretch's cycle, only its outputs), `stretch cycle` (a stretch's cycle through the runner's own
cycle: its first, or one before the stretch went to its bulk part), or `stepped: <why>`, why `Stretcher.run` took
no stretch there: `start left` (B36: too little of the period left for a start), `cold left` (B35: a start nothing
prepared, too little left), `not quiet: <condition>` (the first of `Stretcher._quiet`'s conditions that held; a
block's end, a code's handshake, ...), `too short` (quiet, but fewer than 2 cycles to take: the buffer's end) and
`stopping`/`no stretcher`. A stepped cycle's label says too whether its refill and bus exchange ran ahead (B21/B31),
its whole channel step (`step ahead`, the basic MLC, B46) or were skipped (B34). It prints per class the count, the work p50/p99/max and how many cycles passed 150 µs, and
where the run's p99 lands. Figures, not a test: the wrappers add ≈ 1-2 µs to a stepped cycle's slack.
"""

from __future__ import annotations

import argparse
import gc
import os
import resource
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import hil.clock as clock_mod  # noqa: E402
from benchmarks.rt_pieces import Pieces  # noqa: E402
import hil.runner as R  # noqa: E402
import hil.stretch as S  # noqa: E402
from nc.channel import RunState  # noqa: E402

TARGET_US = 150.0  # issue 17's p99 for the lathe demo
_tag = ["start"]
_why = ["no stretcher"]
_in_run = [0]
CYCLES: list[tuple[str, int]] = []  # (class, work ns) a cycle, in order


def _not_quiet(st, r, ch) -> str:
    """The first group of Stretcher._quiet's conditions that holds (a coarse name for the census)."""
    if r.stop_request is not None or r._braking or r._winding_down or r._planner_failed:
        return "stopping"
    if r._at_limit or r._alarmed_drives or r.result.alarms or ch.alarms or ch.emergency:
        return "alarm"
    if ch.css_rpm is not None or ch._css_surface is not None:
        return "css"
    if ch._interrupt is not None or ch.skip_armed or S._event_due(r) or S._panel_state(r.on_cycle) is None:
        return "event"
    mlc = r.mlc
    if isinstance(mlc, S.Mlc):
        if mlc.gate is None or mlc.gate.last is None or mlc.gate.last.dirty:
            return "user scan wrote"
        if mlc.link._mode_switch_cycles or mlc.caxis.state != S.SPINDLE:
            return "C axis"
    for i, (m, rx) in enumerate(zip(r.masters, r.rx)):
        if m.state is not S.State.OPERATION_ENABLED or m.target is not S.Target.ENABLED:
            return "drive state"
    pl = ch.planner
    if pl.held:
        return "hold"
    if pl._thread is not None or pl.threads_queued:
        return "thread"
    if ch.state is RunState.WAIT_AUX:
        return "aux handshake"
    if ch.state is not RunState.RUNNING or ch.pending_aux is not None:
        return f"channel {ch.state.name.lower()}"
    if isinstance(mlc, S.Mlc) and mlc.link._handed is not None:
        return "aux handshake"
    if not pl.blocks:
        return "queue empty"
    if pl.blocks[0].move.css is not None:
        return "css"
    if ch.end is None and not pl.full and ch._deferred is None and ch._limit_alarm is None:
        return "feed reads"
    return "other"


def install() -> None:
    written, tick = clock_mod.RealTimeClock.written, clock_mod.RealTimeClock.tick

    def _written(self):
        if not self._written:
            CYCLES.append((_tag[0], self.now_ns() - self._start_ns))
        written(self)

    clock_mod.RealTimeClock.written = _written
    run, quiet, pace = S.Stretcher.run, S.Stretcher._quiet, S.Stretcher._pace

    def _run(self, limit):
        s0, c0 = self.starts_skipped, self.colds_skipped
        _why[0] = "too short"
        _in_run[0] += 1
        _tag[0] = "stretch cycle"
        try:
            ok = run(self, limit)
        finally:
            _in_run[0] -= 1
        if not ok:
            if self.starts_skipped != s0:
                _why[0] = "start left"
            elif self.colds_skipped != c0:
                _why[0] = "cold left"
        return ok

    def _quiet(self, r, ch):
        k = quiet(self, r, ch)
        if k is None and _in_run[0]:
            _why[0] = "not quiet: " + _not_quiet(self, r, ch)
        return k

    def _pace(self, *a, **k):
        _tag[0] = "paced"
        try:
            return pace(self, *a, **k)
        finally:
            _tag[0] = "stretch cycle"

    S.Stretcher.run, S.Stretcher._quiet, S.Stretcher._pace = _run, _quiet, _pace
    exchange = R.BenchRunner._exchange

    def _exchange(self, step=None, bus_ahead=True, ahead=None):
        how = "skipped ahead" if not bus_ahead else "refill ahead" if step is not None else "bus ahead"
        _tag[0] = f"stepped: {_why[0]} ({how})"
        if ahead is not None:  # B46: the whole channel step ahead, or (where it cannot) the refill ahead or nothing
            def ahead(tx, _ahead=ahead):
                st = self._stretcher
                n = st.steps_ahead
                step = _ahead(tx)
                how = "step ahead" if st.steps_ahead != n else "refill ahead" if step is not None else "bus ahead"
                _tag[0] = f"stepped: {_why[0]} ({how})"
                return step
        try:
            return exchange(self, step, bus_ahead, ahead)
        finally:
            if _why[0] not in ("power_up", "settle", "shutdown"):
                _why[0] = "stopping"  # unless Stretcher.run says otherwise before the next one

    R.BenchRunner._exchange = _exchange
    for name in ("power_up", "_settle", "_shutdown"):  # the cycles outside the program's loop
        def outside(self, *a, _f=getattr(R.BenchRunner, name), _name=name.strip("_"), **k):
            _why[0] = _name
            try:
                return _f(self, *a, **k)
            finally:
                _why[0] = "stopping"

        setattr(R.BenchRunner, name, outside)


def report(cycles: list[tuple[str, int]], out=sys.stdout) -> None:
    us = np.array([c[1] for c in cycles]) / 1e3
    p99 = float(np.percentile(us, 99))
    over = int((us > TARGET_US).sum())
    print(f"{len(us)} cycles: work p50 {np.percentile(us, 50):.0f} µs, p99 {p99:.0f} µs; over {TARGET_US:.0f} µs: "
          f"{over} ({over / len(us):.2%}; p99 <= {TARGET_US:.0f} needs fewer than {len(us) // 100})", file=out)
    by: dict[str, list[float]] = defaultdict(list)
    for tag, ns in cycles:
        by[tag].append(ns / 1e3)
    print(f"{'class':58s} {'n':>6s} {'p50':>5s} {'p99':>5s} {'max':>6s} {'>150':>5s} {'>p99':>5s}", file=out)
    for tag, v in sorted(by.items(), key=lambda kv: -len(kv[1])):
        a = np.array(v)
        print(f"{tag:58s} {len(a):6d} {np.percentile(a, 50):5.0f} {np.percentile(a, 99):5.0f} {a.max():6.0f} "
              f"{(a > TARGET_US).sum():5d} {(a >= p99).sum():5d}", file=out)
    stepped = sum(len(v) for t, v in by.items() if t.startswith("stepped"))
    print(f"stepped {stepped} ({stepped / len(us):.2%})", file=out)



# ---- why each overrun happened (issue 17, session 19, decision bench B98) -------------------------------------------
# A period runs from a cycle's wake-up (its tick returning) to the next tick's call; the tick is late (an overrun)
# when that call comes after its deadline. What each period spent is recorded: its thread CPU, the sleeps it asked
# for and got (the B43 sleep before the warm-up), its run-queue wait (/proc/thread-self/schedstat), its context
# switches, page faults and system time (getrusage RUSAGE_THREAD), the garbage collections (gc.callbacks), the
# Parquet writer thread's busy time overlapping it (it shares the GIL), and the thread CPU of each piece of our work.
_tt = time.thread_time_ns
_now = time.monotonic_ns
_SCHED = os.open("/proc/thread-self/schedstat", os.O_RDONLY) if os.path.exists("/proc/thread-self/schedstat") else -1


def _probe() -> tuple:
    ru = resource.getrusage(resource.RUSAGE_THREAD)
    rd = int(os.pread(_SCHED, 128, 0).split()[1]) if _SCHED >= 0 else 0
    return _tt(), rd, ru.ru_nvcsw, ru.ru_nivcsw, ru.ru_minflt + ru.ru_majflt  # (system time: tick-sampled here)


@dataclass
class Period:
    start: int  # the wake-up (tick returned), monotonic ns
    probe: tuple  # _probe() at the wake-up
    late_start: int  # ns the wake-up came after its deadline
    wait_from: int = 0  # the tick's call before the wake-up (its sleep and spin)
    wait: tuple = ()  # _probe() differences over that wait
    deadline: int = 0  # the next tick's deadline
    written: int = 0  # outputs written: cycle work ends, the slack's work begins
    call: int = 0  # the next tick called
    over: int = 0  # ns the call came after the deadline (> 0: an overrun)
    cpu: int = 0
    run_delay: int = 0
    vcsw: int = 0
    ivcsw: int = 0
    faults: int = 0
    slept: int = 0  # ns in sleeps outside the tick (asked and got)
    sleep_over: int = 0  # ns those sleeps overshot what they asked
    sleeps: int = 0
    gc_ns: int = 0
    writer_ns: int = 0
    pieces: dict = field(default_factory=lambda: defaultdict(int))  # "cycle:" / "slack:" + name → thread CPU ns
    cause: str = ""
    duty: float = 0.0  # the thread's CPU over the second before, a share of it (_duties)


PERIODS: list[Period] = []
_cur: list[Period | None] = [None]
_phase = ["cycle"]
_WRITER: list[tuple[int, int]] = []  # the Parquet writer's busy intervals (monotonic ns)
_gc_t0 = [0]


def _account(label: str, ns: int) -> None:
    p = _cur[0]
    if p is not None:
        p.pieces[_phase[0] + ": " + label] += ns


_pieces = Pieces(_account)
_charge, _piece, _piece_gen = _pieces.charge, _pieces.wrap, _pieces.wrap_gen


def install_causes() -> None:
    from hil import cycle_lean, fit_ahead, stretch_ahead as SA, stretch_bulk as SB, stretch_realtime as SR
    from hil import stretch_pass as SP, stretch_state as SS, trace_parquet as TP
    from fieldbus.link import SimLink
    from nc.channel import Channel
    from nc.motion import fit_memo, planner_runs, spline_feed
    from nc.motion.planner import Planner

    clk = clock_mod.RealTimeClock
    tick, written, init = clk.tick, clk.written, clk.__init__

    def _tick(self):
        if hasattr(self, "idle"):  # B98's idle work ends the slack: counted in it, as the tick's own call does
            _piece("idle work", self.idle)()
        call = self.now_ns()
        pr = _probe()
        _charge()
        p = _cur[0]
        if p is not None:
            p.call, p.deadline, p.over = call, self._deadline, call - self._deadline
            p.cpu = pr[0] - p.probe[0]
            p.run_delay, p.vcsw, p.ivcsw, p.faults = (x - y for x, y in zip(pr[1:], p.probe[1:]))
            PERIODS.append(p)
            _cur[0] = None
        _phase[0] = "tick"
        t = tick(self)
        if PERIODS and t.overrun and PERIODS[-1].over <= 0:  # on time at the call, late once the probe above ran
            PERIODS[-1].over, PERIODS[-1].cause = 1, "the census's own probe (instrumentation)"
        q = _probe()
        _cur[0] = Period(self._start_ns, q, int(t.late * 1e9), wait_from=call,
                         wait=tuple(x - y for x, y in zip(q, pr)))
        _phase[0] = "cycle"
        _pieces.restart()
        return t

    def _written(self):
        written(self)
        _charge()
        if _cur[0] is not None:
            _cur[0].written = self._done_ns
        _phase[0] = "slack"

    def _init(self, *a, **k):
        init(self, *a, **k)
        sleep = self.sleep

        def timed_sleep(s):
            if _phase[0] == "tick":
                return sleep(s)
            t0 = _now()
            sleep(s)
            dt = _now() - t0
            p = _cur[0]
            if p is not None:
                p.slept += dt
                p.sleep_over += max(0, dt - int(s * 1e9))
                p.sleeps += 1
        self.sleep = timed_sleep

    clock_mod.RealTimeClock.tick, clock_mod.RealTimeClock.written = _tick, _written
    clock_mod.RealTimeClock.__init__ = _init

    def _gc(phase, info):
        if phase == "start":
            _gc_t0[0] = _now()
        elif _cur[0] is not None:
            _cur[0].gc_ns += _now() - _gc_t0[0]
    gc.callbacks.append(_gc)

    write_part = TP.ParquetTrace._write_part

    def _write_part(self, *a, **k):
        t0 = _now()
        try:
            return write_part(self, *a, **k)
        finally:
            _WRITER.append((t0, _now()))
    TP.ParquetTrace._write_part = _write_part

    # our pieces, each its exclusive thread CPU
    for name in ("bulk_cycles", "first_change", "outputs_hold"):
        w = _piece(name, getattr(SB, name))
        for mod in (S, SR, SS, SB):
            if hasattr(mod, name):
                setattr(mod, name, w)
    for name in ("sample_stretch", "stand_stretch", "csp_stretch", "csv_stretch"):  # compared by identity: one wrapper
        w = _piece(name, getattr(S, name))
        for mod in (S, SR, SS, SB):
            if hasattr(mod, name):
                setattr(mod, name, w)
    for cls, names in ((S.Stretcher, ("run", "_refill_ahead", "_fill_next", "_spec_start", "_launch")),
                       (Planner, ("_refill", "_start_plan", "push", "step")),
                       (Channel, ("_feed_planner",)), (SimLink, ("exchange",)), (SP.Pass, ("run",)),
                       (spline_feed.RunFeed, ("_fix",)),
                       (fit_memo.FitReceiver, tuple(n for n in ("get", "work_part")
                                                    if hasattr(fit_memo.FitReceiver, n))),
                       (planner_runs.FittedRuns, ("_let_through",)),
                       (R.BenchRunner, ("_row",))):
        for n in names:
            setattr(cls, n, _piece(f"{cls.__name__}.{n}", getattr(cls, n)))
    S.Stretcher._prepare = _piece_gen("Stretcher._prepare", S.Stretcher._prepare)
    S.Stretcher._cut_ahead = _piece_gen("Stretcher._cut_ahead", S.Stretcher._cut_ahead)
    SA.step_ahead = _piece("step_ahead", SA.step_ahead)
    R.warm = _piece("warm", cycle_lean.warm)
    for cls in (TP.ParquetTrace,):
        for n in ("write", "write_columns"):
            setattr(cls, n, _piece(f"trace.{n}", getattr(cls, n)))
    mlc_scan = []
    for mod in ("mlc.basic", "mlc.machine"):
        m = __import__(mod, fromlist=["x"])
        for cname in ("BasicMlc", "Mlc"):
            c = getattr(m, cname, None)
            if c is not None and "scan" in c.__dict__ and c not in mlc_scan:
                mlc_scan.append(c)
                c.scan = _piece(f"{cname}.scan", c.scan)
    del fit_ahead


def _overlap(a: int, b: int) -> int:
    """ns of the Parquet writer's busy time within [a, b]."""
    return sum(max(0, min(y, b) - max(x, a)) for x, y in _WRITER if y > a and x < b)


FAULT_NS = 2_000  # what a page fault is taken to cost (≈ 1-2 µs; few are expected once memory is locked)


THROTTLE_NS = 10_000_000  # a run-queue wait this long at SCHED_FIFO is the kernel's RT throttling (50 ms a second)
THROTTLE_DUTY = 0.85  # … where our thread's CPU over the second before was near the RT share (95 % by default)


def _duties(periods: list[Period]) -> None:
    """Each period's `duty`: the thread's CPU (its work and the pacer's spin) over the second before its wake-up."""
    j, acc = 0, 0
    for p in periods:
        acc += p.cpu + (p.wait[0] if p.wait else 0)
        while periods[j].start < p.start - 1_000_000_000:
            q = periods[j]
            acc -= q.cpu + (q.wait[0] if q.wait else 0)
            j += 1
        p.duty = acc / 1e9


def _classify(p: Period) -> str:
    """The cause of one late tick (the call `over` ns after its deadline): the first that alone accounts for it.
    A wake-up already late by as much is the wait's (the tick's sleep and spin before it): the GIL held by the
    writer (a voluntary switch beyond the sleep's), the host (the run queue, or a vCPU not running: steal)."""
    over = p.over
    if p.cause:
        return p.cause
    p.writer_ns = _overlap(p.start, p.call)
    if p.late_start >= over and p.wait:
        cpu, rd, vcsw, ivcsw = p.wait[:4]
        if rd >= THROTTLE_NS and p.duty >= THROTTLE_DUTY:
            return "RT throttling (our thread's CPU over the last second near sched_rt_runtime_us)"
        if vcsw > 1 and _overlap(p.wait_from, p.start):
            return "trace writer (GIL) at the wake-up"
        if rd or ivcsw:
            return "host: preempted (run queue) at the wake-up"
        return "host: late wake-up (steal, interrupts)"
    avail = p.deadline - p.start  # the period from its wake-up to the deadline
    off = (p.call - p.start) - p.cpu - p.slept  # neither running nor asleep: preempted, stolen, waiting for the GIL
    if p.gc_ns and p.gc_ns >= over:
        return "garbage collection"
    if p.writer_ns >= over and p.vcsw > p.sleeps:
        return "trace writer (GIL)"
    if p.cpu > avail:  # our own CPU alone passes the deadline
        if p.faults * FAULT_NS >= p.cpu - avail:
            return "page faults"
        if not p.pieces:
            return "ours: (unwrapped)"
        name, _ = max(p.pieces.items(), key=lambda kv: kv[1])
        return "ours: " + name
    if p.sleep_over >= over:
        return "host: late wake-up from a sleep"
    if p.run_delay >= over or p.ivcsw:
        return "host: preempted (run queue)"
    if off >= over:
        return "host: steal / interrupts"
    return "mixed"


def report_causes(periods: list[Period], out=sys.stdout, listing: int = 0) -> dict[str, int]:
    _duties(periods)
    late = [p for p in periods if p.over > 0]
    counts: dict[str, list[Period]] = defaultdict(list)
    for p in late:
        p.cause = _classify(p)
        counts[p.cause].append(p)
    print(f"{len(late)} late ticks of {len(periods)} periods; by cause (late by µs p50 / max; the period's thread "
          f"CPU, "
          f"run-queue wait, off-CPU µs p50):", file=out)
    for cause, ps in sorted(counts.items(), key=lambda kv: -len(kv[1])):
        o = np.array([p.over for p in ps]) / 1e3
        cpu = np.median([p.cpu for p in ps]) / 1e3
        rd = np.median([p.run_delay for p in ps]) / 1e3
        off = np.median([(p.call - p.start) - p.cpu - p.slept for p in ps]) / 1e3
        print(f"  {cause:60s} {len(ps):4d}  late {np.median(o):6.0f} / {o.max():6.0f}  cpu {cpu:6.0f}  run queue "
              f"{rd:5.0f}  off {off:6.0f}", file=out)
    for p in sorted(late, key=lambda p: -p.over)[:listing]:
        top = sorted(p.pieces.items(), key=lambda kv: -kv[1])[:4]
        print(f"    late {p.over / 1e3:7.0f} µs: {p.cause}; CPU share over the second before {p.duty:.0%}; period "
              f"{(p.call - p.start) / 1e3:.0f} of {(p.deadline - p.start) / 1e3:.0f}, late start "
              f"{p.late_start / 1e3:.0f}, cpu {p.cpu / 1e3:.0f}, cycle work {(p.written - p.start) / 1e3:.0f}, "
              f"slept {p.slept / 1e3:.0f} (over {p.sleep_over / 1e3:.0f}), run queue "
              f"{p.run_delay / 1e3:.0f}, ivcsw {p.ivcsw}, vcsw {p.vcsw}, faults {p.faults}, "
              f"gc {p.gc_ns / 1e3:.0f}, writer {p.writer_ns / 1e3:.0f}; "
              + ", ".join(f"{k} {v / 1e3:.0f}" for k, v in top), file=out)
    return {c: len(v) for c, v in counts.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("program", nargs="?", default=str(ROOT / "examples" / "lathe_demo.nc"))
    ap.add_argument("bench", nargs="?", default=None)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--list", type=int, default=0, help="list the N latest ticks with what their period spent")
    args = ap.parse_args()
    from hil import api

    install()
    install_causes()
    total: dict[str, int] = defaultdict(int)
    for _ in range(args.runs):
        CYCLES.clear()
        PERIODS.clear()
        _WRITER.clear()
        with tempfile.TemporaryDirectory() as d:
            res = api.run(args.program, args.bench, trace=os.path.join(d, "rt.parquet"), realtime=True, check=False)
        r = res.run
        e = r.timing.get("exec", {})
        print(f"DELTAHIL_STRETCH={os.environ.get('DELTAHIL_STRETCH', '(unset)')}: {r.cycles} cycles "
              f"({r.stretched / max(1, r.cycles):.1%} in stretches), {r.overruns} overruns; cycle work p50 "
              f"{e.get('p50', 0) * 1e6:.0f} µs, p99 {e.get('p99', 0) * 1e6:.0f} µs")
        report(CYCLES)
        for cause, n in report_causes(PERIODS,
                                      listing=args.list).items():
            total[cause] += n
    if args.runs > 1:
        print("all runs: " + ", ".join(f"{c} {n}" for c, n in sorted(total.items(), key=lambda kv: -kv[1])))


if __name__ == "__main__":
    main()
