"""Which cycles of a real-time run are stepped, why, and what each costs (issue 17, decision bench B38).

Usage: python benchmarks/rt_census.py [PROGRAM [BENCH]] [--runs N]   (DELTAHIL_STRETCH as for `hil run`; default the
lathe demo with the lathe MLC and a Parquet trace, 1 ms, stretches on)

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
import os
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import hil.clock as clock_mod  # noqa: E402
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("program", nargs="?", default=str(ROOT / "examples" / "lathe_demo.nc"))
    ap.add_argument("bench", nargs="?", default=None)
    ap.add_argument("--runs", type=int, default=1)
    args = ap.parse_args()
    from hil import api

    install()
    for _ in range(args.runs):
        CYCLES.clear()
        with tempfile.TemporaryDirectory() as d:
            res = api.run(args.program, args.bench, trace=os.path.join(d, "rt.parquet"), realtime=True, check=False)
        r = res.run
        e = r.timing.get("exec", {})
        print(f"DELTAHIL_STRETCH={os.environ.get('DELTAHIL_STRETCH', '(unset)')}: {r.cycles} cycles "
              f"({r.stretched / max(1, r.cycles):.1%} in stretches), {r.overruns} overruns; cycle work p50 "
              f"{e.get('p50', 0) * 1e6:.0f} µs, p99 {e.get('p99', 0) * 1e6:.0f} µs")
        report(CYCLES)


if __name__ == "__main__":
    main()
