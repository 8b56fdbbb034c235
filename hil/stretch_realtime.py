"""The stretch runner in real time (decision B21): each cycle of a stretch paced with its own tick, and the
work of the next cycles (a stepped cycle's refill, the next stretch's) worked out ahead in the periods' slack.
A mixin of `hil.stretch.Stretcher`, on its state."""

from __future__ import annotations

import copy
from operator import is_
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from fieldbus.pdo import RxPdo
from hil.clock import CycleTiming
from hil.stretch_bulk import first_change, written_devices
from hil.stretch_state import (_NOT_AHEAD, _SPINDLE_FEEDBACK, _not_ahead, _panel_state, _refilled, _restore_planner,
                               _sample_across, _save_planner, _signature, _stand_queued)
from mlc.basic import BasicMlc
from nc.channel import Channel, RunState
from nc.motion.planner import Planner, Setpoint
from nc.motion.stretch import Samples, sample_stretch, stand_stretch
from virtual_bus.drive_stretch import Stretch, csp_stretch, csv_stretch

# A part of the next start (B22) runs in a paced cycle's slack only while this much of the period is left: the
# largest part (a refill, or the planner samples) is ≈ 0.2-0.3 ms of CPU on the 2-vCPU VM
PREP_LEFT_NS = 600_000
# first_change where the gated user scan read drive status devices: its first guess of ns a cycle (measured after),
# and the part of the period left after it for the first paced cycle's wake-up (B22)
FIRST_CHANGE_NS = 40_000
FIRST_CHANGE_MARGIN_NS = 150_000
# A start nothing prepared (after a stepped cycle: a block's end, a dropped or cut start) samples and models only
# this many cycles in its slack (B23): its work there scales with the cycles (≈ 25 µs a cycle on the 2-vCPU VM). 4
# (was 8) since B33: its 2-3 paced slacks hold the next start's 4-5 parts, several a slack within SLACK_BUDGET_NS
COLD_CYCLES = 4
# B33: a paced slack takes one part of the next start, and more while less than this went since the cycle's
# outputs were written (on the clock the pacer reads; the parts are ≈ 50-250 µs each, a refill's solve more)
SLACK_BUDGET_NS = 250_000
# B34: a stepped cycle's work ahead (its in-process bus exchange and its refill, p50 150 µs in the CAM program) is
# skipped when the cycle before it worked longer than AHEAD_WORK_NS or less than AHEAD_LEFT_NS of the period is left:
# the next cycle then does that work itself, after its tick, as stepping does (a block solve's ≈ 1 ms cycle left
# no room for it: 29 of 44 late ticks of CAM followed such slacks, B33). 600 µs (was 300) since B39: the lathe demo's
# stepped cycles paced are 200-430 µs, and over 300 each skipped the next one's exchange ahead, which made that one
# as long: chains of 2-5 stepped cycles over 150 µs after a block end (benchmarks/rt_census.py)
AHEAD_WORK_NS = 600_000
AHEAD_LEFT_NS = 500_000
# B35: a start nothing prepared (B23: its samples and models in this slack, p50 ≈ 600 µs in the CAM program at load
# 1-3) is taken only while this much of the period is left; else the cycle steps (exact, as always). 550 µs (was
# 700) since B39: after a block end's stepped cycle (200-400 µs) 700 refused the next start 1-4 times in a row, each
# refusal a stepped cycle of 200-400 µs (37-86 a lathe demo run, the most of its stepped cycles); at 500-600 the
# overruns stayed as many (rt_census A/B)
COLD_LEFT_NS = 550_000
# B36: no stretch start at all (not even a prepared one: its checks and set-up, p50 ≈ 330 µs at load 4) while less
# than this is left of the period, as after a stepped cycle's block solve in the CAM program; the cycle steps
START_LEFT_NS = 500_000
_WRITTEN: dict[int, set] = {}


def _all_same(d: dict, a: dict) -> bool:
    """Every field of `a` is the very object in `d` (B22's check, in C loops: ≈ 3x a generator's speed, B33)."""
    return all(map(is_, map(d.get, a), a.values()))


