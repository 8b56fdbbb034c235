"""Quiet cycles a stretch at a time (issue 17, decisions B19/B20).

While the channel runs a planned move with nothing event-like pending, the runner takes up to
MAX_CYCLES cycles at once: the planner's samples through `nc.motion.stretch.sample_stretch`, every drive
over the stretch (`virtual_bus.drive_stretch`), then each cycle's feedback handed to the runner's own
cycle (`BenchRunner._cycle`) in place of the bus exchange, with the cycle's sample in place of the
channel step. What the cycle does with them (masters, checks, MLC exchange, setpoints, trace row) is the
per-cycle code itself, so the trace is the cycle-by-cycle one; what a stretch saves is the bus, the drive
models and the channel step.

B19's order is kept: the drive steps in cycle k to the setpoint of cycle k-1, so a stretch of n cycles
sends the pending target and the first n-1 samples; the last sample waits in the RxPdo. A stretch ends
early, at the first cycle where it would differ from stepping:
- a drive would fault (following error window, overspeed) or the bench's overspeed check would fire:
  the stretch ends before that cycle, which runs through `_exchange`;
- the MLC scan changed what the channel reads (state, overrides, hold, alarms ...): that cycle's step
  is the channel's own, and the stretch ends after it;
- the user scan ran and changed something, the operator panel or an `--at` event wrote a device, or a
  cycle's outputs differ from what the drives were stepped with: the stretch ends after that cycle.
Ending early restores the planner and the drives as they were and takes the shorter stretch again (the
parts are deterministic, so its cycles are the same). `DELTAHIL_STRETCH=0` turns stretches off: tests
compare both runs column by column (`ahead`: real time stepped with the work ahead only, decision B31).

With the basic MLC in lock-step a stretch runs the NC's steps itself, feeds and solves included (decisions
B26/B27, hil/stretch_pass.py). Its real-time part (decision B21: pacing, work ahead in the slack) is hil/stretch_realtime.py, a mixin on
the same state; the planner saved and restored around a stretch, and the channel's signature, hil/stretch_state.py.

Why one file of ~510 lines: `Stretcher` is one decision (may the next cycles be taken at once, and where must they
end), and its start, cut, settle (B38) and finish checks read and restore the same runner, planner and drive state;
what is not that decision lives beside it (stretch_bulk, stretch_pass, stretch_reads, stretch_state, stretch_realtime;
stretch_ahead: with the basic MLC, a stepped cycle's whole channel step before its tick, B46).
"""

from __future__ import annotations

import copy
import os
from collections.abc import Iterator
from typing import Any


from fieldbus.cia402 import State, Target
from fieldbus.link import SimLink
from fieldbus.pdo import RxPdo, TxPdo
from hil.clock import LockStepClock, RealTimeClock
from hil.stretch_bulk import _rest, bulk_cycles, bulk_ok, count_cycles, first_change, outputs_hold
from hil.stretch_pass import Pass, _save as _save_nc, no_reads
from hil.stretch_reads import may_read
from hil import stretch_realtime
from hil.stretch_realtime import COLD_CYCLES, FIRST_CHANGE_NS, RealTimeStretches, _fed
from hil.stretch_thread import thread_running, thread_sampler
from hil.stretch_state import (_across, _event_due, _panel_state, _refilled, _restore_planner, _sample_across,
                               _save_planner, _signature, _stand_queued)
from mlc.basic import BasicMlc
from mlc.machine import Mlc
from mlc.spindle_axis import SPINDLE
from nc.channel import Channel, RunState
from nc.motion.planner import Planner, Setpoint, feed_rpm, replans
from nc.motion.plan_core import state_field  # the saved position (the C fields, bench B172)
from nc.motion.stretch import Samples, sample_per_rev, sample_stretch, settle_stretch, stand_stretch
from virtual_bus.drive import Cia402Drive
from virtual_bus.drive_stretch import Stretch, can_stretch, csp_stretch, csv_stretch

