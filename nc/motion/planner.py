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

Why one file of ~800 lines: the planner is one state machine. Its queue, active plan, sample buffer
and event flags are read and written by every method below, in an order that the one-setpoint-per-
cycle guarantee depends on; split across modules, those invariants would be spread over files that
each see part of the state. The pure parts live beside it: look-ahead passes (lookahead.py), ruckig
profiles (profile.py), tolerance shares (shares.py), the position filter (smoothing.py), threading
geometry (threading.py, thread_corners.py) and stretch sampling (stretch.py).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from nc.alarm_table import PLANNING_STALL
from nc.alarms import NcAlarm
from nc.motion.corner_blends import blend_block
from nc.motion.limits import MotionConfig
from nc.motion.lookahead import MARGIN, Block, Limits, backward, change_distance, max_speed_at, reach
from nc.motion.path import Segment
from nc.motion.profile import Piecewise, solve_axes, solve_position, solve_velocity
from nc.motion.share_zones import ShareZones
from nc.motion.shares import MAX_FACTOR, jerk_factor
from nc.motion.smoothing import PositionFilter
from nc.motion.thread_corners import corner_offset
from nc.motion import threading as thr
from nc.moves import Move

CHUNK = 64  # cycles sampled per vectorised step
OPEN_CHUNK = 4  # ... while the queue cannot tell the jerk factor yet (the channel reads 4 blocks a cycle)
MAX_SOLVES_PER_CYCLE = 1000  # plans one cycle may start and end before a sample is due (decisions B4)


def _near(a: np.ndarray, b: np.ndarray) -> bool:
    """np.allclose(a, b, atol=1e-6) on plain floats: checked at every block start, where numpy's
    call cost more than the three comparisons (issue 17)."""
    return all(abs(x - y) <= 1e-6 + 1e-5 * abs(y) for x, y in zip(a.tolist(), b.tolist()))


@dataclass
class Setpoint:
    positions: np.ndarray  # machine coordinates per axis, in MotionConfig.axes order
    line: int  # program line of the active move (0 when idle before any move)
    path_velocity: float  # mm/s along the path
    move: Move | None


@dataclass
class _Plan:
    kind: str  # "path" (to the block end), "ramp" (velocity change, may span blocks), "dwell", "indep"
    pw: Piecewise | None
    duration: float
    t_next: float  # plan time of the next sample
    base: float = 0.0  # plan position at the start of blocks[0] (ramps that cross blocks)
    target: float = 0.0  # ramp target speed
    rpm: float = 0.0  # spindle speed the feed-per-rev cap used
    settled: bool = False  # that speed was the command the spindle had reached
    emitted: bool = False  # some of its samples went out (the planner state is the last of them)
    # A path solve whose jerk factor the queue could not tell yet (nc.motion.shares): sampled a
    # few cycles at a time and solved again once more than `queued` moves were pushed.
    open: bool = False
    queued: int = 0
    # A "cruise" (decision motion 44): whole blocks sampled at once; `carry` the next plan's t0 after the last
    # of them, `last` its offset from blocks[0] when sampled.
    carry: float = 0.0
    last: int = 0