def _fed(ch: Channel, pl: Planner) -> None:
    """What a stretch's first cycle's feed does before it finds nothing to read (the same in its later cycles)."""
    pl.closed = ch.end is not None or ch._deferred is not None or ch._limit_alarm is not None
    if ch.statement_budget is not None:
        ch.statement_budget.new_cycle()


@dataclass
class _Start:
    """A stretch start worked out ahead (B22), with what it read: the planner (its fields, filter, queue and plan
    as they were), the channel's signature, the drives' fields and the RxPdos it assumed the last cycle leaves."""

    asked: int  # the cycles Stretcher.run asks for (with a refill: as many as it buffered)
    n: int  # the cycles sampled, fewer where a drive's stretch ends early
    sampler: Callable  # sample_stretch (after a refill: with `fill`), stand_stretch or _stand_queued
    sig: tuple
    blocks: list
    plan_fields: dict | None
    saved_pl: dict  # _save_planner before (with a refill's plan as before): what a cut restores
    after_pl: dict  # _save_planner after the samples (with a refill's plan as after)
    fill: tuple | None
    smp: Samples
    rx0: list[RxPdo]
    targets: list[list[int]]
    saved_drives: list[dict]
    drives_after: list[dict]
    outs: list[Stretch]


class RealTimeStretches:
    """`Stretcher`'s real-time methods."""

    def _pace(self, r: Any, k: int, m: int, positions: np.ndarray, targets: list[list[int]],
              panel: tuple | None, rows: Callable[[int, CycleTiming], None] | None = None,
              count: Callable[[int], None] | None = None) -> tuple[int, list[CycleTiming]]:
        """Real time, a bulk stretch (B21): cycles k … m-1 paced one by one, each its tick (the wait for its
        deadline, the overrun count, its timing) and its outputs, the setpoints of its sample (converted
        ahead, here in the slack), and with `rows` its trace row (B36); with `count`, the runner's counters of
        the cycles paced so far in the slack before the last one's (B36); the rest of those cycles (the MLC)
        is done at once after the last one (`bulk_cycles`). Ends after a cycle in which a stop was
        asked or the panel was pressed, which the next cycle must see. Returns the end (k + the cycles paced)
        and their timings."""
        clock, rx = r.clock, r.rx
        n_axes = self.n_axes
        org = r.origin.tolist()
        last = positions[len(targets[0]) - 1].tolist() if n_axes else []
        # the setpoint each cycle writes: the sample of that cycle (targets[i][c + 1]; the last one converted here)
        tgt = [targets[i][1:] + [r.scales[i].to_counts(last[i] - org[i])] for i in range(n_axes)]
        pairs = list(zip(rx[:n_axes], tgt))
        timings: list[CycleTiming] = []
        for c in range(k, m):
            t = clock.tick()
            timings.append(t)
            if t.overrun:
                r._overrun()  # counted: a bench whose overrun is an alarm takes no paced bulk (_bulk_ok)
            for out, col in pairs:
                out.target_position = col[c]
            clock.written()
            clock.done()
            if rows is not None:  # the cycle's trace row, in its own slack as stepping writes it (B36)
                rows(c, t)
            if count is not None and c == m - 2:  # the counters of cycles k … c, not in the bulk part's slack
                count(c)
            # parts of the next stretch's start in this slack (B22): one, more while its budget holds (B33)
            first = True
            while self._prep is not None and c < m - 1 and clock.left_ns() > PREP_LEFT_NS \
                    and (first or clock.slack_ns() < SLACK_BUDGET_NS):
                first = False
                try:
                    next(self._prep)
                except StopIteration:
                    self._prep = None
            if r.stop_request is not None or _panel_state(r.on_cycle) != panel:
                break
        return k + len(timings), timings

    def _paced_rows(self, r: Any, outs: list[Stretch], smp: Samples, k: int
                    ) -> Callable[[int, CycleTiming], None] | None:
        """B36: the trace row of each paced cycle c = k, k+1, … (in order), written in its own slack instead of all
        at once in the bulk part's: BenchRunner._row's expressions (hil/cycle_lean.row) on the stretch's columns,
        with the time, cycle and line carried as bulk_cycles and stepping count them. None without a trace."""
        trace = r.trace
        if trace is None:
            return None
        write, facs, n_axes, dt = trace.write, r._factors, self.n_axes, r.bench.cycle
        org = r.origin.tolist()
        positions, lines = smp.positions, smp.lines
        # the spindle's command column: its target velocity, the same through the stretch (_still_quiet)
        spindle = [r.rx[i].target_velocity / f.raw_per_cps / f.cpu / f.lead * 60.0
                   for i, f in enumerate(facs) if i >= n_axes]
        axes = list(zip(outs[:n_axes], facs[:n_axes], org))
        spindles = list(zip(outs[n_axes:], facs[n_axes:], spindle))
        now = [r.time, r.cycle, r.line]

        def row(c: int, timing: CycleTiming) -> None:
            t, cycle, line = now
            t += dt  # as bulk_cycles' accumulate and stepping's r.time add, one cycle at a time
            line = lines[c] or line
            now[:] = t, cycle + 1, line
            out: list = [round(t, 9), line, cycle + 1, timing.period, timing.late, ""]  # no alarms: _quiet
            for cmd, (o, f, o0) in zip(positions[c].tolist(), axes):
                cpu = f.cpu
                out += [cmd, o.position_actual[c] / cpu + o0, o.velocity_actual[c] / f.raw_per_cps / cpu,
                        o.torque_actual[c] * f.torque, o.following_error[c] / cpu, o.statusword[c]]
            for o, f, cmd in spindles:
                cpu, rpc, lead = f.cpu, f.raw_per_cps, f.lead
                out += [cmd, o.velocity_actual[c] / rpc / cpu / lead * 60.0, o.position_actual[c] / cpu % 360.0,
                        o.torque_actual[c] * f.torque, o.statusword[c]]
            write(out)

        return row

    def _fill_next(self, r: Any, ch: Channel, pl: Planner, last_raw: Any) -> None:
        """In the slack before a paced stretch's last cycle, with its bulk part (nothing cuts it any more), where
        it samples its block's buffer to the end: the refill the next stretch will start with (_refill_ahead),
        worked out on the planner as this stretch leaves it (its position the last raw sample), kept with what
        it read; so the slack after the last cycle, the next stretch's start, holds that much less. That start
        takes it only when all of that is still the same (_early_fill), else works the refill out itself."""
        self._next_fill = None
        if self._sampler in (stand_stretch, _stand_queued, _sample_across) or not pl._buf_done:
            return  # standing, or a cruise across blocks: no refill where it ends
        pos, pl.position = pl.position, last_raw
        try:
            before = pl.state()
            sig = _signature(ch)
            fill = self._refill_ahead(r, ch, pl)
        finally:
            pl.position = pos
        if fill is not None:
            self._next_fill = (fill, before, sig)

    def _early_fill(self, r: Any, ch: Channel, pl: Planner, kind: str) -> tuple | None:
        """The refill ahead of this stretch's start: the one worked out early (_fill_next) when the planner's
        fields are the very ones it read, its plan's fields and queue as they were and the channel's signature
        the same; else worked out here (B21)."""
        early, self._early = self._early, None
        if early is not None and kind == "run":
            fill, before, sig = early
            p, p0, q0 = fill[0], fill[1], fill[5]
            q = pl.blocks
            if (pl.plan is p and (p is None or p.__dict__ == p0) and pl.same_state(before) and len(q) == len(q0)
                    and all(a is b for a, b in zip(q, q0)) and _signature(ch) == sig):
                self.fills_early += 1
                return fill
        return self._refill_ahead(r, ch, pl)

    def skip_ahead(self) -> bool:
        """Real time (B34): True when this slack should not work the next stepped cycle's part ahead (its bus
        exchange, its refill): the cycle before it was long, or the next tick is near. Counted."""
        clock = self.r.clock
        if clock.work_ns() > AHEAD_WORK_NS or clock.left_ns() < AHEAD_LEFT_NS:
            self.aheads_skipped += 1
            return True
        return False

    def ahead(self) -> Callable[[Channel], Setpoint] | None:
        """Real time (B21): the planner's refill of the next cycle (a stepped cycle where the planner's buffer
        ran out: ≈ 100 µs of sampling, more with a block's end and the next one's solve) computed now, in the
        period's slack, and kept aside; the cycle's step puts it in place when nothing the refill read changed
        since (the planner's fields, its queue and its plan as they were, the channel's inputs), and otherwise
        leaves the planner to refill itself. None: the cycle steps as usual."""
        r = self.r
        ch = r.channel
        if not self.paced or ch is None:
            return None
        pl = ch.planner
        fill = self._refill_ahead(r, ch, pl, across=True)
        if fill is None:
            return None
        p, p0, s1, p1, _, q0, q1 = fill
        s0 = pl.state()
        sig = _signature(ch)

        def step(channel: Channel) -> Setpoint:
            q = pl.blocks
            if (_signature(channel) == sig and pl.plan is p and (p is None or p.__dict__ == p0)
                    and len(q) == len(q0) and all(a is b for a, b in zip(q, q0)) and pl.same_state(s0)):
                pl.update_state(s1)
                if p is not None:
                    p.__dict__.update(p1)
                if q1 is not None:  # the refill finished blocks: the queue as it left it (the same deque)
                    q.clear()
                    q.extend(q1)
                self.ahead_used += 1
            return channel.step()

        return step

    def _refill_ahead(self, r: Any, ch: Channel, pl: Planner, across: bool = False) -> tuple | None:
        """The refill the next channel step would make (its buffer ran out), worked out and put back: (plan, its
        fields before, the planner's fields after, the plan's fields after, buffer rows in this block, the queue
        before and after, None if unchanged), or None. Without `across` only a refill that continues the same
        plan in the same block (a stretch starting there hands its samples to the MLC scans before the step;
        ending a block changes what they read); with it also one that ends blocks and solves the next, for a
        step that puts it in place after the scan. Spindle feedback (feed per revolution, threads) is not read
        ahead: the refills that would are left to the step."""
        p = pl.plan
        if (p is None and not across) or (p is not None and p.kind == "cruise") or not pl._buf_done \
                or not pl.blocks or pl.blocks[0].move.per_rev:
            return None  # per_rev: _check_spindle, which comes before the refill, may re-plan; a cruise's
            # sampling snaps the next blocks' starts (it changes blocks in place)
        if self._quiet(r, ch) != "run":
            return None
        s0, p0, q0 = pl.state(), dict(p.__dict__) if p is not None else None, list(pl.blocks)
        guards = ("_no_progress",) if across else _NOT_AHEAD
        for name in guards:
            setattr(pl, name, _not_ahead)
        feedback = {name: s0[name] for name in _SPINDLE_FEEDBACK if s0.get(name) is not None}
        for name in feedback:
            setattr(pl, name, _not_ahead)
        try:
            # what the step's feed sets first (it reads nothing in a quiet cycle: Stretcher._quiet)
            pl.closed = ch.end is not None or ch._deferred is not None or ch._limit_alarm is not None
            pl._refill()
            ok = (across or pl.plan is p) and not pl._buf_done
        except Exception:  # _NotAhead, or an alarm of the refill: the cycle's own, it raises it there
            ok = False
        finally:
            for name in guards:
                delattr(pl, name)
            pl.update_state(feedback)
        rows = pl._block_rows() if ok else 0
        s1, p1, q1 = pl.state(), dict(p.__dict__) if p is not None else None, list(pl.blocks)
        pl.restore(s0)
        if p is not None:
            p.__dict__.clear()
            p.__dict__.update(p0)
        pl.blocks.clear()
        pl.blocks.extend(q0)
        changed = len(q1) != len(q0) or any(a is not b for a, b in zip(q1, q0))
        return (p, p0, s1, p1, rows, q0, q1 if changed else None) if ok else None

    # ---- the next start, a part a slack (B22) ----------------------------------------------------------
    def _prepare(self, r: Any, ch: Channel, pl: Planner, last_raw: Any, positions: np.ndarray,
                 m: int) -> Iterator[None]:
        """The start the next stretch would make where this one (m cycles, not cut) ends, worked out in the
        slacks of its paced cycles, one part a slack: the refill where its buffer runs out, the planner's
        samples, each drive's model. Each part leaves the planner and the drives as it found them; the
        result is `self._spec`, which the next start takes when all it read is still the same (_spec_start).
        A standing stretch (an M/S/T code's wait, a filter's tail) prepares another as long as Stretcher.run's
        would be (its filter's tail as this one leaves it)."""
        sampler: Callable = self._sampler
        if sampler is _sample_across:
            return  # a cruise across its blocks: the next start samples across too, which is not worked out ahead
        here = pl.position
        pl.position = last_raw  # as this stretch leaves it
        standing = sampler in (stand_stretch, _stand_queued)
        if not standing:
            sampler = sample_stretch
        try:
            before = _save_planner(pl)
            blocks, p0 = list(pl.blocks), dict(pl.plan.__dict__) if pl.plan is not None else None
            sig = _signature(ch)
            rows = pl._block_rows() if not standing else 0
            fill = self._refill_ahead(r, ch, pl) if rows == 0 and not standing else None
        finally:
            pl.position = here
        if standing:
            f = pl.filter
            wait = sampler is stand_stretch and ch.state in (RunState.WAIT_AUX, RunState.FINISHED)  # FINISHED: B38
            n = self.max_cycles if wait else min(self.max_cycles, f.span - f._still) if f is not None else 0
        elif rows == 0 and fill is None:
            return
        else:
            n = min(self.max_cycles, fill[4] if fill is not None else rows)
        if n < 2:
            return
        if fill is not None:
            yield
        saved_pl = dict(before)
        if fill is not None:
            saved_pl["plan"] = (fill[0], fill[1])
        asked = n  # the cycles Stretcher.run would ask for; fewer where a drive's stretch ends early (below)
        while True:
            _restore_planner(pl, saved_pl)  # the planner as at the first part (its position this stretch's end)
            try:
                smp = (_refilled(fill) if fill is not None else sampler)(pl, n)
                if smp is not None:
                    after = _save_planner(pl)
                    if fill is not None:
                        after["plan"] = (fill[0], dict(fill[0].__dict__))
            finally:
                _restore_planner(pl, saved_pl)
                pl.position = here
            if smp is None or len(smp.positions) < 2:
                return
            n = len(smp.positions)
            yield
            org, last = r.origin.tolist(), positions[m - 1].tolist()
            rx0 = [copy.copy(rx) for rx in r.rx]
            for i in range(self.n_axes):  # the setpoint this stretch's last cycle writes
                rx0[i].target_position = r.scales[i].to_counts(last[i] - org[i])
            targets = self._targets(smp, rx0, n)
            saved_drives, drives_after, outs = [], [], []
            dt = r.bench.cycle
            for i, (d, rx) in enumerate(zip(self.drives, rx0)):
                if i:
                    yield
                s0 = dict(d.__dict__)
                outs.append(csp_stretch(d, rx, targets[i][:n], dt) if i < self.n_axes else csv_stretch(d, rx, n, dt))
                drives_after.append(dict(d.__dict__))
                d.__dict__.clear()
                d.__dict__.update(s0)
                saved_drives.append(s0)
            done = min(o.done for o in outs)
            if done >= n:
                break
            if done < 2:  # a drive would fault or latch an index at once: that start steps its cycle
                return
            n = done  # the start as Stretcher._launch would cut it (a spindle's index pulse): taken again shorter
            yield
        self._spec = _Start(asked, n, sampler, sig, blocks, p0, saved_pl, after, fill, smp, rx0, targets,
                            saved_drives, drives_after, outs)

    def _spec_start(self, r: Any, ch: Channel, pl: Planner, kind: str, n: int, exact: bool) -> bool | None:
        """The start worked out ahead (_prepare), taken when it sampled with this start's sampler as many cycles
        (`exact`; else at most n), and the planner, the channel, the drives and the RxPdos are as it read them
        (the same objects; the filter's windows the same rows); None: work it out."""
        spec, self._taken = self._taken, None
        if spec is None or spec.sampler is not self._sampler or (spec.asked != n if exact else spec.asked > n) \
                or not self._same(spec, r, ch, pl):
            return None
        _restore_planner(pl, spec.after_pl)  # the planner as its samples left it
        if spec.fill is not None:
            self._sampler = _refilled(spec.fill)  # a cut samples again from before the refill
            self.fills_early += 1
        if kind not in ("wait", "settle"):  # as Stretcher.run
            _fed(ch, pl)
        for d, after in zip(self.drives, spec.drives_after):
            d.__dict__.clear()
            d.__dict__.update(after)
        self.specs_used += 1
        return self._launch(r, ch, pl, spec.smp, spec.n, (spec.saved_pl, spec.saved_drives, spec.rx0, spec.targets),
                            spec.outs)

    def _same(self, spec: _Start, r: Any, ch: Channel, pl: Planner) -> bool:
        if _signature(ch) != spec.sig:
            return False
        if not pl.same_state(spec.saved_pl["pl"]):  # its C fields too (nc.motion.plan_core, B172)
            return False
        q = pl.blocks
        if len(q) != len(spec.blocks) or not all(map(is_, q, spec.blocks)):
            return False
        if pl.plan is not None and pl.plan.__dict__ != spec.plan_fields:
            return False
        z = spec.saved_pl.get("zones")
        if z is not None and (len(z) != len(pl._zones.zones) or not all(map(is_, z, pl._zones.zones))):
            return False
        f = pl.filter
        if f is not None and not f.same_state(spec.saved_pl["f"]):  # (its state bit for bit)
            return False
        for drv, s0 in zip(self.drives, spec.saved_drives):
            dd = drv.__dict__
            if len(dd) != len(s0):
                return False
            s0["_rx"] = dd["_rx"]  # (not compared) what a cut restores, as run() saves it
            if not _all_same(dd, s0):
                return False
        return all(a == b for a, b in zip(r.rx, spec.rx0))

    def _cut_ahead(self, pl: Planner, saved_pl: dict, saved_drives: list[dict], rx0: list[RxPdo],
                   targets: list[list[int]], j: int) -> Iterator[None]:
        """A stretch that ends before cycle j, cut in a paced cycle's slack (not in the bulk part's), B22."""
        self._cut_outs = (j, self._cut(pl, saved_pl, saved_drives, rx0, targets, j, j))
        yield

    def _first_change(self, r: Any, ch: Channel, outs: list[Stretch], k: int, m: int, raw: list) -> int:
        """`first_change` in real time (B22): where it works the drive status out cycle by cycle (the gated user
        scan read devices it writes, or waits for a timer: ≈ 30-40 µs a cycle), over as many cycles as this
        slack has time for; a stretch with no change among them ends after them (the next cycle is stepped,
        which is always exact)."""
        mlc = r.mlc
        if type(mlc) is BasicMlc:
            return first_change(r, ch, outs, k, m, raw)
        rec = mlc.gate.last
        x = mlc.link.x
        devices = _WRITTEN.get(x)
        if devices is None:
            devices = _WRITTEN[x] = written_devices(x)  # the devices first_change works out cycle by cycle
        if not rec.timers and not any(key in devices for key in rec.reads):
            return first_change(r, ch, outs, k, m, raw)  # nothing worked out cycle by cycle: a few µs
        clock = r.clock
        left = clock.left_ns() - FIRST_CHANGE_MARGIN_NS
        e = m if self._fc_ns * (m - k) <= left else min(m, k + max(2, left // self._fc_ns))
        t0 = clock.now_ns()
        j = first_change(r, ch, outs, k, e, raw)
        # the next guess: this call's cost a cycle, or a tenth less than the last guess when that was higher
        self._fc_ns = max(20_000, (clock.now_ns() - t0) // max(1, min(j + 1, e) - k), self._fc_ns * 9 // 10)
        return j