ENV = "DELTAHIL_STRETCH"  # "0": every cycle is stepped (the reference the tests compare against)
ENV_READS = "DELTAHIL_STRETCH_READS"  # "0": no feeds or solves inside stretches (B25's, benchmarks compare)
MAX_CYCLES = 64  # the planner's buffers are up to 64 cycles: a stretch never spans two
# A stretch whose NC steps inside it (B27) refills the planner itself, so the buffer does not bound it: PASS_CYCLES,
# then on to the first cycle whose feed reads nothing, at most PASS_OVER more (decision B68: a start and an end cost
# ≈ 0.3 ms, and a stretch cannot start at a reading cycle: one ending before it left it and the next ones stepped;
# a stop signal waits for the stretch's end, ≤ 0.3 s simulated, ≈ 30 ms of CPU on a CAM program)
PASS_CYCLES, PASS_OVER = 256, 32
# Real time (decision B21): a stretch's planner samples and drive models are computed in the slack of the period
# before its first cycle, so that work must fit there; RT_CYCLES cycles of it cost ≈ 0.2 ms on the lathe demo
RT_CYCLES = 16
MODE_CSP, MODE_CSV = 8, 9
# B103: after a start refused because the next sample changes the G96 rpm (X moving), none is tried for these cycles
CSS_RETRY = 16


def wanted(realtime: bool = False) -> bool:
    """Stretches on? Unless DELTAHIL_STRETCH=0, in lock-step and (since decision bench B37) in real time too, where
    `ahead` means every cycle stepped with its work ahead (B31). B21 had made them opt-in in real time (a start's
    work, ≈ 0.6-1 ms in one slack, overran it); B22-B36 cut that work into parts and guards, and with B36 they
    miss fewer deadlines than stepping on the lathe demo and the CAM program (interleaved runs, B32's rule)."""
    value = os.environ.get(ENV)
    return value not in ("0", "ahead") if realtime else value != "0"


def ahead_wanted() -> bool:
    """Real time with DELTAHIL_STRETCH=ahead (decision bench B31, opt-in): every cycle stepped, but the planner refill
    it will make (`Stretcher.ahead`) and its in-process bus exchange worked out in the slack before its tick. In
    lock-step the value is the default (stretches on)."""
    return os.environ.get(ENV) == "ahead"


def _spindle_linked(ch: Channel) -> bool:
    """G96 or a feed per revolution: what the cycles read moves with the spindle (decision bench B103)."""
    pl = ch.planner
    return ch.css_rpm is not None or ch._css_surface is not None or (bool(pl.blocks) and pl.blocks[0].move.per_rev)


