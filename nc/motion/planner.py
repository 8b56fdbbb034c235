"""The planner: a look-ahead queue of blocks turned into one setpoint per bus cycle.

`push` adds a move to the look-ahead queue (junction speed + incremental backward pass).
When a block starts, the forward pass caps its end speed by what its entry speed can reach,
and ruckig solves ONE 1-DoF profile along its path length, (s, v, a) → (L, v_end, 0). The
profile's phases are sampled a chunk of cycles at a time with numpy and mapped through the
block geometry. A profile is re-solved only on an event: a feed/rapid override change, a feed
hold, a reset, a change of the spindle's actual speed under feed per revolution.

Operator controls (the channel maps the MLC's relays onto them):
  feed_override (0..1.5), rapid_override (0..1; 0 = slow rapid), hold()/resume(), stop(),
  dry_run (feed of every cutting block replaced by `dry_run_feed`).

Why one class of ~750 lines: the planner is one state machine. Its queue, active plan, sample buffer
and event flags are read and written by every method below, in an order that the one-setpoint-per-
cycle guarantee depends on. Three groups of its methods that each serve one feature live in mixins
beside it, on the same state: cruise sampling across blocks (planner_cruise.py, decision motion 44),
corner blends and the filter's share (planner_corners.py, decisions 42-45) and thread chains
(planner_thread.py); its records in plan_state.py. The pure parts live beside it too: look-ahead
passes (lookahead.py), ruckig profiles (profile.py), tolerance shares (shares.py), the position
filter (smoothing.py), threading geometry (threading.py, thread_corners.py) and stretch sampling
(stretch.py).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.alarm_table import PLANNING_STALL
from nc.alarms import NcAlarm
from nc.motion.limits import MotionConfig
from nc.motion.block import Block, new_block
from nc.motion.lookahead import (CUT, MARGIN, RAPID, THREAD, Limits, backward, change_distance, fastest_state,
                                 max_speed_at, reach)
from nc.motion.path import Segment
from nc.motion.plan_core import PlanCore
from nc.motion.plan_state import CHUNK, Setpoint, _Plan
from nc.motion.filter_ramps import HISTORY, FilterStops, seg_history
from nc.motion.planner_corners import CornerShares, _corner_at
from nc.motion.planner_cruise import CruiseSampling
from nc.motion.planner_runs import FittedRuns
from nc.motion.spline_feed import NOTHING
from nc.motion.planner_thread import ThreadStepping
from nc.motion.hold_stop import brakes_below, crosses_too_fast
from nc.motion.profile import clip, fits_queue, later, solve_axes, solve_position, solve_velocity, time_at
from nc.motion.sample_rows import few_rows
from nc.motion.share_zones import ShareZones
from nc.motion.shares import MAX_FACTOR, jerk_factor
from nc.motion.smoothing import PositionFilter
from nc.motion import threading as thr
from nc.moves import Move

# blocks a run through every lower cap takes at most (decision motion 83: its end then the junction there at its end
# speed; the fitted spans' chains the sweep found take 4-5; unbounded, the walk cost 1 % of the CAM instructions)
THROUGH = 16
OPEN_CHUNK = 4  # cycles sampled at a time (CHUNK otherwise) while the queue cannot tell the jerk factor yet (the channel reads 4 blocks a cycle)
MAX_SOLVES_PER_CYCLE = 1000  # plans one cycle may start and end before a sample is due (decisions B4)


def feed_rpm(measured: float, command: float) -> tuple[float, bool]:
    """Spindle speed for feed per revolution: the measured one, or the command once the measurement
    is within 0.1 % of it (then noise cannot re-trigger planning). Second value: settled."""
    rpm, cmd = abs(measured), abs(command)
    if cmd > 0.0 and abs(rpm - cmd) <= 1e-3 * cmd:
        return cmd, True
    return rpm, False


def replans(p: _Plan, rpm: float, settled: bool) -> bool:
    """Does a feed-per-revolution plan made at p.rpm re-plan at this spindle speed? 2 % hides measurement
    noise; a spindle that reaches its command re-plans once more, so a feed planned during the run-up does not
    stay up to 2 % low (E-N11); only once: under G96 the command moves every cycle (motion decisions 30).
    (A stretch asks it for each of its cycles, hil/stretch.py.)"""
    return not (abs(rpm - p.rpm) <= 0.02 * max(p.rpm, 1.0) and (not settled or p.settled))


def _near_floats(a: list, b: list) -> bool:
    """`plan_state._near` on two points' floats: every |x - y| <= 1e-6 + 1e-5·|y| (a C loop where compiled, planner.pxd;
    session 31, decision bench B186)."""
    for k in range(min(len(a), len(b))):
        x = a[k]
        y = b[k]
        if not abs(x - y) <= 1e-6 + 1e-5 * abs(y):
            return False
    return True


def _factor_span(planner: "Planner", lim: Limits, b: Block, s: float, dist: float) -> tuple[float, bool]:
    """Planner._factor_over's work, a C function where compiled (planner.pxd; session 29, decision bench B164): each
    of the planner's fields read once (a generic attribute read from compiled code, ~230 instructions), the share
    zones and jerk_factor called in C."""
    blend = lim.blend
    if blend is None:
        return 1.0, False
    start = b.s_end - b.length
    zones = planner._zones
    if zones is not None:
        span = blend.span_max
        if zones.near(start + s - span, start + dist + span):
            return 1.0, False  # λ < 1 there: the raw path keeps the tangential share (decision motion 45)
    return jerk_factor(planner.cfg, blend, planner.blocks, start + s, start + dist, planner.closed)


# Planner._run_target's work, called in C from `_plan_path` and `_jerk_factor` (session 31, decision bench B204): the
# Python-visible call, `self.lookahead()` (its body spelt out) and the loop's test on a Python int k_max were ≈ 0.8k a
# block. (k_max stays a Python int: absurd limits give a look-ahead depth beyond a C integer, test_harden_budgets;
# the loop compares k with it clamped to 2**62, a depth no deque reaches.)
KMAX_C = 2 ** 62


def _target_run(self: "Planner", cap: float, extend: bool, cruise_from: float, jf: float, through: float,
                limit: int) -> tuple[float, float, float, float, float]:
    if self._pushed:  # self.lookahead(), spelt out
        backward(self.blocks, 0, False, self._need)
        self._pushed = self._need = 0
    it = iter(self.blocks)  # the queue walked in order (a deque indexes in O(k)); b is blocks[k], nx blocks[k + 1]
    b = next(it)
    dist, ra, rj = b.length, b.a, b.j
    vmax = cap
    cap_lo = cap - 1e-9
    k_max = limit if limit else 2 * self.depth
    kmax = k_max if k_max < KMAX_C else KMAX_C  # min(k_max, 2**62): k never gets there
    for k, nx in enumerate(it):
        if nx.kind != "path" or nx.cap < cap_lo or b.vend <= 0.0 or k >= kmax \
                or (b.vend >= vmax - 1e-9 and dist >= cruise_from):
            # (asked here, once a call: the loop's own test stays as it was for every other solve)
            if not (through <= nx.cap < cap_lo and nx.kind == "path" and b.vend > 0.0 and k < kmax
                    and not (b.vend >= vmax - 1e-9 and dist >= cruise_from)):
                self._end_cap = nx.cap if nx.kind == "path" else -1.0
                return dist, vmax if vmax < b.vend else b.vend, ra, rj * jf, vmax  # min(b.vend, vmax)
            if nx.cap < vmax:  # a lower cap `through` goes on past: it holds the whole run (motion 77)
                vmax = nx.cap
        if b.vjunc < cap_lo:
            if b.binding and self._unbound(b, nx, dist, ra, rj * jf):
                # Not reachable faster than it allows from the present state (a rising
                # chain of caps behind a corner): it cannot bind, and a profile that ended
                # there at zero acceleration would only lose time.
                pass
            elif not extend or b.binding:
                return dist, vmax if vmax < b.vend else b.vend, ra, rj * jf, vmax  # min(b.vend, vmax)
            else:
                if b.vjunc < vmax:  # min(vmax, b.vjunc)
                    vmax = b.vjunc
        dist += nx.length
        x = nx.a  # ra = min(ra, nx.a) and rj = min(rj, nx.j), spelt out
        if x < ra:
            ra = x
        x = nx.j
        if x < rj:
            rj = x
        b = nx
    self._end_cap = -1.0
    return dist, vmax if vmax < b.vend else b.vend, ra, rj * jf, vmax  # b is the queue's last block


def _cap_of(self: "Planner", b: Block, rpm: float | None) -> float:
    """Planner._update_cap's work, a C function where compiled (planner.pxd; session 31, decision bench B181): the
    push calls it once a block, and a Python method call from compiled code was ≈ 320 instructions of its ≈ 500."""
    if b.kind != "path" and b.kind != "thread":
        b.cap = 0.0
        return 0.0
    # min(cap, x) spelt out `x if x < cap else cap` (min keeps the first of equal ones; ~3 a push, session 15)
    cap = b.cap_hard
    if b.rapid:
        if self._rapid_ovr > 0.0:
            cap = cap * self._rapid_ovr
        else:
            x = self.cfg.slow_rapid
            cap = x if x < cap else cap
    elif self.dry_run:
        x = self.dry_run_feed * self._feed_ovr
        cap = x if x < cap else cap
    else:
        feed = b.feed or 0.0
        if b.move.per_rev:
            feed *= abs(rpm if rpm is not None else self.spindle_rpm()) / 60.0
        x = feed * self._feed_ovr
        cap = x if x < cap else cap
    x = b.vtop
    if x > 0.0 and x < cap:
        cap = x  # the filter windows were sized with it (dry run switched on later)
    b.cap = cap
    return cap


class Planner(PlanCore, CruiseSampling, CornerShares, ThreadStepping, FilterStops, FittedRuns):
    # (PlanCore first: where compiled an extension type holding the hot fields in C, nc.motion.plan_core; its
    # state()/restore() save and restore every field, bench B172)
    # True: every block of a run starts a new solve, also where the run cruises at its cap (the reference
    # tests compare the cruise sampling against, decision motion 44)
    per_block = False

    def __init__(self, cfg: MotionConfig, start: dict[str, float] | None = None,
                 spindle_rpm: Callable[[], float] | None = None,
                 spindle_angle: Callable[[], float] | None = None,
                 spindle_index: Callable[[], float] | None = None,
                 spindle_command: Callable[[], float] | None = None) -> None:
        self.cfg = cfg
        self.axes = cfg.axes
        self.lim = Limits(cfg)
        self.position = np.array([(start or {}).get(a, 0.0) for a in self.axes], dtype=float)
        self.blocks: deque[Block] = deque()
        self.threads_queued = 0  # thread blocks in `blocks`: Channel.threading asks every cycle (issue 17)
        self.spindle_rpm = spindle_rpm or (lambda: 0.0)
        # Spindle actual angle (cumulative degrees) and the angle of one index pulse; without a
        # spindle_angle source an ideal spindle at spindle_rpm() is integrated (offline runs).
        self._sim_angle = 0.0
        self.spindle_angle = spindle_angle or (lambda: self._sim_angle)
        self._integrate_angle = spindle_angle is None
        self.spindle_index = spindle_index or (lambda: 0.0)
        # The commanded spindle speed (the MLC's): a feed-per-rev move whose spindle is commanded to turn
        # but still stands (M03 just issued) waits for it instead of alarming. None: measured = commanded.
        self.spindle_command = spindle_command
        self._thread: thr.ThreadState | None = None
        self.thread_log: list[tuple[int, float, float]] = []  # (line, sync angle, ramp start angle) per chain
        # A chain arms once the measured speed has settled at the command (decisions 33); while it
        # waits the axes stand and spindle_wait is True. thread_waits: (line, cycles waited) per chain.
        self._settle = thr.SpindleSettle()
        self.spindle_wait = False
        self._wait_cycles = 0
        self.thread_waits: list[tuple[int, int]] = []
        self.depth = cfg.lookahead_depth()
        # The queue refills in batches: once `full` it takes more blocks only when it has fallen
        # below depth (never shallower than configured), up to depth + batch. One backward pass
        # then serves the whole batch instead of one per block; the batch stays small (8 blocks
        # at the default depth) so a refill costs a fraction of a 1 ms cycle, not a spike.
        self._batch = self.depth // 12
        self._filling = True
        # Backward pass owed (run lazily before a plan reads end speeds): pushes since the last
        # pass, and how many blocks from the tail it must recompute at least.
        self._pushed = 0
        self._need = 0
        self.line = 0
        # operator controls
        self._feed_ovr = 1.0
        self._rapid_ovr = 1.0
        self.dry_run = False
        self.dry_run_feed = 5000.0 / 60.0  # mm/s
        self.held = False  # feed hold active (or reached)
        self._stopping = False  # reset: flush once at rest
        # execution state: path position in blocks[0], speed, acceleration
        self.s = 0.0
        self.v = 0.0
        self.a = 0.0
        self._axis_v = np.zeros(len(self.axes))  # independent rapids keep per-axis state
        self._axis_a = np.zeros(len(self.axes))
        self.plan: _Plan | None = None
        self._started = False  # blocks[0] has begun executing
        self._carry = cfg.cycle  # plan time of the first sample of the next plan
        self._buf_pos: np.ndarray | None = None
        self._buf_vel: np.ndarray | None = None
        self._buf_line: list[int] = []
        self._buf_i = 0
        self._buf_state: list[tuple[float, float, float]] = []
        # A cruise's buffer spans blocks: per row the offset of its block from blocks[0] when sampled (None:
        # every row in blocks[0]), and how many of those blocks the rows handed out so far finished.
        self._buf_blk: list[int] | None = None
        self._buf_popped = 0
        self._buf_carry: list[float] = []
        self.solves = 0  # ruckig solves so far (one per block plus one per event)
        # Post-interpolation filter (N1.036/N1.037); None when both times are zero.
        self.filter: PositionFilter | None = None
        if cfg.filtered:
            self.filter = PositionFilter(*cfg.filter_cycles(), self.position)
        self._path_s = 0.0  # path length pushed so far (junction windows are measured on it)
        # Half the least tangential acceleration and jerk of any line: the braking `_may_blend` allows for.
        # Under the filter, where its share λ gives way to blends (nc.motion.share_zones); None without
        # the filter, or where λ cannot act (PositionFilter.lag).
        self._zones: ShareZones | None = None
        if self.filter is not None and self.filter.lag is not None and (cfg.path_tolerance or 0.0) > 0.0:
            self._zones = ShareZones(cfg.filter_time + cfg.filter_scurve)
        self._share_s = 0.0
        self._lam = 1.0
        self._a_lo = 0.5 * self.lim.line_a_lo  # N1.034/N1.035 lower them (decision motion 94)
        self._j_lo = 0.5 * self.lim.line_j_lo
        # The channel sets `closed` when no move comes before the queue has run out to rest (program
        # end, an M/S/T or preview barrier); a push clears it. _jf: tangential jerk factor of the
        # last path solve (nc.motion.shares).
        self.closed = False
        self._jf = 1.0
        self._end_cap = -1.0  # the cap of the block that ended the last `_run_target` run (-1: none, not a path)
        # The path plan a block boundary just ended (to re-solve in the next block) and the path length since its
        # blocks[0] start: kept where that re-solve misses (`_kept`, decision motion 85); None once a plan started
        self._cont: tuple[_Plan, float] | None = None
        # an acceleration step a·Δu at a corner under the filter has the jerk of a velocity step a·T·Δu, T the
        # shorter window (`_unbound`, decisions motion 84, 86)
        self._t_step = min(cfg.filter_cycles()) * cfg.cycle if self.filter is not None else 0.0
        self._pushes = 0  # moves pushed so far (an open plan re-solves when more came)
        self.output = self.position.copy()  # the last setpoint handed out (filtered)
        self._init_filter_stops()
        self._init_runs()

    # ---- queue ----------------------------------------------------------------------------
    @cython.locals(self=PlanCore)
    def push(self, move: Move) -> None:
        self._closed = False  # the `closed` setter's whole work for False (once per push)
        if self._runs is not None:  # runs of short lines are held back and fitted (nc.motion.spline_feed)
            self._feed_run(move)
        else:
            self._push(move)

    @cython.locals(self=PlanCore, b=Block, prev=Block, x=cython.double, added=cython.Py_ssize_t, need=cython.Py_ssize_t,
                   w=cython.Py_ssize_t, pushed=cython.Py_ssize_t, lim=Limits, zones=ShareZones, ln=Segment,
                   cut_line=cython.bint)
    def _push(self, move: Move, span: Segment | None = None, line: Segment | None = None) -> None:
        self._pushes += 1
        lim = self.lim
        cut_line = line is not None
        if cut_line:  # the run feed's line (RunFeed._line: a G01 at a feed, not per revolution, longer than 1e-6
            # mm): its block here, without `_block`'s tests of the move (session 29, decision bench B166)
            ln = line
            v, a, j = lim.block_limits(ln, False, CUT)
            b = new_block(move, "path", ln, ln.length, v, a, j, move.feed / 60.0, False)
        elif span is not None:
            b = self._span_block(move, span)
        else:  # one argument: benchmarks/bench_spline_bound.py patches _block(self, move)
            b = self._block(move)
        if b is None:
            return
        # The limits' junction, the corner and the share zones are C calls where compiled, on locals read once
        # (session 28, decision bench B157)
        blocks = self.blocks
        blend = lim.blend
        if blend is not None:
            b.vtop = b.cap_hard
            if cut_line or (b.kind == "path" and not b.rapid and not b.move.per_rev):
                x = 1.5 * (self.dry_run_feed if self.dry_run else (b.feed or 0.0))
                if x < b.cap_hard:  # min(cap_hard, x), spelt out (once per push)
                    b.vtop = x
        _cap_of(self, b, None)  # `_update_cap`'s work as a C call where compiled (bench B181)
        added = 1
        if blocks:
            prev = blocks[-1]
            prev.vjunc = lim.junction(prev, b)
            added += _corner_at(self, prev, b)
        x = self._path_s + b.length  # after the corner: a blend gave path (it set _path_s)
        self._path_s = x
        b.s_end = x
        zones = self._zones
        if zones is not None:
            zones.block(b.s_end - b.length, b.vtop)
        if cut_line:
            b.scan_plain = True
        else:
            seg = b.seg
            b.scan_plain = b.kind == "path" and seg is not None and seg.kind != "arc"
        blocks.append(b)
        if b.kind == "thread":  # `threads_queued += kind == "thread"`, read and written only where it changes
            self.threads_queued += 1
        # Blocks pushed since the last pass never had one: the pass must reach past all of them.
        pushed = self._pushed + added
        self._pushed = pushed
        need = self._need + added  # max() spelt out here and below
        if pushed > need:
            need = pushed
        if blend is not None:
            w = blend.window(blocks)
            if w > need:
                need = w
        self._need = need

    @cython.locals(self=PlanCore)
    def lookahead(self) -> None:
        """Bring the queue's end speeds up to date (the backward pass the pushes owe)."""
        if self._pushed:
            backward(self.blocks, 0, False, self._need)  # a C call where compiled (lookahead.pxd, bench B181)
            self._pushed = self._need = 0

    @property
    def queue(self) -> deque[Block]:
        return self.blocks

    @property
    def active(self) -> Block | None:
        return self.blocks[0] if self._started and self.blocks else None

    @property
    @cython.locals(self=PlanCore)
    def full(self) -> bool:
        n = len(self.blocks)
        if n >= self.depth + self._batch:
            self._filling = False
        elif n < self.depth:
            self._filling = True
        return not self._filling

    @property
    def idle(self) -> bool:
        return not self.blocks and self.plan is None and self._buf_done and self._settled and not self._held.moves

    @property
    def halted(self) -> bool:
        """Held (feed hold / stop) and standing still, with the queue kept."""
        return self.held and self.plan is None and self._buf_done and self.at_rest and self._settled

    @property
    @cython.locals(self=PlanCore)
    def _settled(self) -> bool:
        return self.filter is None or self.filter.settled

    @property
    @cython.locals(self=PlanCore)
    def at_rest(self) -> bool:
        return abs(self.v) < 1e-9 and not np.any(self._axis_v)

    @property
    @cython.locals(self=PlanCore)
    def _buf_done(self) -> bool:
        return self._buf_pos is None or self._buf_i >= len(self._buf_pos)

    def reset_position(self, pos: dict[str, float]) -> None:
        """Take over the actual position (after enable, or after a stop)."""
        self.position = np.array([pos.get(a, 0.0) for a in self.axes], dtype=float)
        self.output = self.position.copy()
        if self.filter is not None:
            self.filter.reset(self.position)

    # ---- operator controls ----------------------------------------------------------------
    @property
    def feed_override(self) -> float:
        return self._feed_ovr

    @feed_override.setter
    def feed_override(self, value: float) -> None:
        value = min(max(float(value), 0.0), 1.5)
        if value != self._feed_ovr:
            self._feed_ovr = value
            self._limits_changed()

    @property
    def rapid_override(self) -> float:
        return self._rapid_ovr

    @rapid_override.setter
    def rapid_override(self, value: float) -> None:
        value = min(max(float(value), 0.0), 1.0)
        if value != self._rapid_ovr:
            self._rapid_ovr = value
            self._limits_changed()

    def set_dry_run(self, on: bool, feed_mm_min: float | None = None) -> None:
        self.dry_run = bool(on)
        if feed_mm_min:
            self.dry_run_feed = feed_mm_min / 60.0
        self._limits_changed()

    def hold(self) -> None:
        """Feed hold: jerk-limited stop along the path (across blocks if need be); keeps the queue."""
        if self.held:
            return
        self.release_run()  # what a run holds back joins the queue (an interrupt re-reads the queue)
        self.held = True
        self._replan()

    def resume(self) -> None:
        if self.held and not self._stopping:
            self.held = False
            self._replan()

    def end_dwell(self) -> None:
        """Held: a dwell in progress ends now instead of running out (the M96 interrupt; the
        dwell's block stays queued, so it can run again whole)."""
        if self.held and self.plan is not None and self.plan.kind == "dwell":
            self.plan, self._buf_pos, self._buf_i = None, None, 0

    def stop(self) -> None:
        """Reset: controlled stop along the path, then flush the queue once at rest."""
        self._stopping = True
        self.held = True
        self.end_dwell()  # the axes stand in a dwell: nothing to brake, the stop is at once (decision M24-1)
        self._replan()
        if self.at_rest and self.plan is None:
            self._flush()

    def abort(self) -> None:
        """E-stop: forget every plan this cycle; the setpoint freezes where it is."""
        self._flush()
        # The drives were given the filtered setpoint: freeze there, not at the filter's input.
        self.position = self.output.copy()
        if self.filter is not None:
            self.filter.reset(self.position)
        self.v = self.a = 0.0
        self._axis_v[:] = 0.0
        self._axis_a[:] = 0.0

    # ---- per cycle ------------------------------------------------------------------------
    @cython.locals(self=PlanCore)
    def step(self) -> Setpoint:
        f = self.filter
        if f is None:
            sp = self._step_path()
            self.output = sp.positions
            return sp
        if f.settled and not self.blocks and self.plan is None and self._buf_done \
                and not np.array_equal(self.position, f.output):
            f.reset(self.position)  # the position was taken over at rest (manual modes, homing)
        sp = self._step_path()
        mv = sp.move
        if mv is not None and (mv.kind == "thread" or "G31" in mv.tags):
            # Spindle-locked threads and skip moves follow the raw interpolation: their timing is
            # the point (phase, stop within one cycle). They start and end at rest with the
            # filter settled, so passing it by keeps the stream continuous.
            f.reset(sp.positions)
        else:
            sp.positions = f.push(sp.positions, self._share() if self._zones is not None else 1.0)
        self.output = sp.positions
        return sp

    @cython.locals(self=PlanCore)
    def _step_path(self) -> Setpoint:
        if self._integrate_angle:
            self._sim_angle += self.spindle_rpm() * 6.0 * self.cfg.cycle
        self._check_spindle()
        if self.spindle_command is not None:
            self._settle.update(float(self.spindle_rpm()), float(self.spindle_command()))
        self._before_take()
        pos = self._buf_pos
        i = self._buf_i
        done = pos is None or i >= len(pos)  # `_buf_done`, read once
        if done and self.plan is None and self.blocks and self.blocks[0].kind == "thread" \
                and (self._thread is not None or self._settled):
            return self._thread_step()
        if done:  # standing still (idle, held, or waiting)
            self.v = self.a = 0.0
            blk = self.blocks[0].move if self._started and self.blocks else None
            return Setpoint(self.position.copy(), self.line, 0.0, blk)
        self._buf_i = i + 1
        self._take(i)
        blk = self.blocks[0].move if self.blocks else None
        return Setpoint(self.position.copy(), self.line, float(self._buf_vel[i]), blk)

    # ---- planning -------------------------------------------------------------------------
    @cython.locals(lim=Limits, what=cython.Py_ssize_t)
    def _block(self, move: Move, seg: Segment | None = None) -> Block | None:
        """The move's block; `seg`: its line segment when the run feed built it already."""
        kind = move.kind  # read once (a Move's field: an attribute lookup each, session 28)
        if kind == "dwell":
            return Block(move, "dwell", None, 0.0, 0.0, 1.0, 1.0, None)
        if seg is None:
            seg = Segment.of(move, self.axes)
        if seg.length < 1e-9:
            return None
        if kind == "rapid" and self.cfg.rapid_independent:
            return Block(move, "indep", seg, seg.length, 0.0, 1.0, 1.0, None, rapid=True)
        # G00 and cutting moves each under their own NC5 parameters (decision motion 90); a C call where compiled
        lim = self.lim
        what = RAPID if kind == "rapid" else THREAD if kind == "thread" else CUT
        v, a, j = lim.block_limits(seg, False, what)
        feed = None if kind == "rapid" else (move.feed or 0.0) / (1.0 if move.per_rev else 60.0)
        return Block(move, "thread" if kind == "thread" else "path", seg, seg.length, v, a, j, feed,
                     kind == "rapid")  # the 9th field: rapid

    def _update_cap(self, b: Block, rpm: float | None = None) -> float:
        """Block b's speed cap (b.cap) from its feed, the overrides and dry run; `rpm`: the spindle speed feed per
        revolution uses (None: the measured one)."""
        return _cap_of(self, b, rpm)

    def _limits_changed(self) -> None:
        for b in self.blocks:
            self._update_cap(b)
        if self.lim.blend is not None:
            self.lim.blend.touch()  # the caps nc.motion.shares' kept verdicts were found with
        backward(self.blocks, 0, full=True)
        self._pushed = self._need = 0
        self._replan()

    @cython.locals(self=PlanCore)
    def _replan(self) -> None:
        """Drop the sampled-ahead cycles and plan again from the last emitted state."""
        if self.plan is None and self._buf_done:
            return
        if self.plan is not None and self.plan.kind == "dwell":
            return  # a dwell holds position anyway; the next plan sees the new settings
        if self._deferred():
            return  # a filter stop or start runs as checked (nc.motion.filter_ramps); then the new settings
        self._buf_pos = None
        self._buf_i = 0
        self.plan = None
        self._cont = None
        self._carry = self.cfg.cycle

    @cython.locals(self=PlanCore)
    def per_rev_plan(self) -> _Plan | None:
        """The running plan when it is a feed-per-revolution path, which each step checks against the measured
        spindle speed (`_check_spindle`); None otherwise."""
        p = self.plan
        if p is None or p.kind != "path" or not self.blocks or not self.blocks[0].move.per_rev:
            return None
        return p

    @cython.locals(self=PlanCore)
    def _check_spindle(self) -> None:
        p = self.per_rev_plan()
        if p is None:
            return
        rpm, settled = self._feed_rpm()
        if not replans(p, rpm, settled):
            return
        self._update_cap(self.blocks[0], rpm)
        self._replan()

    def _feed_rpm(self) -> tuple[float, bool]:
        return feed_rpm(self.spindle_rpm(), self.spindle_command() if self.spindle_command is not None else 0.0)

    def _flush(self) -> None:
        self._thread = None
        self._held = NOTHING
        self.spindle_wait = False
        self._wait_cycles = 0
        self.blocks.clear()
        self.threads_queued = 0
        self._pushed = self._need = 0
        self.plan = None
        self._buf_pos = None
        self._started = False
        self._stopping = False
        self.held = False
        self.s = self.v = self.a = 0.0

    # (n stays a Python int: absurd limits give a duration of more cycles than a C integer holds)
    @cython.locals(self=PlanCore, T=cython.double, t_next=cython.double, duration=cython.double)
    def _refill(self) -> None:
        # (`_buf_done` spelt out after a sample: what it read is the rows just sampled, issue 17)
        T = self.cfg.cycle
        for _ in range(MAX_SOLVES_PER_CYCLE):
            p = self.plan
            if p is None:
                # `not self._settled and self.at_rest`, the two properties spelt out (Python calls compiled, bench B204)
                f = self.filter
                if f is not None and not f.settled and abs(self.v) < 1e-9 and not np.any(self._axis_v):
                    return  # exact stop: the filtered setpoint reaches the point before anything starts
                p = self._start_plan()
                self.plan = p
                self._cont = None
                if p is None:
                    return
            if p.kind == "cruise":
                if not p.emitted:
                    self._sample_cruise(p)
                    if self._buf_i < len(self._buf_pos):  # (a cruise samples at least a row: never None)
                        return
                self._end_plan(p)
                continue
            if p.open and p.emitted and self._pushes > p.queued and not self.held:
                self._replan()  # more of the path is known: the jerk factor may rise
                continue
            t_next, duration = p.t_next, p.duration
            n = int(math.floor((duration - t_next) / T + 1e-9)) + 1
            if t_next <= duration + 1e-12 and n > 0:
                c = OPEN_CHUNK if p.open else CHUNK
                self._sample(p, c if c < n else n)  # min(n, c)
                pos = self._buf_pos
                if pos is not None and self._buf_i < len(pos):
                    return
                if self.plan is None:
                    continue  # re-solve at a block boundary
            self._end_plan(p)
        self._no_progress()

    def _no_progress(self) -> None:
        """Every solve of this cycle ended before its first sample: with absurd limits (acceleration
        1e-50, jerk 1e200) planning would spin here cycle after cycle, each taking most of a second
        of wall clock, and never reach the bench's max_time. Alarm instead (decisions B4)."""
        self.plan = None
        b = self.blocks[0] if self.blocks else None
        mv = b.move if b is not None else None
        limits = f" (acceleration {b.a:g}, jerk {b.j:g})" if b is not None else ""
        raise NcAlarm(PLANNING_STALL, f"motion planning made no progress in {MAX_SOLVES_PER_CYCLE} solves in one cycle"
                      f"{limits}: check the axis limits",
                      line=mv.line if mv else None, block=mv.block if mv else None,
                      program=mv.program if mv else None)

    @cython.locals(self=PlanCore, b=Block)
    def _start_plan(self) -> _Plan | None:
        """Plan from the current state; None when there is nothing to do (idle or held at rest)."""
        T = self.cfg.cycle
        t0 = self._carry
        self._carry = T
        while self.blocks:
            b = self.blocks[0]
            if not self._started:
                self._started = True
                self.s = 0.0
                self.line = b.move.line
                seg = b.seg
                # `_near(seg.start, position)` on the floats the segment keeps (no array made from them to compare)
                if seg is not None and _near_floats(seg.start_floats, self.position.tolist()):
                    seg.start = self.position.copy()
            if b.kind == "dwell":
                if self.held:
                    return None
                return _Plan("dwell", None, float(b.move.duration or 0.0), t0)
            if b.kind == "indep":
                return self._plan_indep(b, t0)
            if b.kind == "thread":
                return None  # spindle-locked: stepped cycle by cycle (_thread_step)
            if self.s >= b.length - 1e-9 and len(self.blocks) > 1 and self.blocks[1].kind == "path":
                self.s -= b.length
                self._finish_block(keep_plan=True)
                continue
            if self.s >= b.length - 1e-12 and abs(self.v) < 1e-9:
                self._finish_block()
                continue
            # `not self._deferred()` spelt out (its fields are C fields where compiled; a Python call of filter_ramps)
            if not self.per_block and not ((self._fs_tail is not None and self._fs_tail is self.blocks[-1])
                                           or (self._fr_plan is not None and self._fr_plan is self.plan)):
                cruise = self._cruise(b, t0)
                if cruise is not None:
                    return cruise
            return self._plan_path(b, t0)
        if self._stopping:
            self._flush()
        self._started = False
        return None

    def _spindle_starting(self) -> bool:
        return self.spindle_command is not None and abs(self.spindle_command()) > 0.0

    @cython.locals(self=PlanCore)
    def _plan_path(self, b: Block, t0: float) -> _Plan | None:
        s, v, a = self.s, self.v, self.a
        rpm, settled = self._feed_rpm() if b.move.per_rev else (0.0, False)
        cap = self._update_cap(b, rpm if b.move.per_rev else None)
        if b.move.per_rev and rpm <= 0.0 and not self.dry_run and not self._spindle_starting():
            raise NcAlarm(0x1001, "feed per revolution with the spindle stopped (S0)", line=b.move.line,
                          block=b.move.block, program=b.move.program)
        self.solves += 1
        # (the reference mode solves what a cruise samples: a cruise comes before any filter ramp, _start_plan)
        cruises = self.per_block and not self._deferred() and self._cruise(b, t0) is not None
        # `_filter_ramp` (Python) is not called where its answer is None at its first tests, without a side effect: no
        # filter stop runs, and neither a start (at a nonzero acceleration or at the cap) nor a stop (an open queue)
        # can be taken. (Its look-ahead pass then runs in `_run_target`, before anything reads a junction speed: the
        # same queue, the same speeds.) 1,579 calls on the CAM program, ~1,300 of them asked here (bench B168)
        if self.filter is not None and not cruises and not (
                self._fs_tail is None and (self.held or cap <= 1e-9 or (
                    (abs(a) >= 1e-12 or (v if v > 0.0 else 0.0) >= cap * (1.0 - 1e-9)) and not self.closed))) \
                and (fr := self._filter_ramp(b, s, v, a, cap, t0)) is not None:
            return fr
        if self.held or cap <= 1e-9:
            if abs(v) < 1e-9 and abs(a) < 1e-9:
                if self._stopping:
                    self._flush()
                return None  # at rest: wait for resume / override
            pw = solve_velocity(s, v, a, 0.0, b.a, b.j)
            if pw.v_min() < -1e-7 or crosses_too_fast(pw, s, self.blocks):
                # the stop would back up along the path (braking hard at low speed: a²/2j > v) or cross a junction
                # faster than it allows (a corner, the queue's end): it cannot stop sooner, so the plan's own
                # profile to that junction goes on (within the limits, no reversal) and the stop follows from
                # there (motion 63)
                # the running plan's jerk
                dist, v1, ra, rj, vmax = _target_run(self, max(cap, v, 1e-9), False, math.inf, self._jf, math.inf, 0)
                to = solve_position(s, v, a, dist, v1, vmax, ra, rj)
                if to is not None and to.p_max <= dist + 1e-7 and to.v_min() >= -1e-7:
                    return _Plan("path", to, to.duration, t0, target=dist, queued=self._pushes)
            return _Plan("ramp", pw, pw.duration, t0, 0.0, 0.0)
        # The run: following blocks the profile may cross without a binding junction (same or
        # higher cap, end speed not below the cap); the target is the end of that run.
        cruise = s + change_distance(v, cap, b.a, b.j)
        jf, unknown = self._jerk_factor(b, s, cap, cruise)
        # A profile continued at nonzero acceleration was solved with the previous factor: when
        # the new one cannot meet its target from that state, the previous one still can.
        for f in (jf, self._jf) if self._jf > jf and abs(a) > 1e-9 else (jf,):
            for extend in (0, 1, 2):
                check = None
                if extend < 2:
                    dist, v1, ra, rj, vmax = _target_run(self, cap, extend == 1, cruise, f, math.inf, 0)
                else:  # neither met: on through lower caps the braking state does not reach (motion 77)
                    # (with this solve's own factor only: a cruise leaves self._jf as it was, decision 44)
                    # (only where the extended run ended at such a cap: 12 of 211 that got here in 3000 CAM blocks)
                    x = self._end_cap
                    run = self._run_through(b, s, v, cap, cruise, f, v if v <= x else 0.0) \
                        if a <= 0.0 and f == jf and x < cap - 1e-9 else None
                    if run is None or run[0] <= dist:
                        break  # not braking, or no such cap ahead: the same run
                    if run[4] < v:  # a state above the lower caps (motion 83): it brakes below each before it
                        # gets there, or the solve is not taken (`brakes_below`, after it) and the fallback
                        # ramp below is the extended run's, as before
                        check = (dist, v1, ra, rj, vmax)
                        run = run[:4] + (v,)
                    dist, v1, ra, rj, vmax = run
                # Forward pass: no more than the entry state can reach (a braking state first ramps
                # its deceleration out, losing a²/2j of speed over v·|a|/j of path).
                ve, de = (v - a * a / (2.0 * rj), dist - s - v * abs(a) / rj) if a < 0.0 else (v, dist - s)
                # min(v1, reach(max(ve, 0.0), max(de, 0.0), …)) spelt out (session 15)
                x = reach(0.0 if 0.0 > ve else ve, 0.0 if 0.0 > de else de, MARGIN * ra, MARGIN * rj)
                if x < v1:
                    v1 = x
                pw = solve_position(s, v, a, dist, v1, vmax, ra, rj)
                if check is not None and (pw is None or pw.p_max > dist + 1e-7 or pw.v_min() < -1e-7
                                          or not brakes_below(pw, s, dist, self.blocks)):
                    pw = None
                    dist, v1, ra, rj, vmax = check
                if pw is not None and pw.p_max <= dist + 1e-7 and pw.v_min() >= -1e-7:
                    break
            if pw is not None and pw.p_max <= dist + 1e-7 and pw.v_min() >= -1e-7:
                self._jf = f
                break
        if (pw is None or pw.p_max > dist + 1e-7 or pw.v_min() < -1e-7) and self._cont is not None \
                and (kept := self._kept(s, v, a, t0)) is not None:
            return kept
        if pw is None or pw.p_max > dist + 1e-7 or pw.v_min() < -1e-7:
            # Cannot meet the target from this state (an override just cut the cap): ramp down
            # to the cap first, then plan the rest from there. Within the run's least acceleration:
            # the ramp runs on into the run's next blocks, whose solves start from the state it
            # leaves there (with the block's own, higher one it left a block at 3x that block's
            # acceleration limit, decision motion 77).
            target = min(cap, max(v1, 0.0))
            pw = solve_velocity(s, v, a, target, ra if ra < b.a else b.a, b.j)
            if target > 1e-9:
                # after the ramp, cruise at the target speed to the end of the run, not past it (decision motion 83)
                x = pw.at(pw.duration)[0]
                if x < dist:
                    pw.duration += (dist - x) / target
                pw.t0[:, -1] = np.minimum(pw.t0[:, -1], pw.duration)
                pw._lists = None  # `at` reads the changed arrays
            return _Plan("ramp", pw, pw.duration, t0, 0.0, target)
        if self._jf < MAX_FACTOR and a >= 0.0 and v < cap * (1.0 - 1e-6) and vmax >= cap - 1e-9:
            ramp = self._speed_up(b, s, v, a, cap, cruise, dist, v1, ra, rj, t0)
            if ramp is not None:
                return ramp
        return _Plan("path", pw, pw.duration, t0, target=dist, rpm=rpm, settled=settled, open=unknown,
                     queued=self._pushes)

    @cython.locals(self=PlanCore, done=cython.double, base=cython.double, x=cython.double, t=cython.double,
                   ps=cython.double, pv=cython.double, pa=cython.double, end=cython.double)
    def _kept(self, s: float, v: float, a: float, t0: float) -> _Plan | None:
        """The profile the last path plan followed, on from the state it left at the block boundary where it was
        to be solved again, when that solve missed: ruckig, solving from a state on its own time-optimal profile
        (one cycle after the acceleration turned, as a braking run's), can miss the same target it met before
        (seed 360 of the motion sweep: p_max 0.6 µm past it, v down to −1.1 mm/s), and the fallback ramp then
        crossed a stop between two fitted runs at 0.55 mm/s (decisions motion 83 (c), 85). Kept only where the state lies
        on it and it still fits the queue: its end a junction whose end speed allows its own, no speed on the
        way above a cap or junction speed it crosses (`fits_queue`)."""
        p, done = self._cont
        pw = p.pw
        base = p.base + done  # the old profile's position of blocks[0]'s start
        x = s + base
        t = time_at(pw, x)  # the state's time on it
        ps, pv, pa = pw.at(t)
        if abs(ps - x) > 1e-9 or abs(pv - v) > 1e-6 * (1.0 + abs(v)) or abs(pa - a) > 1e-6 * (1.0 + abs(a)):
            return None
        end = p.target - done
        if not fits_queue(pw, t, end, self.blocks):
            return None
        pw = later(pw, t)  # its clock from the state on, as a solve's from its start state
        return _Plan("path", pw, pw.duration, t0, base, end, p.rpm, p.settled, queued=self._pushes)

    @cython.locals(self=PlanCore)
    def _speed_up(self, b: Block, s: float, v: float, a: float, cap: float, cruise: float, dist: float,
                  v1: float, ra: float, rj: float, t0: float) -> _Plan | None:
        """A run whose jerk stays low because of what lies near its end (decision motion 39) may
        still speed up to its cap with a higher jerk when nothing near the speed-up holds it: a
        ramp to the cap (ending at zero acceleration), after which the run is solved again. Only
        when the run cruises at the cap and has room left to brake from it with its own limits."""
        blend = self.lim.blend
        if blend is None:
            return None
        start = b.s_end - b.length
        if self._zones is not None and self._zones.near(start + s - blend.span_max, start + cruise + blend.span_max):
            return None
        if dist - cruise < change_distance(cap, v1, MARGIN * ra, MARGIN * rj):
            return None  # no cruise between the speed-up and the braking (asked first: no scan, session 12)
        f, unknown = jerk_factor(self.cfg, blend, self.blocks, start + s, start + cruise, self.closed)
        if unknown or f <= self._jf * (1.0 + 1e-9):
            return None
        pw = solve_velocity(s, v, a, cap, ra, rj / self._jf * f)
        end_s = float(pw.sample(np.array([pw.duration]))[0][0])
        if end_s > cruise + 1e-9:
            return None
        return _Plan("ramp", pw, pw.duration, t0, 0.0, cap)

    @cython.locals(self=PlanCore)
    def _run_through(self, b: Block, s: float, v: float, cap: float, cruise: float,
                     f: float, through: float) -> tuple[float, float, float, float, float] | None:
        """The extended run carried on through blocks whose cap is a little lower than b's (the cap of a
        chain of corner-blend pieces falls by 1e-4 mm/s a piece) but not below v, the speed of a state that
        is not speeding up: the ordinary runs end at each such junction, with zero acceleration at a speed
        the braking state cannot meet that soon, while the braking over the whole chain (the backward pass's
        end speeds) can be met (decision motion 77). Its jerk factor is f where f holds over the longer run.
        `through`: v, or 0 where the state is above the lower cap the extended run ended at (a span's cap after a
        long span, decision motion 83): then through every lower cap, the top speed the lowest of them, which
        the caller checks the solve against junction by junction instead, with the plain jerk (factor 1: always
        within the shares; the scan over the longer run cost 1 % of the CAM program's instructions, for 15 of 176
        such solves met there)."""
        dist, v1, ra, rj, vmax = _target_run(self, cap, True, cruise, 1.0, through, 0 if through > 0.0 else THROUGH)
        if through == 0.0 and v > max_speed_at(v1, 0.0, dist - s, ra, rj):
            return None  # no profile brakes from v to v1 there (time reversed, none reaches v): 56 of 176 in CAM
        if f > 1.0 and through > 0.0:  # (through every lower cap: the plain jerk, no scan; rarely met, motion 83)
            g, unknown = self._factor_over(b, s, dist)
            if unknown or g < f:
                f = 1.0 if unknown else g
        return dist, v1, ra, rj * f, vmax

    @cython.locals(self=PlanCore)
    def _jerk_factor(self, b: Block, s: float, cap: float, cruise: float) -> tuple[float, bool]:
        """The tangential jerk factor for a solve from s in b, and whether the queue could not
        tell it yet (nc.motion.shares): over the longest run any solve from here may take (the
        extended one: a higher jerk only ends runs sooner)."""
        lim = self.lim
        if lim.blend is None:
            return 1.0, False
        return _factor_span(self, lim, b, s, _target_run(self, cap, True, cruise, 1.0, math.inf, 0)[0])

    @cython.locals(self=PlanCore)
    def _factor_over(self, b: Block, s: float, dist: float) -> tuple[float, bool]:
        """`_jerk_factor` over a run from s in b to `dist` (measured from b's start)."""
        return _factor_span(self, self.lim, b, s, dist)

    def _run_target(self, cap: float, extend: bool = False, cruise_from: float = math.inf,
                    jf: float = 1.0, through: float = math.inf, limit: int = 0) -> tuple[float, float, float, float, float]:
        """(distance, end speed, acceleration, jerk, top speed) of the run that starts with blocks[0].

        A run ends at the first junction slower than the cap. With `extend` it carries on through
        junctions whose end speed is set downstream (not binding: a braking chain through short
        blocks, which cannot be met with zero acceleration at every junction), its top speed then
        held to the slowest of them so the profile crosses each at no more than it allows.
        A junction past `cruise_from` (where the cap is reached) that may be crossed at the cap
        ends the run too: the profile cruises there, so nothing beyond it changes this solve.
        `jf`: factor on the run's tangential jerk (nc.motion.shares). `through`: a block whose cap is lower
        than `cap` but not below `through` (the speed the present state reaches) does not end the run; the
        top speed drops to its cap instead (`_run_through`, decision motion 77).
        """
        return _target_run(self, cap, extend, cruise_from, jf, through, limit)  # a C call where compiled (bench B204)

    @cython.locals(self=PlanCore)
    def _unbound(self, b: Block, nx: Block, dist: float, ra: float, rj: float) -> bool:
        """The junction b → nx, `dist` from blocks[0]'s start, that no profile from the present state within ra
        and rj reaches faster than its end speed: it cannot bind the run (issue 18). Under the filter a tangent
        jump crossed accelerating steps each axis' acceleration by a·Δu as well as its velocity by v·Δu: through
        the two windows their jerk adds to (v + |a|·min(T1, T2))·Δu/(T1·T2) on the first (or last) T2, so the
        corner's own jerk budget (alone in its windows: budget_j over Δu per axis) must hold v + a·min(T1, T2) of
        the fastest profile from the state there, or the run ends at the junction at zero acceleration as at any
        binding one (decisions motion 84, 86: a resume from a feed hold a few µm before a sharp corner crossed it at
        ≈ 900 mm/s², jerk 1.11× the limit). (The step moves an axis' acceleration from a·u1 to a·u2, both within
        the tangential share: the acceleration budget is not charged.)"""
        blend = self.lim.blend
        if blend is None or b.du_n <= 1e-9 or self._t_step <= 0.0:
            return b.vend >= max_speed_at(self.v, self.a, dist - self.s, ra, rj)
        v, acc = fastest_state(self.v, self.a, dist - self.s, ra, rj)
        if b.vend < v:
            return False
        v += acc * self._t_step
        for d, bj in zip(b.du, blend.budget_jl if b.seg.kind == "line" and nx.seg.kind == "line" else blend.budget_j):
            if d * v > bj:
                return False
        return True

    def _plan_indep(self, b: Block, t0: float) -> _Plan | None:
        assert b.seg is not None
        lim = self.lim
        ovr = self._rapid_ovr
        vmax = lim.rv * ovr if ovr > 0 else np.minimum(lim.rv, self.cfg.slow_rapid)  # N2.020 (decision motion 90)
        self.solves += 1
        if self.held:
            if not np.any(np.abs(self._axis_v) > 1e-9):
                if self._stopping:
                    self._flush()
                return None
            pw = solve_axes(self.position, self._axis_v, self._axis_a, self.position, vmax, lim.racc, lim.rjerk,
                            velocity=True)
        else:
            pw = solve_axes(self.position, self._axis_v, self._axis_a, b.seg.end, vmax, lim.racc, lim.rjerk)
        return _Plan("indep", pw, pw.duration, t0)

    @cython.locals(self=PlanCore)
    def _sample(self, p: _Plan, n: int) -> None:
        T = self.cfg.cycle
        self._buf_blk = None
        if (p.kind == "path" or p.kind == "ramp") and few_rows(self, p, n):
            return  # the same rows on plain floats (nc.motion.sample_rows)
        t = p.t_next + T * np.arange(n)
        p.t_next = float(t[-1] + T)
        line = self.blocks[0].move.line if self.blocks else self.line
        if p.kind == "dwell":
            self._buf_pos = np.repeat(self.position[None, :], n, axis=0)
            self._buf_vel = np.zeros(n)
            self._buf_line = [line] * n
            self._buf_state = [(self.s, 0.0, 0.0)] * n
            self._buf_i = 0
            return
        if p.kind == "indep":
            cols = [p.pw.sample(t, k) for k in range(len(self.axes))]
            self._buf_pos = np.stack([c[0] for c in cols], axis=1)
            vel = np.stack([c[1] for c in cols], axis=1)
            self._axis_v = vel[-1].copy()
            self._axis_a = np.array([c[2][-1] for c in cols])
            self._buf_vel = np.linalg.norm(vel, axis=1)
            self._buf_line = [line] * n
            self._buf_state = [(0.0, 0.0, 0.0)] * n
            self._buf_i = 0
            return
        s, v, a = p.pw.sample(t)
        s = s - p.base
        blocks = self.blocks
        more = len(blocks) > 1 and blocks[1].kind == "path"
        if more and s[0] > blocks[0].length + 1e-12:
            # A ramp that catches up with the cap also re-solves at the boundary: it must not
            # carry its speed into blocks that need less (a hold's ramp to rest runs on).
            if p.kind == "path" or (p.kind == "ramp" and not self.held and p is not self._fr_plan):
                # The next sample lies in the next block: re-solve there from the last emitted
                # state (once per block), now that more of the queue may be known.
                length = blocks[0].length
                s_last = self.s
                self._finish_block(True)
                self.s = s_last - length
                self.plan = None
                # The state re-solved from is the last emitted sample (one cycle back) or, when
                # none of this plan went out yet, the plan's start (t[0] back).
                self._carry = T if p.emitted else float(t[0])
                self._buf_pos = None
                return
            # A ramp runs on into the next block without a new solve.
            while len(blocks) > 1 and blocks[1].kind == "path" and s[0] > blocks[0].length + 1e-12:
                p.base += blocks[0].length
                s = s - blocks[0].length
                self._finish_block(True)
            more = len(blocks) > 1 and blocks[1].kind == "path"
        if more:
            cut = int(np.searchsorted(s, blocks[0].length + 1e-12, side="right"))
            if 0 < cut < n:
                n = cut
                s, v, a = s[:n], v[:n], a[:n]
                p.t_next = float(t[n])
        b = blocks[0]
        line = b.move.line
        p.emitted = True
        self._buf_pos = b.seg.points(clip(s, 0.0, b.length))
        self._buf_vel = v
        self._buf_line = [line] * n
        self._buf_i = 0
        self._buf_state = list(zip(s.tolist(), v.tolist(), a.tolist()))

    @cython.locals(self=PlanCore)
    def _end_plan(self, p: _Plan) -> None:
        T = self.cfg.cycle
        if p.kind == "cruise":  # its last block ends here as that block's own path plan would end it
            self._break_chain(min(self._chain_ok(p, p.last), p.last + 1))
            return
        self._carry = p.t_next - p.duration
        if self._carry <= 1e-12:
            self._carry += T
        self.plan = None
        if p.kind == "path":
            # The run may end past blocks shorter than a cycle that no sample fell into.
            d = p.target
            while len(self.blocks) > 1 and d > self.blocks[0].length + 1e-9:
                d -= self.blocks[0].length
                self._finish_block(True)
            b = self.blocks[0]
            self.s, self.v, self.a = b.length, p.pw.v_end(), 0.0
            self.position = b.seg.end.copy() if b.seg is not None else self.position
            self._finish_block()
        elif p.kind == "dwell":
            self._finish_block()
        elif p.kind == "indep":
            self._axis_v[:] = 0.0
            self._axis_a[:] = 0.0
            if not self.held:
                b = self.blocks[0]
                self.position = b.seg.end.copy()
                self._finish_block()
        else:  # ramp: continue in the current block from where it ended
            end_s, end_v, _ = p.pw.sample(np.array([p.duration]))
            self.s = float(end_s[0] - p.base)
            self.v = float(end_v[0])
            self.a = 0.0
            while len(self.blocks) > 1 and self.blocks[1].kind == "path" and self.s > self.blocks[0].length + 1e-12:
                self.s -= self.blocks[0].length
                self._finish_block(True)
            b = self.blocks[0] if self.blocks else None
            if b is not None and b.seg is not None:
                self.s = min(self.s, b.length)
                self.position = b.seg.points(np.array([self.s]))[0]
            if abs(self.v) < 1e-9 and self._stopping:
                self._flush()

    @cython.locals(self=PlanCore, done=Block, keep_plan=cython.bint, n=cython.Py_ssize_t)
    def _finish_block(self, keep_plan: bool = False) -> None:
        # (the queue read once, the fields each written once: per block, issue 17)
        blocks = self.blocks
        if blocks:
            done = blocks.popleft()
            if done.kind == "thread":
                self.threads_queued -= 1
            seg = done.seg
            if seg is not None:  # onto the chain of finished segments (nc.motion.filter_ramps.seg_history)
                h = self._seg_hist
                n = h[2] + 1 if h else 1
                if n > 2 * HISTORY:  # kept short: the last HISTORY - 1 as a new chain (the old one stays as it was)
                    h, n = (), 1
                    for x in seg_history(self._seg_hist)[1:]:
                        h = (x, h, n)
                        n += 1
                self._seg_hist = (seg, h, n)
            if keep_plan:  # a path plan on into the next block (re-solved there), or the blocks after it
                p = self.plan
                if p is not None:
                    self._cont = (p, done.length) if p.kind == "path" and not p.open else None
                else:
                    cont = self._cont
                    if cont is not None:
                        self._cont = (cont[0], cont[1] + done.length)
        if keep_plan:
            if blocks:
                self._started = True
                self.line = blocks[0].move.line
            else:
                self._started = False
        else:
            self._started = False
            self.s = 0.0
            if blocks:
                self.line = blocks[0].move.line