class Planner:
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
        self._a_lo = 0.5 * cfg.share_tangential * float(self.lim.acc.min())
        self._j_lo = 0.5 * cfg.share_tangential * float(self.lim.jerk.min())
        # The channel sets `closed` when no move comes before the queue has run out to rest (program
        # end, an M/S/T or preview barrier); a push clears it. _jf: tangential jerk factor of the
        # last path solve (nc.motion.shares).
        self.closed = False
        self._jf = 1.0
        self._pushes = 0  # moves pushed so far (an open plan re-solves when more came)
        self.output = self.position.copy()  # the last setpoint handed out (filtered)

    # ---- queue ----------------------------------------------------------------------------
    def push(self, move: Move) -> None:
        self.closed = False
        self._pushes += 1
        b = self._block(move)
        if b is None:
            return
        blend = self.lim.blend
        if blend is not None:
            b.vtop = b.cap_hard
            if b.kind == "path" and not b.rapid and not b.move.per_rev:
                b.vtop = min(b.cap_hard, 1.5 * (self.dry_run_feed if self.dry_run else (b.feed or 0.0)))
        self._update_cap(b)
        added = 1
        if self.blocks:
            prev = self.blocks[-1]
            prev.vjunc = self.lim.junction(prev, b)
            added += self._corner(prev, b)
        self._path_s += b.length
        b.s_end = self._path_s
        if self._zones is not None:
            self._zones.block(b.s_end - b.length, b.vtop)
        self.blocks.append(b)
        self.threads_queued += b.kind == "thread"
        self._pushed += added
        # Blocks pushed since the last pass never had one: the pass must reach past all of them.
        need = max(self._need + added, self._pushed)
        if blend is not None:
            need = max(need, blend.window(self.blocks))
        self._need = need

    def _corner(self, prev: Block, b: Block) -> int:
        """The junction prev → b (prev.vjunc set): a corner blend between them where one is built
        (decisions motion 42, 45), or, under the filter, a hard junction where λ < 1 planned raw.
        Returns the blocks added (the blend: 1)."""
        zones = self._zones
        tol = self.cfg.path_tolerance or 0.0
        if zones is not None and prev.vjunc <= 0.0:
            zones.stop(prev.s_end)
            return 0
        blk = None
        if zones is not None and zones.inside(prev.s_end, max(prev.vtop, b.vtop)):
            # λ stays below 1 here: not blended, the junction is taken as without the filter, and
            # that is what a blend must beat
            prev.vjunc = min(prev.vjunc, self.lim.junction(prev, b, raw=True))
        if (self.lim.blend is None or zones is not None) and self._may_blend(prev):
            if zones is None or zones.blend_allowed(prev.s_end - prev.length, max(prev.vtop, b.vtop), self._now(),
                                                    abs(self.v) < 1e-12 and self.plan is None):
                blk = blend_block(self.lim, prev, b, tol)
        if blk is None:
            if zones is not None and (prev.du_n > 1e-9 or "arc" in (prev.seg.kind, b.seg.kind)):
                if zones.hard(prev.s_end, max(prev.vtop, b.vtop)):
                    prev.vjunc = min(prev.vjunc, self.lim.junction(prev, b, raw=True))
            return 0
        # Both lines gave path to it: the running lengths follow.
        prev.s_end -= blk.seg.tlen
        blk.s_end = prev.s_end + blk.length
        self._path_s = blk.s_end
        if zones is not None:
            blk.vtop = min(blk.cap_hard, prev.vtop)
            zones.add_blend(blk.s_end - blk.length, blk.s_end, max(prev.vtop, b.vtop))
        for x in (prev, blk, b):
            self._update_cap(x)
        self.blocks.append(blk)
        if self.lim.blend is not None:
            # The filter's windows walk the queue and their junction history side by side: the junction
            # prev → blend joins that history now, as any pushed block's does (b's comes with b).
            self._need = max(self._need, self.lim.blend.window(self.blocks) + 1)
        return 1

    def _may_blend(self, prev: Block) -> bool:
        """Whether the tail may still give path to a corner blend (decision motion 42): a tolerance
        to blend within, no hold (its ramp runs on across blocks), and no profile that could be
        caught by the shorter path: nothing planned yet, or the tail further beyond the active
        block than any stop from its speed needs, at half the least tangential limits."""
        tol = self.cfg.path_tolerance
        if tol is None or tol <= 0.0 or self.held or self._stopping:
            return False
        if not self._started and self.plan is None:
            return True
        head = self.blocks[0]
        if prev is head:
            return False
        room = prev.s_end - prev.length - head.s_end
        return room >= change_distance(max(head.cap, abs(self.v)), 0.0, self._a_lo, self._j_lo)

    def lookahead(self) -> None:
        """Bring the queue's end speeds up to date (the backward pass the pushes owe)."""
        if self._pushed:
            backward(self.blocks, 0, depth=self._need)
            self._pushed = self._need = 0

    @property
    def queue(self) -> deque[Block]:
        return self.blocks

    @property
    def active(self) -> Block | None:
        return self.blocks[0] if self._started and self.blocks else None

    @property
    def full(self) -> bool:
        n = len(self.blocks)
        if n >= self.depth + self._batch:
            self._filling = False
        elif n < self.depth:
            self._filling = True
        return not self._filling

    @property
    def idle(self) -> bool:
        return not self.blocks and self.plan is None and self._buf_done and self._settled

    @property
    def halted(self) -> bool:
        """Held (feed hold / stop) and standing still, with the queue kept."""
        return self.held and self.plan is None and self._buf_done and self.at_rest and self._settled

    @property
    def _settled(self) -> bool:
        return self.filter is None or self.filter.settled

    @property
    def at_rest(self) -> bool:
        return abs(self.v) < 1e-9 and not np.any(self._axis_v)

    @property
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

    def _now(self) -> float:
        """Path position (Block.s_end's scale) of the last sample handed out."""
        if self.blocks:
            b = self.blocks[0]
            self._share_s = b.s_end - b.length + (self.s if self._started else 0.0)
        return self._share_s

    def _share(self) -> float:
        """The filter's share λ at the present path position (nc.motion.share_zones)."""
        z = self._zones
        if z is None or not z.zones:
            lam = 1.0
        elif abs(self.v) < 1e-12:
            # At rest λ holds: the output is still settling there (F(p) ≠ p(t − D)). A plan starts only
            # once the filter has settled, where λ may change at once (a stop cuts the zones).
            lam = self._lam
        else:
            lam = z.lam(self._now())
        self._lam = lam
        return lam

    def share_rows(self, i: int, m: int) -> np.ndarray | None:
        """λ of buffer rows i … i + m − 1 as step() would take them one by one (`_share` after `_take`), for a
        stretch's push_many (nc.motion.stretch); None where λ is 1 throughout (no zone left)."""
        z = self._zones
        if z is None or not z.zones:
            return None
        out = np.empty(m)
        blk, popped, blocks = self._buf_blk, self._buf_popped, self.blocks
        for r in range(m):
            s, v, _ = self._buf_state[i + r]
            if not z.zones:
                lam = 1.0
            elif abs(v) < 1e-12:
                lam = self._lam
            else:
                b = blocks[blk[i + r] - popped] if blk is not None else blocks[0]
                self._share_s = b.s_end - b.length + s
                lam = z.lam(self._share_s)
            self._lam = out[r] = lam
        return out

    def share_standing(self, n: int) -> np.ndarray | None:
        """λ of n cycles standing (nc.motion.stretch.stand_stretch): the held one."""
        if self._zones is None or not self._zones.zones:
            return None
        return np.full(n, self._share())

    def _step_path(self) -> Setpoint:
        if self._integrate_angle:
            self._sim_angle += self.spindle_rpm() * 6.0 * self.cfg.cycle
        self._check_spindle()
        if self.spindle_command is not None:
            self._settle.update(float(self.spindle_rpm()), float(self.spindle_command()))
        if self._buf_blk is not None and not self._buf_done:
            k = self._buf_blk[self._buf_i]
            if k > self._buf_popped and (bad := self._chain_ok(self.plan, k)) <= k:
                self._break_chain(bad)
        if self._buf_done:
            self._refill()
        if self._buf_done and self.plan is None and self.blocks and self.blocks[0].kind == "thread" \
                and (self._thread is not None or self._settled):
            return self._thread_step()
        if self._buf_done:  # standing still (idle, held, or waiting)
            self.v = self.a = 0.0
            blk = self.blocks[0].move if self._started and self.blocks else None
            return Setpoint(self.position.copy(), self.line, 0.0, blk)
        i = self._buf_i
        self._buf_i += 1
        self._take(i)
        blk = self.blocks[0].move if self.blocks else None
        return Setpoint(self.position.copy(), self.line, float(self._buf_vel[i]), blk)

    def _block_rows(self) -> int:
        """Buffer rows left that lie in blocks[0] (a stretch stays within one block: nc.motion.stretch)."""
        i, n = self._buf_i, 0 if self._buf_pos is None else len(self._buf_pos)
        blk = self._buf_blk
        if blk is None:
            return n - i
        j = i
        while j < n and blk[j] == self._buf_popped:
            j += 1
        return j - i

    def _cruise_rows(self, n: int) -> int:
        """Of the next n buffer rows, how many a stretch may take across a cruise's blocks: those before the
        first block whose own solve would no longer cruise (`_chain_ok`, with the queue as it stands)."""
        i = self._buf_i
        m = min(n, 0 if self._buf_pos is None else len(self._buf_pos) - i)
        blk = self._buf_blk
        if blk is None or m <= 0:
            return m
        last = blk[i + m - 1]
        if last > self._buf_popped and (bad := self._chain_ok(self.plan, last)) <= last:
            while m > 0 and blk[i + m - 1] >= bad:
                m -= 1
        return m

    def _take(self, i: int) -> None:
        """The state after handing out buffer row i: a cruise's blocks before row i's are finished."""
        if self._buf_blk is not None:
            k = self._buf_blk[i]
            while self._buf_popped < k:
                self._finish_block(keep_plan=True)
                self._buf_popped += 1
        self.position = self._buf_pos[i]
        self.line = self._buf_line[i]
        self.s, self.v, self.a = self._buf_state[i]

    # ---- threads --------------------------------------------------------------------------
    def _thread_step(self) -> Setpoint:
        """One cycle of a spindle-locked thread chain (see nc.motion.threading)."""
        T = self.cfg.cycle
        b = self.blocks[0]
        self._started = True
        angle = float(self.spindle_angle())
        st = self._thread
        if st is None:
            if self._stopping:
                self._flush()
                return Setpoint(self.position.copy(), self.line, 0.0, None)
            if b.seg is not None and _near(b.seg.start, self.position):
                b.seg.start = self.position.copy()
            self.line = b.move.line
            if self.spindle_command is not None and not self._settle.ready(float(self.spindle_command())):
                self.spindle_wait = True  # the spindle still changes speed: stand still on the thread's line
                self._wait_cycles += 1
                self.v = self.a = 0.0
                return Setpoint(self.position.copy(), self.line, 0.0, b.move)
            self.spindle_wait = False
            self.thread_waits.append((b.move.line, self._wait_cycles))
            self._wait_cycles = 0
            st = self._thread = thr.arm(b, angle, float(self.spindle_rpm()), float(self.spindle_index()),
                                        b.move.line)
            self.thread_log.append((b.move.line, st.sync_angle, st.ramp_start))
            self.solves += 1
        if self._stopping and not st.stopping:
            if st.v <= 1e-9 and not st.locked:
                self._flush()
                return Setpoint(self.position.copy(), self.line, 0.0, None)
            thr.stop(st, b)
        while True:
            last = not (len(self.blocks) > 1 and self.blocks[1].kind == "thread") or st.stopping
            if not last:
                thr.add_corner(st, b, self.blocks[1], self.lim.acc, self.lim.jerk)
            s = thr.advance(st, b, angle, T, last)
            if s is not None:
                break
            if last:
                self.position = b.seg.end.copy()
                self._thread = None
                self.s = self.v = self.a = 0.0
                self._finish_block()
                return Setpoint(self.position.copy(), b.move.line, 0.0, b.move)
            self._finish_block(keep_plan=True)
            nb = self.blocks[0]
            thr.next_block(st, b, nb)
            b = nb
        self.position = b.seg.points(np.array([s]))[0]
        if st.corners:  # the chain's corners are rounded within the axes' limits (nc.motion.thread_corners)
            off = corner_offset(st.corners, st.u_block + s / thr.major_factor(b))
            if off is not None:
                self.position = self.position + off
        self.line = b.move.line
        self.s, self.v, self.a = s, st.v, 0.0
        if st.halted:
            self._flush()
            self.v = 0.0
        return Setpoint(self.position.copy(), self.line, st.v, b.move)

    # ---- planning -------------------------------------------------------------------------
    def _block(self, move: Move) -> Block | None:
        if move.kind == "dwell":
            return Block(move, "dwell", None, 0.0, 0.0, 1.0, 1.0, None)
        seg = Segment.of(move, self.axes)
        if seg.length < 1e-9:
            return None
        if move.kind == "rapid" and self.cfg.rapid_independent:
            return Block(move, "indep", seg, seg.length, 0.0, 1.0, 1.0, None, rapid=True)
        v, a, j = self.lim.block_limits(seg)
        feed = None if move.kind == "rapid" else (move.feed or 0.0) / (1.0 if move.per_rev else 60.0)
        kind = "thread" if move.kind == "thread" else "path"
        return Block(move, kind, seg, seg.length, v, a, j, feed, rapid=move.kind == "rapid")

    def _update_cap(self, b: Block, rpm: float | None = None) -> float:
        if b.kind != "path" and b.kind != "thread":
            b.cap = 0.0
            return 0.0
        cap = b.cap_hard
        if b.rapid:
            cap = cap * self._rapid_ovr if self._rapid_ovr > 0.0 else min(cap, self.cfg.slow_rapid)
        elif self.dry_run:
            cap = min(cap, self.dry_run_feed * self._feed_ovr)
        else:
            feed = b.feed or 0.0
            if b.move.per_rev:
                feed *= abs(rpm if rpm is not None else self.spindle_rpm()) / 60.0
            cap = min(cap, feed * self._feed_ovr)
        if b.vtop > 0.0:
            cap = min(cap, b.vtop)  # the filter windows were sized with it (dry run switched on later)
        b.cap = cap
        return cap

    def _limits_changed(self) -> None:
        for b in self.blocks:
            self._update_cap(b)
        backward(self.blocks, 0, full=True)
        self._pushed = self._need = 0
        self._replan()

    def _replan(self) -> None:
        """Drop the sampled-ahead cycles and plan again from the last emitted state."""
        if self.plan is None and self._buf_done:
            return
        if self.plan is not None and self.plan.kind == "dwell":
            return  # a dwell holds position anyway; the next plan sees the new settings
        self._buf_pos = None
        self._buf_i = 0
        self.plan = None
        self._carry = self.cfg.cycle

    def _check_spindle(self) -> None:
        p = self.plan
        if p is None or p.kind != "path" or not self.blocks or not self.blocks[0].move.per_rev:
            return
        rpm, settled = self._feed_rpm()
        # 2 % hides measurement noise; a spindle that reaches its command re-plans once more, so a feed
        # planned during the run-up does not stay up to 2 % low (E-N11); only once: under G96 the
        # command moves every cycle (motion decisions 30)
        if abs(rpm - p.rpm) <= 0.02 * max(p.rpm, 1.0) and (not settled or p.settled):
            return
        self._update_cap(self.blocks[0], rpm)
        self._replan()

    def _feed_rpm(self) -> tuple[float, bool]:
        """Spindle speed for feed per revolution: the measured one, or the command once the measurement
        is within 0.1 % of it (then noise cannot re-trigger planning). Second value: settled."""
        rpm = abs(self.spindle_rpm())
        cmd = abs(self.spindle_command()) if self.spindle_command is not None else 0.0
        if cmd > 0.0 and abs(rpm - cmd) <= 1e-3 * cmd:
            return cmd, True
        return rpm, False

    def _flush(self) -> None:
        self._thread = None
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

    def _refill(self) -> None:
        T = self.cfg.cycle
        for _ in range(MAX_SOLVES_PER_CYCLE):
            if self.plan is None and not self._settled and self.at_rest:
                return  # exact stop: the filtered setpoint reaches the point before anything starts
            if self.plan is None:
                self.plan = self._start_plan()
                if self.plan is None:
                    return
            p = self.plan
            if p.kind == "cruise":
                if not p.emitted:
                    self._sample_cruise(p)
                    if not self._buf_done:
                        return
                self._end_plan(p)
                continue
            if p.open and p.emitted and self._pushes > p.queued and not self.held:
                self._replan()  # more of the path is known: the jerk factor may rise
                continue
            n = int(math.floor((p.duration - p.t_next) / T + 1e-9)) + 1
            if p.t_next <= p.duration + 1e-12 and n > 0:
                self._sample(p, min(n, OPEN_CHUNK if p.open else CHUNK))
                if not self._buf_done:
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
                if b.seg is not None and _near(b.seg.start, self.position):
                    b.seg.start = self.position.copy()
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
            if not self.per_block:
                cruise = self._cruise(b, t0)
                if cruise is not None:
                    return cruise
            return self._plan_path(b, t0)
        if self._stopping:
            self._flush()
        self._started = False
        return None

    def _cruising(self, b: Block, v: float) -> bool:
        """A solve at b's start (or within b) from speed v at zero acceleration would cruise at v to b's end:
        its run ends there (b's end speed is not below its cap), its cap is v, nothing re-plans it per cycle.
        Not a corner blend (decision motion 45): measured, its solve does not give a cruise bit for bit."""
        return (b.kind == "path" and b.cap == v and b.vend >= v and not b.move.per_rev and b.move.css is None
                and "G31" not in b.move.tags and b.seg.kind != "blend")

    def _cruise(self, b: Block, t0: float) -> _Plan | None:
        """Decision motion 44: at its cap, with zero acceleration, a run whose end speed is the cap solves to
        constant speed to the end of its block, and so does the next block's solve while the same holds there.
        Such a chain is sampled across its blocks at once (no solve): positions as the per-block solves give
        them (tests/test_motion_cruise.py). A push may change the junction speeds far back in the queue
        (FilterCorners.window): once one came, each block of the chain is checked again when its first row is
        due, when its own solve would run (`_chain_ok`)."""
        v = self.v
        if self.held or self._stopping or self.a != 0.0 or v <= 0.0:
            return None
        self.lookahead()
        if not self._cruising(b, v):
            return None
        return _Plan("cruise", None, math.inf, t0, queued=self._pushes)

    def _sample_cruise(self, p: _Plan) -> None:
        """The rows of a cruise, whole blocks up to at least CHUNK rows: each block as its own solve gives them
        (a constant-speed profile from s0 at the plan time t0, s = s0 + v·t, sampled a CHUNK at a time while
        t <= duration + 1e-9 cycles, as `_refill` and `_sample` do; the next block's t0 the time left over, as
        `_end_plan` carries it), and the snap of a block's start to where the last one ended (`_start_plan`)."""
        T = self.cfg.cycle
        v = self.v
        blocks = self.blocks
        s0, t_next, k, nb = self.s, p.t_next, 0, len(blocks)
        pos: list[np.ndarray] = []
        st: list[float] = []
        offs: list[int] = []
        lines: list[int] = []
        carries: list[float] = []  # the plan time left over at the end of each block
        rows = 0
        while True:
            b = blocks[k]
            if k and _near(b.seg.start, blocks[k - 1].seg.end):
                b.seg.start = blocks[k - 1].seg.end.copy()
            duration = (b.length - s0) / v  # ruckig's duration of this profile, to the bit
            while True:
                n = int(math.floor((duration - t_next) / T + 1e-9)) + 1
                if not (t_next <= duration + 1e-12 and n > 0):
                    break
                n = min(n, CHUNK)
                t = t_next + T * np.arange(n)
                t_next = float(t[-1] + T)
                s = s0 + np.clip(t, 0.0, duration) * v
                pos.append(b.seg.points(np.clip(s, 0.0, b.length)))
                st += s.tolist()
                offs += [k] * n
                lines += [b.move.line] * n
                rows += n
            p.carry = t_next - duration if t_next - duration > 1e-12 else t_next - duration + T
            carries.append(p.carry)
            p.last = k
            if rows >= CHUNK or k + 1 >= nb or not self._cruising(blocks[k + 1], v):
                break
            k, s0, t_next = k + 1, 0.0, p.carry
        p.emitted = True
        self._buf_pos = np.concatenate(pos) if pos else np.empty((0, len(self.axes)))
        self._buf_vel = np.full(rows, v)
        self._buf_line = lines
        self._buf_state = [(x, v, 0.0) for x in st]
        self._buf_blk = offs
        self._buf_popped = 0
        self._buf_i = 0
        self._buf_carry = carries

    def _chain_ok(self, p: _Plan | None, upto: int) -> int:
        """The first block offset up to `upto` (where a cruise's next row lies) whose own solve would no longer
        cruise: a push since the chain was sampled changed its end speed (the same check `_cruise` makes, at
        the cycle the per-block solve would make it); `upto + 1` when all still cruise."""
        if p is None or p.kind != "cruise" or self._pushes == p.queued:
            return upto + 1
        self.lookahead()
        for k in range(self._buf_popped + 1, upto + 1):
            if not self._cruising(self.blocks[k - self._buf_popped], self.v):
                return k
        return upto + 1

    def _break_chain(self, k: int) -> None:
        """Block offset k does not cruise any more: the chain ends at the end of block k - 1, as that block's
        own plan would end there (`_end_plan`); the next refill solves block k."""
        while self._buf_popped < k - 1:
            self._finish_block(keep_plan=True)
            self._buf_popped += 1
        self._carry = self._buf_carry[k - 1]
        self.position = self.blocks[0].seg.end.copy()
        self.a = 0.0
        self._finish_block()
        self.plan = None
        self._buf_pos = None
        self._buf_blk = None

    def _spindle_starting(self) -> bool:
        return self.spindle_command is not None and abs(self.spindle_command()) > 0.0

    def _plan_path(self, b: Block, t0: float) -> _Plan | None:
        s, v, a = self.s, self.v, self.a
        rpm, settled = self._feed_rpm() if b.move.per_rev else (0.0, False)
        cap = self._update_cap(b, rpm if b.move.per_rev else None)
        if b.move.per_rev and rpm <= 0.0 and not self.dry_run and not self._spindle_starting():
            raise NcAlarm(0x1001, "feed per revolution with the spindle stopped (S0)", line=b.move.line,
                          block=b.move.block, program=b.move.program)
        self.solves += 1
        if self.held or cap <= 1e-9:
            if abs(v) < 1e-9 and abs(a) < 1e-9:
                if self._stopping:
                    self._flush()
                return None  # at rest: wait for resume / override
            pw = solve_velocity(s, v, a, 0.0, b.a, b.j)
            return _Plan("ramp", pw, pw.duration, t0, 0.0, 0.0)
        # The run: following blocks the profile may cross without a binding junction (same or
        # higher cap, end speed not below the cap); the target is the end of that run.
        cruise = s + change_distance(v, cap, b.a, b.j)
        jf, unknown = self._jerk_factor(b, s, cap, cruise)
        # A profile continued at nonzero acceleration was solved with the previous factor: when
        # the new one cannot meet its target from that state, the previous one still can.
        for f in (jf, self._jf) if self._jf > jf and abs(a) > 1e-9 else (jf,):
            for extend in (False, True):
                dist, v1, ra, rj, vmax = self._run_target(cap, extend, cruise, f)
                # Forward pass: no more than the entry state can reach (a braking state first ramps
                # its deceleration out, losing a²/2j of speed over v·|a|/j of path).
                ve, de = (v - a * a / (2.0 * rj), dist - s - v * abs(a) / rj) if a < 0.0 else (v, dist - s)
                v1 = min(v1, reach(max(ve, 0.0), max(de, 0.0), MARGIN * ra, MARGIN * rj))
                pw = solve_position(s, v, a, dist, v1, vmax, ra, rj)
                if pw is not None and pw.p_max <= dist + 1e-7 and pw.v_min() >= -1e-7:
                    break
            if pw is not None and pw.p_max <= dist + 1e-7 and pw.v_min() >= -1e-7:
                self._jf = f
                break
        if pw is None or pw.p_max > dist + 1e-7 or pw.v_min() < -1e-7:
            # Cannot meet the target from this state (an override just cut the cap): ramp down
            # to the cap first, then plan the rest from there.
            target = min(cap, max(v1, 0.0))
            pw = solve_velocity(s, v, a, target, b.a, b.j)
            if target > 1e-9:
                # after the ramp, cruise at the target speed to the end of the run
                pw.duration = max(pw.duration, (dist - s) / target)
                pw.t0[:, -1] = np.minimum(pw.t0[:, -1], pw.duration)
            return _Plan("ramp", pw, pw.duration, t0, 0.0, target)
        if self._jf < MAX_FACTOR and a >= 0.0 and v < cap * (1.0 - 1e-6) and vmax >= cap - 1e-9:
            ramp = self._speed_up(b, s, v, a, cap, cruise, dist, v1, ra, rj, t0)
            if ramp is not None:
                return ramp
        return _Plan("path", pw, pw.duration, t0, target=dist, rpm=rpm, settled=settled, open=unknown,
                     queued=self._pushes)

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
        f, unknown = jerk_factor(self.cfg, blend, self.blocks, start + s, start + cruise, self.closed)
        if unknown or f <= self._jf * (1.0 + 1e-9):
            return None
        if dist - cruise < change_distance(cap, v1, MARGIN * ra, MARGIN * rj):
            return None  # no cruise between the speed-up and the braking
        pw = solve_velocity(s, v, a, cap, ra, rj / self._jf * f)
        end_s = float(pw.sample(np.array([pw.duration]))[0][0])
        if end_s > cruise + 1e-9:
            return None
        return _Plan("ramp", pw, pw.duration, t0, 0.0, cap)

    def _jerk_factor(self, b: Block, s: float, cap: float, cruise: float) -> tuple[float, bool]:
        """The tangential jerk factor for a solve from s in b, and whether the queue could not
        tell it yet (nc.motion.shares): over the longest run any solve from here may take (the
        extended one: a higher jerk only ends runs sooner)."""
        blend = self.lim.blend
        if blend is None:
            return 1.0, False
        dist = self._run_target(cap, True, cruise)[0]
        start = b.s_end - b.length
        if self._zones is not None and self._zones.near(start + s - blend.span_max, start + dist + blend.span_max):
            return 1.0, False  # λ < 1 there: the raw path keeps the tangential share (decision motion 45)
        return jerk_factor(self.cfg, blend, self.blocks, start + s, start + dist, self.closed)

    def _run_target(self, cap: float, extend: bool = False, cruise_from: float = math.inf,
                    jf: float = 1.0) -> tuple[float, float, float, float, float]:
        """(distance, end speed, acceleration, jerk, top speed) of the run that starts with blocks[0].

        A run ends at the first junction slower than the cap. With `extend` it carries on through
        junctions whose end speed is set downstream (not binding: a braking chain through short
        blocks, which cannot be met with zero acceleration at every junction), its top speed then
        held to the slowest of them so the profile crosses each at no more than it allows.
        A junction past `cruise_from` (where the cap is reached) that may be crossed at the cap
        ends the run too: the profile cruises there, so nothing beyond it changes this solve.
        `jf`: factor on the run's tangential jerk (nc.motion.shares).
        """
        self.lookahead()
        blocks = self.blocks
        b = blocks[0]
        dist, ra, rj = b.length, b.a, b.j
        vmax = cap
        k = 0
        n = len(blocks)
        while True:
            b = blocks[k]
            if k + 1 >= n:
                return dist, min(b.vend, vmax), ra, rj * jf, vmax
            nx = blocks[k + 1]
            if nx.kind != "path" or nx.cap < cap - 1e-9 or b.vend <= 0.0 or k >= 2 * self.depth \
                    or (b.vend >= vmax - 1e-9 and dist >= cruise_from):
                return dist, min(b.vend, vmax), ra, rj * jf, vmax
            if b.vjunc < cap - 1e-9:
                if b.binding and b.vend >= max_speed_at(self.v, self.a, dist - self.s, ra, rj * jf):
                    # Not reachable faster than it allows from the present state (a rising
                    # chain of caps behind a corner): it cannot bind, and a profile that ended
                    # there at zero acceleration would only lose time.
                    pass
                elif not extend or b.binding:
                    return dist, min(b.vend, vmax), ra, rj * jf, vmax
                else:
                    vmax = min(vmax, b.vjunc)
            dist += nx.length
            ra, rj = min(ra, nx.a), min(rj, nx.j)
            k += 1

    def _plan_indep(self, b: Block, t0: float) -> _Plan | None:
        assert b.seg is not None
        lim = self.lim
        ovr = self._rapid_ovr
        vmax = lim.v * ovr if ovr > 0 else np.minimum(lim.v, self.cfg.slow_rapid)
        self.solves += 1
        if self.held:
            if not np.any(np.abs(self._axis_v) > 1e-9):
                if self._stopping:
                    self._flush()
                return None
            pw = solve_axes(self.position, self._axis_v, self._axis_a, self.position, vmax, lim.acc, lim.jerk,
                            velocity=True)
        else:
            pw = solve_axes(self.position, self._axis_v, self._axis_a, b.seg.end, vmax, lim.acc, lim.jerk)
        return _Plan("indep", pw, pw.duration, t0)

    def _sample(self, p: _Plan, n: int) -> None:
        T = self.cfg.cycle
        self._buf_blk = None
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
            if p.kind == "path" or (p.kind == "ramp" and not self.held):
                # The next sample lies in the next block: re-solve there from the last emitted
                # state (once per block), now that more of the queue may be known.
                length = blocks[0].length
                s_last = self.s
                self._finish_block(keep_plan=True)
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
                self._finish_block(keep_plan=True)
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
        self._buf_pos = b.seg.points(np.clip(s, 0.0, b.length))
        self._buf_vel = v
        self._buf_line = [line] * n
        self._buf_i = 0
        self._buf_state = list(zip(s.tolist(), v.tolist(), a.tolist()))

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
                self._finish_block(keep_plan=True)
            b = self.blocks[0]
            self.s, self.v, self.a = b.length, float(p.pw.v[0][-1]), 0.0
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
                self._finish_block(keep_plan=True)
            b = self.blocks[0] if self.blocks else None
            if b is not None and b.seg is not None:
                self.s = min(self.s, b.length)
                self.position = b.seg.points(np.array([self.s]))[0]
            if abs(self.v) < 1e-9 and self._stopping:
                self._flush()

    def _finish_block(self, keep_plan: bool = False) -> None:
        if self.blocks:
            self.threads_queued -= self.blocks.popleft().kind == "thread"
        self._started = False
        if not keep_plan:
            self.s = 0.0
        if self.blocks and not keep_plan:
            self.line = self.blocks[0].move.line
        if keep_plan and self.blocks:
            self._started = True
            self.line = self.blocks[0].move.line