class Stretcher(RealTimeStretches):
    """Takes stretches for one runner (a `hil.runner.BenchRunner`)."""

    def __init__(self, runner: Any, drives: list[Cia402Drive]) -> None:
        self.r = runner
        self.drives = drives
        # Real time: every cycle of a stretch is paced (its own tick, overrun check, outputs), none at once
        self.paced = type(runner.clock) is RealTimeClock
        self.max_cycles = RT_CYCLES if self.paced else MAX_CYCLES
        self.n_axes = len(runner.axes)
        self._sampler = sample_stretch  # the planner's samples of this stretch (stand_stretch while it waits)
        self.stretches = 0  # stretches taken and cycles in them (benchmarks, tests)
        self.cycles = 0
        self.ahead_used = 0  # real time: refills computed ahead and taken by their cycle
        self.aheads_skipped = 0  # real time: stepped cycles whose work ahead was skipped (B34)
        self.colds_skipped = 0  # real time: starts nothing prepared, not taken for lack of time left (B35)
        self.starts_skipped = 0  # real time: no start tried for lack of time left (B36)
        # real time: the refill the next stretch starts with, worked out in the slack before the last cycle of the
        # one before, with what it read (the planner's fields, the channel's signature): taken if still the same
        self._next_fill: tuple | None = None
        self._early: tuple | None = None
        self.fills_early = 0
        # real time (B22): the next start worked out a part a slack while this stretch's cycles are paced (_prepare,
        # a generator the pacing advances), and the start it made, taken when all it read is still the same
        self._prep: Iterator[None] | None = None
        self._spec: Any = None
        self._taken: Any = None
        self._cut_outs: tuple[int, list[Stretch]] | None = None  # a cut made in a paced cycle's slack (B22)
        self._fc_ns = FIRST_CHANGE_NS  # first_change's CPU a cycle where it works the drive status out (B22)
        self.specs_used = 0
        # B26/B27: the channel's feeds and the planner's steps run inside stretches (reads_ok False: B25's stretches)
        self.reads_ok = os.environ.get(ENV_READS) != "0"
        self.feeds = 0
        self._fed0 = False
        self.ahead_only = self.paced and not wanted(True)  # real time: steps every cycle, its refill ahead
        # B38: the runner's settle after the program (BenchRunner._settle) asks for stretches too: the channel has
        # finished and stands, only the drives settle; a stretch ends at the first cycle every axis is at rest
        self.settling = False
        self.steps_ahead = 0  # real time, the basic MLC: stepped cycles whose channel step ran before the tick (B46)
        self._css_retry = 0  # B103: the cycle from which a start is tried again under G96

    @classmethod
    def for_runner(cls, runner: Any) -> "Stretcher | None":
        """A stretcher where stretches can be exact: the in-process bus with its simulated drives, in lock-step
        or paced in real time (B21)."""
        link = runner.link
        rt = type(runner.clock) is RealTimeClock
        if not (wanted(rt) or (rt and ahead_wanted())) or type(link) is not SimLink or type(runner.clock) not in (LockStepClock, RealTimeClock):
            return None
        drives = list(link.slaves)
        if len(drives) != len(runner.rx) or any(type(d) is not Cia402Drive for d in drives):
            return None
        if type(runner.mlc) not in (Mlc, BasicMlc):
            return None
        return cls(runner, drives)

    # ---- one stretch ---------------------------------------------------------------------------
    def run(self, limit: int) -> bool:
        """Up to `limit` cycles as one stretch; False when no stretch can start here (step this cycle)."""
        r = self.r
        ch: Channel | None = r.channel
        self._early, self._next_fill = self._next_fill, None  # the one before's, for this start only
        self._taken, self._spec, self._prep = self._spec, None, None  # B22: the one before's, this start's only
        if limit < 2 or ch is None or self.ahead_only:
            return False
        if self.paced and r.clock.left_ns() < stretch_realtime.START_LEFT_NS:
            self.starts_skipped += 1  # B36: too near the next tick for a start's checks and set-up: step
            return False
        # B103: G96 or feed per revolution: the samples of the planner's buffer, ended where the spindle would change
        # what a cycle reads (neither the NC's steps inside the stretch nor a cruise across blocks)
        linked = _spindle_linked(ch)
        if linked and r.cycle < self._css_retry:
            return False  # B103: X moves under G96, the rpm changes every cycle: no start tried for a few cycles
        kind = self._quiet(r, ch)  # (after the back-off: `_quiet` only reads, and a start there is refused anyway)
        if kind is None:
            return False
        pl = ch.planner
        if kind == "run" and self.reads_ok and not self.paced and type(r.mlc) is BasicMlc and self._bulk_ok(r) \
                and not linked and (may_read(ch, pl) or (no_reads(ch) and not ch.alarms and not pl.held)):
            return self._run_pass(r, ch, pl, limit)  # B27: the NC's steps inside the stretch
        fill = None
        if kind in ("wait", "drain", "settle"):  # standing: an M/S/T code waits for its finish, the filter's tail,
            n = min(limit, self.max_cycles)        # or the drives settle after the program (B38)
            if kind == "drain":  # the cycle that begins with the filter settled issues the waiting code: stepped
                n = min(n, pl.filter.span - pl.filter._still)
            self._sampler = stand_stretch
        elif type(r.mlc) is BasicMlc and pl._buf_blk is not None and not linked:
            # a cruise, across its blocks (nothing reads the queue's length in between)
            n = _across(ch, pl, min(limit, self.max_cycles))
            self._sampler = _sample_across
        elif pl._thread is not None:  # B104: a thread chain, on the spindle's feedback worked out first
            if len(self.drives) <= self.n_axes:
                return False
            d = self.drives[self.n_axes]
            was = dict(d.__dict__)
            out = csv_stretch(d, r.rx[self.n_axes], min(limit, self.max_cycles), r.bench.cycle)
            d.__dict__.clear()
            d.__dict__.update(was)
            n = out.done
            if n < 2:
                return False
            self._sampler = thread_sampler(r, out, self.n_axes)
        elif pl.plan is None and pl._buf_done and pl.filter is not None and not pl.filter.settled and pl.at_rest:
            # an exact stop between blocks: the planner stands until its filter settled, the cycle that begins
            # settled starts the next block (stepped), as "drain" before a code
            n = min(limit, self.max_cycles, pl.filter.span - pl.filter._still)
            self._sampler = _stand_queued
        else:  # to the buffer's end: the planner stays on its block (dropped at the refill, a stepped cycle)
            n = min(limit, self.max_cycles, pl._block_rows())  # a cruise's buffer spans blocks: this one's rows
            self._sampler = sample_per_rev if not self.paced and pl.per_rev_plan() is not None else sample_stretch
            if self.paced:  # real time: this start worked out in the slacks of the stretch before (B22)
                started = self._spec_start(r, ch, pl, kind, limit, False)
                if started is not None:
                    return started
            # real time: where the buffer ran out, the refill the first cycle's step would make, made ahead (B21)
            fill = self._early_fill(r, ch, pl, kind) if self.paced and n == 0 else None
            if fill is not None:
                n = min(limit, self.max_cycles, fill[4])
                self._sampler = _refilled(fill)
        if self.paced and fill is None and self._sampler in (stand_stretch, _stand_queued):  # standing (B22)
            started = self._spec_start(r, ch, pl, kind, n, True)
            if started is not None:
                return started
        if self.paced:  # real time, a start nothing prepared: a short one, the next prepared in its slacks (B23)
            n = min(n, COLD_CYCLES)
            if r.clock.left_ns() < stretch_realtime.COLD_LEFT_NS:  # B35: too little of the period left for its work: step
                self.colds_skipped += 1
                return False
        if n < 2:
            return False
        saved_pl = _save_planner(pl)
        if fill is not None:  # the planner as before the refill: a stretch cut before its first sample steps it
            saved_pl["plan"] = (fill[0], fill[1])
        smp = self._sampler(pl, n)
        if smp is None:
            _restore_planner(pl, saved_pl)  # as it was (a refill ahead was put in place before sampling)
            return False
        if len(smp.positions) < n:  # a cruise's block that would not cruise any more: the stretch ends before it
            n = len(smp.positions)
            if n < 2:
                _restore_planner(pl, saved_pl)
                return False
        if linked and (c := self._css_bound(ch, smp, n)) < n:  # B103: before the cycle whose step changes the G96 rpm
            _restore_planner(pl, saved_pl)
            if c < 2:
                self._css_retry = r.cycle + CSS_RETRY
                return False
            smp, n = self._sampler(pl, c), c
        if kind not in ("wait", "settle"):  # (a finished channel's step feeds nothing either)
            _fed(ch, pl)
        rx0 = [copy.copy(rx) for rx in r.rx]  # what the drives are stepped with (the runner's change per cycle)
        saved_drives = [dict(d.__dict__) for d in self.drives]
        targets = self._targets(smp, rx0, n)
        outs = self._step_drives(rx0, targets, n)
        return self._launch(r, ch, pl, smp, n, (saved_pl, saved_drives, rx0, targets), outs)

    def _run_pass(self, r: Any, ch: Channel, pl: Planner, limit: int) -> bool:
        """A stretch whose NC steps inside it (B27, hil/stretch_pass.py), played at once."""
        # (the basic MLC: an AuxWatch warning due)
        n = first_change(r, ch, [], 0, min(limit, PASS_CYCLES + PASS_OVER), [])
        if n < 2:
            return False
        self._fed0, ch._fed = ch._fed, False  # a feed a stretch before ran for this first cycle (B26)
        _fed(ch, pl)
        saved_pl = _save_nc(pl)
        rx0 = [copy.copy(rx) for rx in r.rx]  # what the drives are stepped with (the runner's change per cycle)
        saved_drives = [dict(d.__dict__) for d in self.drives]
        ps = Pass(self, ch, pl, rx0, saved_drives, PASS_CYCLES)
        m = ps.run(n)
        self.feeds += ps.feeds
        if m < 2:  # (no feed ran: feeds come from the third cycle on)
            _restore_planner(pl, saved_pl)
            self._restore_drives(saved_drives)
            ch._fed = self._fed0
            return False
        self._sampler = sample_stretch
        return self._play(r, ch, pl, ps.samples(), ps.outs, m, (saved_pl, saved_drives, rx0, ps.targets))

    def _launch(self, r: Any, ch: Channel, pl: Planner, smp: Samples, n: int, saved: tuple,
                outs: list[Stretch]) -> bool:
        """The stretch's n sampled cycles with the drives stepped over them (`outs`): shortened to the first
        cycle a drive or the bench's overspeed check would fault in, then played."""
        saved_pl, saved_drives, rx0, targets = saved
        m = min(o.done for o in outs)
        if pl.per_rev_plan() is not None:
            m = min(m, self._rev_bound(r, pl, outs, m))
        if self.settling:  # B38: BenchRunner._settle stops after the first cycle every axis is at rest
            m = min(m, self._first_rest(r, outs, m))
        for i in range(self.n_axes):  # the bench's overspeed check (App. A 0x0602) fires in that cycle
            v, lim = outs[i].velocity_actual[:m], r._overspeed[i]
            if v and max(map(abs, v)) > lim:  # (in Python: numpy's conversions cost ≈ 20 µs a start, B33)
                m = next(c for c, x in enumerate(v) if abs(x) > lim)
        if m < 2:
            _restore_planner(pl, saved_pl)
            self._restore_drives(saved_drives)
            return False
        if m < n:
            outs = self._cut(pl, saved_pl, saved_drives, rx0, targets, m, m)
        self._fed0, ch._fed = ch._fed, False  # a feed a stretch before ran for this first cycle (B26)
        return self._play(r, ch, pl, smp, outs, m, saved)

    def _play(self, r: Any, ch: Channel, pl: Planner, smp: Samples, outs: list[Stretch], m: int,
              saved: tuple) -> bool:
        """The stretch's cycles through the runner's cycle, each with its feedback and sample."""
        saved_pl, saved_drives, rx0, targets = saved
        sig = _signature(ch)
        panel = _panel_state(r.on_cycle)
        gate = getattr(r.mlc, "gate", None)
        rpms: list[float] = []
        cmds: list[float] = []
        settle = pl.spindle_command is not None
        dt, link, clock = r.bench.cycle, r.link, r.clock
        fixed = [(d.error_code, d.mode) for d in self.drives]
        probes = [(o.last.touch_probe_status, o.last.touch_probe_pos1, o.last.digital_inputs) for o in outs]
        positions, lines, vel, mv, moves = smp.positions, smp.lines, smp.path_velocity, smp.move, smp.moves
        state = {"fell_back": False}
        # The MLC exchange reads the planner's own position (M3x352+i, axis at 0) before the cycle's step: the
        # raw sample of the cycle before, as it stood in stepping (sample_stretch moved it to the last one).
        if smp.raw is not None:  # a stretch over the planner's steps (B27): the rows it took
            raw = [state_field(saved_pl["pl"], "position"), *smp.raw[:m - 1]]
        else:
            raw = [state_field(saved_pl["pl"], "position"), *pl._buf_pos[pl._buf_i - m:pl._buf_i - 1]] \
                if self._sampler not in (stand_stretch, _stand_queued) else [pl.position] * m
        last_raw = pl.position
        k = 0

        def step(channel: Channel) -> Setpoint:
            if _signature(channel) != sig:  # the scan changed what the channel reads: its own step (B20)
                self._cut(pl, saved_pl, saved_drives, rx0, targets, k, k + 1, rpms, cmds)
                state["fell_back"] = True
                channel._fed = self._fed0 and k == 0
                return channel.step()
            if settle:
                rpms.append(float(pl.spindle_rpm()))
                cmds.append(float(pl.spindle_command()))  # type: ignore[misc]
            return Setpoint(positions[k], lines[k], float(vel[k]), mv if moves is None else moves[k])

        cut = False
        while k < m:
            # The rest at once once the NC outputs the stretch's state decides are written: by its first cycle,
            # or, from the first, when writing them now leaves every device the gated user scan read as it saw it
            if (k == 1 and self._bulk_ok(r)) or (k == 0 and self._bulk_ok(r) and outputs_hold(r, ch, raw[0])):
                # the first cycle whose scan would not be skipped (real time: within what the slack has time for)
                j = self._first_change(r, ch, outs, k, m, raw) if self.paced else first_change(r, ch, outs, k, m, raw)
                if j > k:
                    timings = None
                    if self.paced:  # each cycle paced, with its outputs; the rest of them at once in the slack
                        # before the last one (so the next stretch's work ahead has the slack after it to itself)
                        stop = j - 1 if j - k >= 2 else j
                        # the next stretch's start worked out in these cycles' slacks, a part a slack
                        # (B22), or the cut where it ends early
                        self._cut_outs = None
                        self._prep = self._prepare(r, ch, pl, last_raw, positions, m) if j == m else \
                            self._cut_ahead(pl, saved_pl, saved_drives, rx0, targets, j)
                        rows = self._paced_rows(r, outs, smp, k)  # each paced cycle's row in its slack (B36)
                        counted = [k]  # and the counters of the cycles paced, in the slack before the bulk part's

                        def count(c: int, outs: list[Stretch] = outs, k: int = k) -> None:
                            count_cycles(r, outs, k, c + 1)
                            counted[0] = c + 1

                        end, timings = self._pace(r, k, stop, positions, targets, panel, rows, count)
                        if end < stop or r.stop_request is not None or _panel_state(r.on_cycle) != panel:
                            j = end  # a stop or a press ended it (in its last paced cycle too): at once up to there
                            self._prep = self._spec = self._cut_outs = None
                    if j < m:  # the stretch ends before it: that cycle is stepped (real time: cut in a slack)
                        done = self._cut_outs
                        outs = done[1] if done is not None and done[0] == j else \
                            self._cut(pl, saved_pl, saved_drives, rx0, targets, j, j)
                        m, last_raw, cut = j, pl.position, True
                        if settle:
                            rpms, cmds = rpms[:k], cmds[:k]
                    last_row = bulk_cycles(r, ch, pl, smp, outs, k, m, raw[m - 1], (rpms, cmds) if settle else None,
                                           timings, timings is not None and r.trace is not None,
                                           counted[0] if timings is not None else None)
                    if last_row is not None:  # real time: the last cycle, paced after the rest
                        if not cut and self._spec is None:  # nothing cuts this stretch any more: the next
                            self._fill_next(r, ch, pl, last_raw)  # one's refill, unless its start is worked out
                        last_row(self._pace(r, m - 1, m, positions, targets, panel)[1][0])
                    if cut and settle:
                        settle_stretch(pl, rpms, cmds)
                    k = m
                    pl.position = last_raw
                    break
            r.timing = clock.tick()  # real time: the period's wake-up; the work above was in the last one's slack
            if r.timing.overrun:
                r._overrun()
            link.time += dt
            link.cycles += 1
            tx = [TxPdo(o.statusword[k], o.position_actual[k], o.velocity_actual[k], o.torque_actual[k],
                        o.following_error[k], ec, md, tps, tpp, di)
                  for o, (ec, md), (tps, tpp, di) in zip(outs, fixed, probes)]
            scans = gate.scans if gate is not None else 0
            pl.position = raw[k]
            r._cycle(tx, step)
            k += 1
            if state["fell_back"]:
                cut = True
                break
            pl.position = raw[k] if k < m else last_raw
            if k < m and not self._still_quiet(r, gate, scans, panel, rx0, targets, k):
                self._cut(pl, saved_pl, saved_drives, rx0, targets, k, k, rpms, cmds)
                cut = True
                break
        if not cut and settle:
            settle_stretch(pl, rpms, cmds)
        for d, rx in zip(self.drives, r.rx):
            d._rx = rx  # the runner's own RxPdo from now on, as exchange() latches it
        self.stretches += 1
        self.cycles += k
        return True

    def _css_bound(self, ch: Channel, smp: Samples, n: int) -> int:
        """B103: of a stretch's n samples under G96, how many come before the first whose step changes the G96
        speed (`Channel.css_state`): that cycle's trace row and spindle command have the new one, so it is stepped."""
        if ch._css_surface is None and ch.css_rpm is None:
            return n
        now = (ch._css_surface, ch._css_origin, ch.css_rpm)
        positions, moves, mv = smp.positions, smp.moves, smp.move
        for c in range(n):
            if ch.css_state(mv if moves is None else moves[c], positions[c]) != now:
                return c
        return n

    def _rev_bound(self, r: Any, pl: Planner, outs: list[Stretch], m: int) -> int:
        """B103: of a stretch's m cycles over a feed-per-revolution path, how many come before the first whose step
        would re-plan the feed from the measured spindle speed (`nc.motion.planner.replans`, on each cycle's
        feedback). The spindle command stays what it is at the start: anything that changes it changes what the
        channel or the drives see, which ends the stretch on its own (`_signature`, `_still_quiet`)."""
        p = pl.per_rev_plan()
        assert p is not None
        cmd = pl.spindle_command() if pl.spindle_command is not None else 0.0
        n = self.n_axes
        if len(r.scales) <= n:  # no spindle drive: the speed measured is the command (spindle_actual_rpm)
            return 0 if replans(p, *feed_rpm(cmd, cmd)) else m
        to_rpm, vel = r.scales[n].drive_to_rpm, outs[n].velocity_actual
        for c in range(m):
            if replans(p, *feed_rpm(to_rpm(vel[c]), cmd)):
                return c
        return m

    def _first_rest(self, r: Any, outs: list[Stretch], m: int) -> int:
        """B38: the cycles of a settle stretch up to and including the first one after which every axis is at rest
        (BenchRunner._at_rest on the rest counters feedback() would count, its following error); m if none."""
        from hil.runner import stands

        axes = range(self.n_axes)
        rest, last = r._rest[:self.n_axes], r._last_position[:self.n_axes]
        enabled = [r.masters[i].enabled for i in axes]  # (a stretch keeps every master in its state)
        for c in range(m):
            still = True
            for i in axes:
                o = outs[i]
                rest[i], last[i] = _rest(rest[i], last[i], o.position_actual[c:c + 1], o.velocity_actual[c:c + 1])
                still = still and stands(rest[i], o.following_error[c], enabled[i])
            if still:
                return c + 1
        return m

    # ---- real time -----------------------------------------------------------------------------------
    def _bulk_ok(self, r: Any) -> bool:
        """At once (stretch_bulk), or in real time paced with only the outputs per cycle (B21). Not on a bench
        whose overrun is an alarm: its alarm lands in the cycle after the late tick, which must be stepped."""
        return bulk_ok(r) and not (self.paced and r.bench.realtime.overrun == "alarm")

    # ---- conditions ----------------------------------------------------------------------------
    def _quiet(self, r: Any, ch: Channel) -> str | None:
        """Nothing event-like is pending, so every cycle of a stretch would take the same path through the NC,
        the MLC exchange and the drives (module doc): "run" (the channel runs a planned move), "wait" (an
        M/S/T code handed to the MLC waits for its finish, nothing moving but the drives settling), else None."""
        if (r.stop_request is not None or r._braking or r._winding_down or r._planner_failed or r._at_limit
                or r._servo_off or r._mlc_axes or r._alarmed_drives or r.result.alarms or ch.alarms):
            return None
        if (ch.emergency or ch._interrupt is not None or ch.skip_armed or _panel_state(r.on_cycle) is None
                or _event_due(r)):
            return None
        if self.paced and _spindle_linked(ch):  # (lock-step: the stretch ends where G96 or the spindle would change
            return None                          # what the cycles read, `_css_bound` and `_rev_bound`, B103)
        pl = ch.planner
        mlc = r.mlc
        if isinstance(mlc, Mlc):
            if mlc.gate is None and not getattr(mlc, "program_failed", False):
                return None  # a scan that runs every cycle may write anything: no stretch
            if mlc.gate is not None and (mlc.gate.last is None or mlc.gate.last.dirty):
                return None
            if mlc.link._mode_switch_cycles or mlc.caxis.state != SPINDLE:
                return None
        for i, (d, rx, m) in enumerate(zip(self.drives, r.rx, r.masters)):
            mode = MODE_CSP if i < self.n_axes else MODE_CSV
            if (m.state is not State.OPERATION_ENABLED or m.target is not Target.ENABLED or rx.mode != mode
                    or d.params.home_switch is not None or not can_stretch(d, rx, mode)):
                return None
        if pl.held:
            return None
        if pl._thread is not None or pl.threads_queued:
            # lock-step: a chain running through its block (B104), a move with a thread queued behind it (B103)
            if self.paced or ((pl._thread is not None or pl.blocks[0].kind == "thread") and not thread_running(pl)):
                return None
        if ch.state is RunState.WAIT_AUX:
            # the code is handed (strobe up) and not finished: the NC's side of the handshake stands still
            link = getattr(mlc, "link", None)
            if (type(mlc) is not Mlc or ch.pending_aux is None or link._handed is not ch.pending_aux
                    or link._system_hold is not None or link._m2(16) or pl.blocks):
                return None
            watch = r.progress
            if hasattr(watch, "_aux") and watch._aux is not ch.pending_aux:
                return None  # AuxWatch has not seen the code yet (it times the wait)
            return "wait"
        if ch.state is RunState.FINISHED and self.settling:  # B38: the program's end, the drives settling
            if (ch.pending_aux is not None or pl.blocks or pl.plan is not None or ch.single_block
                    or (isinstance(mlc, Mlc) and (mlc.link._handed is not None or mlc.link._system_hold is not None))):
                return None
            return "settle"
        if ch.state is not RunState.RUNNING or ch.pending_aux is not None:
            return None
        if isinstance(mlc, Mlc) and mlc.link._handed is not None:
            return None
        if not pl.blocks:  # the last move's filter tail before a waiting code or the program's end
            if (pl.plan is not None or pl.filter is None or pl.filter.settled or ch._limit_alarm is not None
                    or (ch._deferred is None and ch.end is None) or ch.single_block):
                return None
            budget = ch.statement_budget
            return None if budget is not None and budget.spent else "drain"
        if self.paced and pl.blocks[0].move.css is not None:
            return None
        # Channel._feed_planner reads nothing in these cycles: the program has ended, the queue is full (asked as
        # its loop asks), or it waits for the queue to drain (an M/S/T code, a sync, a limit alarm, single block)
        if ch.end is None and not pl.full and ch._deferred is None and ch._limit_alarm is None \
                and not (ch.single_block and ch._block_moves):
            return None
        budget = ch.statement_budget
        if budget is not None and budget.spent:
            return None
        return "run"

    def _still_quiet(self, r: Any, gate: Any, scans: int, panel: tuple | None, rx0: list[RxPdo],
                     targets: list[list[int]], k: int) -> bool:
        """After cycle k-1 of the stretch: nothing it did changes what cycle k reads or is stepped with."""
        if r.stop_request is not None:
            return False  # a signal: the stop path starts at the next cycle, stepped (a paced stretch is 16 ms)
        if gate is not None and gate.scans != scans and (gate.last is None or gate.last.dirty):
            return False  # the user scan ran and wrote: the NC reads it next cycle
        if _panel_state(r.on_cycle) != panel:
            return False
        for i, (rx, was) in enumerate(zip(r.rx, rx0)):
            if rx.controlword != was.controlword or rx.mode != was.mode or rx.target_velocity != was.target_velocity:
                return False
            if i < self.n_axes and rx.target_position != targets[i][k]:
                return False
        return True

    # ---- parts ---------------------------------------------------------------------------------
    def _targets(self, smp: Samples, rx0: list[RxPdo], n: int) -> list[list[int]]:
        """Each axis drive's targets, cycle by cycle: the pending one, then the samples as the runner sends them."""
        r = self.r
        org = r.origin.tolist()
        out = []
        for i in range(self.n_axes):
            cpu, o = r.scales[i]._cpu, org[i]  # AxisScaling.to_counts's expression, inline
            out.append([rx0[i].target_position] + [int(round((c - o) * cpu)) for c in smp.positions[: n - 1, i].tolist()])
        return out

    def _step_drives(self, rx0: list[RxPdo], targets: list[list[int]], n: int) -> list[Stretch]:
        dt = self.r.bench.cycle
        outs = []
        for i, (d, rx) in enumerate(zip(self.drives, rx0)):
            outs.append(csp_stretch(d, rx, targets[i][:n], dt) if i < self.n_axes else csv_stretch(d, rx, n, dt))
        return outs

    def _restore_drives(self, saved: list[dict]) -> None:
        for d, s in zip(self.drives, saved):
            d.__dict__.clear()
            d.__dict__.update(s)

    def _cut(self, pl: Planner, saved_pl: dict, saved_drives: list[dict], rx0: list[RxPdo],
             targets: list[list[int]], samples: int, cycles: int, rpms: list[float] | None = None,
             cmds: list[float] | None = None) -> list[Stretch]:
        """The stretch shortened: the planner as after `samples` samples, the drives after `cycles` cycles
        (taken again from the state before the stretch), the spindle settle count after those samples."""
        _restore_planner(pl, saved_pl)
        if samples:
            self._sampler(pl, samples)
        if rpms is not None and cmds is not None and pl.spindle_command is not None:
            settle_stretch(pl, rpms[:samples], cmds[:samples])
        self._restore_drives(saved_drives)
        return self._step_drives(rx0, targets, cycles)

