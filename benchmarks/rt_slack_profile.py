"""Where a real-time run's slack work goes (issue 17, decision bench B33): the thread CPU of each period's slack
(from the cycle's outputs written to the next tick) of `hil run --realtime`, split by the pieces done there.

Usage: python benchmarks/rt_slack_profile.py [PROGRAM [BENCH]]   (DELTAHIL_STRETCH as for `hil run`; default the
lathe demo with the lathe MLC and a Parquet trace, 1 ms, stretches on)

Each piece is wrapped (its exclusive thread CPU, so a piece inside another counts once); a piece of the next start
worked out in a paced slack (B22) is listed as `prep:`. A slack is put in one class: a block-end `solve` (the
planner's refill or plan solve > 200 µs), `bulk` (a paced stretch's cycles at once, before its last), `start` (a
stretch start, prepared ahead or not: `cold start` with its own samples and drive models), `prep part` or `other`
(a paced cycle's bookkeeping), or `step ahead` (a stepped cycle's channel step before its tick, the basic MLC,
B46). It prints the slack distribution, per class its p50/p99/max, how many slacks passed
300/500 µs and how many late ticks followed, and the mean split of the classes that pass 300 µs. Figures, not a
test: the wrappers add ≈ 1 µs a call, and the load of the machine sets the tail.
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import hil.clock as clock_mod  # noqa: E402
from benchmarks.rt_pieces import Pieces  # noqa: E402
import hil.stretch as S  # noqa: E402
import hil.stretch_ahead as SA  # noqa: E402
import hil.stretch_bulk as SB  # noqa: E402
import hil.stretch_realtime as SR  # noqa: E402
import hil.stretch_state as SS  # noqa: E402
from mlc.nc_link import ChannelLink  # noqa: E402
from nc.channel import Channel  # noqa: E402
from nc.motion.planner import Planner  # noqa: E402

_acc: dict[str, int] = defaultdict(int)
_in_slack = [False]
SLACKS: list[tuple[int, dict[str, int], list[bool]]] = []  # (thread CPU ns, by piece, [a late tick followed])


def _account(label: str, ns: int) -> None:
    if _in_slack[0]:
        _acc[label] += ns


_pieces = Pieces(_account, base="other", gen_prefix="prep:")
_charge, _wrap, _wrap_gen = _pieces.charge, _pieces.wrap, _pieces.wrap_gen


def install() -> None:
    written, tick = clock_mod.RealTimeClock.written, clock_mod.RealTimeClock.tick

    def _written(self):
        written(self)
        _charge()
        _acc.clear()
        _in_slack[0] = True
        _pieces.restart()

    def _tick(self):
        late = [False]
        if _in_slack[0]:
            _charge()
            _in_slack[0] = False
            SLACKS.append((sum(_acc.values()), dict(_acc), late))
        t = tick(self)
        late[0] = t.overrun
        return t

    clock_mod.RealTimeClock.written, clock_mod.RealTimeClock.tick = _written, _tick
    bulk = SB.bulk_cycles

    def bulk_cycles(*a, **k):  # its returned last_row (the last paced cycle's row) charged on its own
        last_row = bulk(*a, **k)
        return None if last_row is None else _wrap("last_row", last_row)

    for name, f in (("bulk_cycles", bulk_cycles), *((n, getattr(SB, n)) for n in ("first_change", "outputs_hold")),
                    *((n, getattr(S, n)) for n in ("sample_stretch", "stand_stretch", "csp_stretch", "csv_stretch")),
                    *((n, getattr(SS, n)) for n in ("_stand_queued", "_sample_across", "_save_planner",
                                                     "_restore_planner"))):
        w = _wrap(name, f)
        for mod in (S, SR, SS, SB):  # the same wrapper everywhere: samplers are compared by identity
            if hasattr(mod, name):
                setattr(mod, name, w)
    for cls, names in ((S.Stretcher, ("run", "_quiet", "_spec_start", "_same", "_launch", "_play", "_pace",
                                      "_refill_ahead", "_fill_next", "ahead", "_cut", "_first_change")),
                       (Planner, ("_refill", "_start_plan", "_sample", "_end_plan")),
                       (ChannelLink, ("nc_outputs",))):
        for n in names:
            setattr(cls, n, _wrap(f"{cls.__name__}.{n}", getattr(cls, n)))
    import hil.runner as R
    R.BenchRunner._exchange = _wrap("BenchRunner._exchange", R.BenchRunner._exchange)
    SA.step_ahead = _wrap("step_ahead", SA.step_ahead)  # B46: a stepped cycle's channel step before its tick
    Channel._feed_planner = _wrap("Channel._feed_planner", Channel._feed_planner)
    S.Stretcher._prepare = _wrap_gen("_prepare", S.Stretcher._prepare)
    S.Stretcher._cut_ahead = _wrap_gen("_cut_ahead", S.Stretcher._cut_ahead)


def kind(d: dict[str, int]) -> str:
    if d.get("Planner._start_plan", 0) + d.get("Planner._refill", 0) + d.get("Planner._end_plan", 0) > 200_000:
        return "solve"
    if "bulk_cycles" in d:
        return "bulk"
    if "step_ahead" in d:
        return "step ahead"
    if "Stretcher.run" in d and ("csp_stretch" in d or "csv_stretch" in d):
        return "cold start"
    if "Stretcher._spec_start" in d or "Stretcher._quiet" in d:
        return "start"
    if any(k.startswith("prep:") or k == "_prepare" for k in d):
        return "prep part"
    return "other"


def report() -> None:
    us = np.array([s[0] for s in SLACKS]) / 1e3
    print(f"slack thread CPU: p50 {np.percentile(us, 50):.0f} µs, p99 {np.percentile(us, 99):.0f}, p99.9 "
          f"{np.percentile(us, 99.9):.0f}, max {us.max():.0f}; slacks > 300 µs {(us > 300).sum()}, > 500 µs "
          f"{(us > 500).sum()}; late ticks {sum(s[2][0] for s in SLACKS)}")
    by: dict[str, list] = defaultdict(list)
    for s in SLACKS:
        by[kind(s[1])].append(s)
    print(f"{'slack':11s} {'n':>6s} {'p50':>5s} {'p99':>5s} {'max':>6s} {'>300':>5s} {'>500':>5s} {'late after':>10s}")
    for k, v in sorted(by.items(), key=lambda kv: -len(kv[1])):
        a = np.array([s[0] for s in v]) / 1e3
        print(f"{k:11s} {len(v):6d} {np.percentile(a, 50):5.0f} {np.percentile(a, 99):5.0f} {a.max():6.0f} "
              f"{(a > 300).sum():5d} {(a > 500).sum():5d} {sum(s[2][0] for s in v):10d}")
    for k, v in by.items():
        if sum(s[0] > 300_000 for s in v) < 10:
            continue
        agg: dict[str, int] = defaultdict(int)
        for s in v:
            for piece, ns in s[1].items():
                agg[piece] += ns
        top = sorted(agg.items(), key=lambda kv: -kv[1])[:12]
        print(f"{k}, mean µs a slack: " + ", ".join(f"{p} {ns / 1e3 / len(v):.0f}" for p, ns in top))


def main() -> None:
    from hil import api

    program = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "examples" / "lathe_demo.nc")
    bench = sys.argv[2] if len(sys.argv) > 2 else None
    os.environ.setdefault("DELTAHIL_STRETCH", "1")
    install()
    with tempfile.TemporaryDirectory() as d:
        res = api.run(program, bench, trace=os.path.join(d, "rt.parquet"), realtime=True, check=False)
    r = res.run
    e = r.timing.get("exec", {})
    print(f"DELTAHIL_STRETCH={os.environ['DELTAHIL_STRETCH']}: {r.cycles} cycles ({r.stretched / max(1, r.cycles):.0%} "
          f"in stretches), {r.overruns} overruns; cycle work p50 {e.get('p50', 0) * 1e6:.0f} µs, p99 "
          f"{e.get('p99', 0) * 1e6:.0f} µs ({r.granted})")
    report()


if __name__ == "__main__":
    main()
