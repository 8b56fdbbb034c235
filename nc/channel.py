"""One NC channel in AUTO: pulls the interpreter, feeds the planner's look-ahead queue, runs the
M/S/T handshake, and turns any alarm into a controlled stop.

The MLC side of the handshake is reached only through `pending_aux` / `finish_aux()`, so the
channel runs the same with Delta's special M/D relays behind it or with no MLC at all.

Operator controls (what the MLC maps Delta's relays/registers onto, e.g. M2x001 feed hold,
D2x002 feed override, D2x004 rapid override; all take effect in the next cycle, jerk-limited):

- ``feed_override``  float 0.0–1.5 (0–150 %); 0 stops cutting moves along the path.
- ``rapid_override`` float 0.0–1.0; 0 means the slow rapid speed (``MotionConfig.slow_rapid``).
- ``feed_hold()``    decelerate along the path and stay (state HOLD); ``cycle_start()`` resumes.
- ``single_block``   bool; when set, the channel stops after every block (state BLOCK_STOP,
                     moves end at rest); ``cycle_start()`` runs the next block.
- ``dry_run``        bool; cutting moves run at ``dry_run_feed`` (mm/min) × feed override.
- ``reset()``        controlled stop along the path, then flush the queue and the program
                     (state IDLE once at rest).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any
from dataclasses import dataclass, field
from enum import Enum

from nc.alarms import Alarm, NcAlarm, internal_error
from nc.interrupt import M96Link, interrupt_stream
from nc.motion.css import css_rpm_at, x_origin
from nc.motion.limits import MotionConfig
from nc.motion.planner import Planner, Setpoint
from nc.budget import StatementBudget
from nc.moves import Aux, Busy, Event, MainLoop, Move, ProgramEnd, Sync
from nc.param_switch import capped, rebuilt
from nc.softlimits import SoftLimits
from nc.tap_interrupt import (TAP_TAGS, Retraction, TapStatus, guarded, interruption_alarms, plan_retraction,
                              record_of)

# Moves read from the interpreter into the look-ahead per cycle (M/S/T codes and preview stops do
# not count). Filling a 100-block queue at once takes ≈ 4 ms of interpretation and planning, which
# overran the first 1 ms real-time cycle of a CAM program; 4 (≈ 0.2 ms) keep up with blocks as
# short as 1/4 cycle. A first block that is long is planned with the 3 after it in view.
READS_PER_CYCLE = 4


class RunState(Enum):
    IDLE = "idle"
    RUNNING = "running"
    WAIT_AUX = "waiting for MLC finish"
    HOLD = "feed hold"
    BLOCK_STOP = "single block stop"
    STOPPING = "stopping"
    RESETTING = "resetting"
    FINISHED = "finished"
    ALARM = "alarm"


# The states `step`, `_feed_planner` and `busy` compare several times every cycle, as module names: an Enum
# member read from its class costs ~0.1 µs (EnumType's look-up), a global a tenth of that (issue 17)
_IDLE, _RUNNING, _WAIT_AUX, _HOLD, _BLOCK_STOP = (RunState.IDLE, RunState.RUNNING, RunState.WAIT_AUX, RunState.HOLD,
                                                  RunState.BLOCK_STOP)
_STOPPING, _RESETTING, _FINISHED, _ALARM = RunState.STOPPING, RunState.RESETTING, RunState.FINISHED, RunState.ALARM
_BUSY = (_RUNNING, _WAIT_AUX, _STOPPING, _HOLD, _BLOCK_STOP, _RESETTING)  # `Channel.busy`

@dataclass
class Channel:
    planner: Planner
    events: Iterator[Event] | None = None
    state: RunState = RunState.IDLE
    alarms: list[Alarm] = field(default_factory=list)
    pending_aux: Aux | None = None
    spindle_rpm: float = 0.0  # programmed S with direction, for feed per revolution
    end: ProgramEnd | None = None
    single_block: bool = False
    dry_run_feed: float = 5000.0  # mm/min
    _deferred: Aux | Sync | MainLoop | None = None
    # G96 (issue 5): the spindle speed constant surface speed asks for now (rpm), None under G97;
    # the runner/MLC sends it to the spindle drive. spindle_max is the G50/G92 S clamp.
    css_rpm: float | None = None
    spindle_max: float | None = None
    _css_surface: float | None = None
    _css_origin: float | None = None  # machine X of the work centre line (from the move or the S aux)
    css_diameter: bool = True  # the profile programs X in diameter (N2.001 Bit10 = 0)
    # D2x026 / 100, set by the MLC link: the NC applies it to the drive's speed, G97 and G96 alike,
    # forced to 100 % while a thread runs or waits in the look-ahead (`spindle_factor`, decisions 32)
    spindle_override: float = 1.0
    _block_moves: int = 0  # moves pushed since the last single-block stop
    # single block after an M/S/T-only block (decision M22-2): the line of the code issued since the last stop
    # (None: none), the event read after its handshake that begins the next block (held for the next cycle
    # start), and the line the channel last stopped after (a code on a motion block's line is that block's tail)
    _aux_line: int | None = None
    _next_ev: Event | None = None
    _stop_line: int = -1
    soft_limits: SoftLimits | None = None  # checked before a move reaches the planner (issue 8)
    _limit_alarm: Alarm | None = None  # raised once the moves before the offending one have run out
    # G31 skip (issue 5): the runner feeds the probe latch through skip(); on_skip(latched, stop)
    # hands the trigger position and the stop point to the interpreter before it reads on.
    on_skip: Callable[[dict[str, float], dict[str, float]], None] | None = None
    skip_latched: dict[str, float] | None = None
    _skip_move: Move | None = None
    # M96 (nc.interrupt): the MLC's M2x019 edge reaches interrupt(); m96 links the interpreter.
    m96: M96Link | None = None
    _interrupt: str | None = None  # "pending" (trigger taken) | "stopping" (braking along the path)
    _m96_running: bool = False  # the interrupt program's motion is in progress (M3x031)
    # the interpreter's macro statement budget, opened anew every cycle (nc.budget, decisions B2)
    statement_budget: StatementBudget | None = None
    emergency: bool = False  # an E-stop froze the setpoints: the bench must brake with the drives
    # this cycle's feed ran already, inside a stretch that ended before the cycle's step (hil/stretch_reads.py)
    _fed: bool = False
    # a move read ahead of the feed whose soft limits were checked then, as the feed checks it when it reads it
    _checked: Move | None = None
    # the stream read ahead (hil.stretch_reads.Ahead) while it is `events`: its `plain` moves were checked when read
    _ahead: Any = None
    # M2x026 M99 Call Stop, set by the MLC link: at the main program's M99 (an M code: the motion before it runs out
    # to rest) the program ends while it is ON (ProgramEnd code 99) instead of running again (decision mlc M25-1)
    m99_call_stop: bool = False
    # G05 (N§3.8.2, decision language L25-1): the planner's settings by parameter group, 0 the original ones (a
    # bench's `motion_configs()`); a G05 P of a group not here is 0x120D. Empty: only G05 P0 runs.
    param_groups: dict[int, MotionConfig] = field(default_factory=dict)
    group_log: list[tuple[int, int]] = field(default_factory=list)  # (G05 line, group) of every switch applied
    # N§3.13.2 G84 note (6) (decisions mlc M26-1 ... M26-9): the tapping interrupt status, kept from program to
    # program (hil.scripting hands it on), and the G84.48 / M2x707 retraction while it runs
    tap: TapStatus = field(default_factory=TapStatus)
    _retract: Retraction | None = None
    _tap_line: int | None = None  # line of the last tapping move started (M3x707 through its spindle reversal)
    _tap_mv: Move | None = None  # the active move `rigid_tapping` looked at last
    on_retracted: Callable[[dict[str, float]], None] | None = None  # the interpreter's position after G84.48
    # Axes the MLC handed back (hil/mlc_axes.py, decision M26-23) and where they stand: the next move pushed must start
    # there, else the preview read it before the hand-back and it would step the axis back (0x141C, decision M26-30)
    handed_back: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._feed_cap = self.planner.cfg.max_feed  # N1.033 of the settings in force (None: no limit)

    def load(self, events: Iterator[Event]) -> None:
        if self.tap.holds:  # axis moves and spindle starts are refused until G84.48 / M2x080 (M26-2)
            events = guarded(events, self.tap)
        self.events = events
        self.end = None
        self.state = RunState.IDLE
        self._interrupt, self._m96_running = None, False
        self._aux_line, self._next_ev, self._stop_line, self._block_moves = None, None, -1, 0

    def cycle_start(self) -> None:
        """Start the loaded program, resume after a feed hold, or run the next single block."""
        if self.events is not None and self.state is RunState.IDLE:
            self.state = RunState.RUNNING
        elif self.state is RunState.HOLD:
            self.planner.resume()
            self.state = RunState.RUNNING if self.pending_aux is None else RunState.WAIT_AUX
        elif self.state is RunState.BLOCK_STOP:
            self._block_moves = 0
            self._aux_line = None
            self.state = RunState.RUNNING

    @property
    def busy(self) -> bool:
        return self.state in _BUSY or self._retract is not None

    # ---- operator controls --------------------------------------------------------------
    @property
    def feed_override(self) -> float:
        return self.planner.feed_override

    @feed_override.setter
    def feed_override(self, value: float) -> None:
        self.planner.feed_override = value

    @property
    def rapid_override(self) -> float:
        return self.planner.rapid_override

    @rapid_override.setter
    def rapid_override(self, value: float) -> None:
        self.planner.rapid_override = value

    @property
    def dry_run(self) -> bool:
        return self.planner.dry_run

    @dry_run.setter
    def dry_run(self, on: bool) -> None:
        self.planner.set_dry_run(on, self.dry_run_feed)

    def feed_hold(self) -> None:
        if self.state in (RunState.RUNNING, RunState.WAIT_AUX, RunState.BLOCK_STOP):
            self.planner.hold()
            self.state = RunState.HOLD

    def reset(self) -> None:
        """Controlled stop, then flush motion, the pending M/S/T and the rest of the program."""
        if self._retract is not None and not self._retract.braking:
            # a reset interrupts the retraction too: it brakes short of R under control, the status stays (M26-8)
            self._retract.brake()
            self.alarms += interruption_alarms(self._retract.record, "reset")
        if self.state in (RunState.IDLE, RunState.FINISHED):
            return
        self._interrupt_tap("reset")  # N§3.13.2 note (6): a reset interrupts a tap as an E-stop does (M26-1)
        self.planner.stop()
        self.pending_aux = None
        self._deferred = None
        self._limit_alarm = None
        self._skip_move = None
        self._interrupt, self._m96_running = None, False  # a reset ends an interrupt program too
        self.events = None
        self._fed = False
        self._aux_line, self._next_ev, self._block_moves = None, None, 0
        self.state = RunState.RESETTING if not self.planner.idle else RunState.IDLE

    # ---- MLC side ---------------------------------------------------------------------
    def finish_aux(self) -> None:
        """The MLC's finish signal for the pending M/S/T code."""
        if self.pending_aux is not None:
            self.pending_aux = None
            if self.state is RunState.WAIT_AUX:
                self.state = RunState.RUNNING

    def released_by_cycle_start(self) -> None:
        """The pending code's hold (M00, M01) ended with a cycle start: under single block that press was the
        block's stop, the next block runs on without another (decision M22-2)."""
        self._aux_line = None

    # ---- G31 skip -----------------------------------------------------------------------
    @property
    def skip_armed(self) -> bool:
        """A G31 move is queued or running and no skip signal has been taken yet (arm the probe)."""
        return self._skip_move is not None and self.skip_latched is None

    def skip(self, latched: dict[str, float]) -> None:
        """The skip input: `latched` holds the probe's latched position for the axes that saw the
        edge. The G31 move brakes from this cycle on (jerk-limited, the planner's stop) and the
        rest of the move is dropped; the other axes' latch is the path point at the same place."""
        mv = self._skip_move
        if mv is None or self.skip_latched is not None or not latched:
            return
        self.skip_latched = _on_path(mv, latched)
        self.planner.stop()

    def _skip_done(self) -> None:
        """The G31 Sync drained: report the latch (the end point when nothing triggered, as Fanuc
        and Delta do) and the stop point, then read on from there."""
        mv, self._skip_move = self._skip_move, None
        stop = dict(zip(self.planner.axes, self.planner.position.tolist()))
        latched = self.skip_latched if self.skip_latched is not None else dict(mv.end)
        self.skip_latched = latched
        if self.on_skip is not None:
            self.on_skip(latched, stop)

    # ---- M96 program interruption ---------------------------------------------------------
    @property
    def interrupt_active(self) -> bool:
        """M3x031: the interrupt program runs (from the stop until its last move has ended)."""
        return self._m96_running and self.state in (RunState.RUNNING, RunState.WAIT_AUX, RunState.HOLD,
                                                    RunState.BLOCK_STOP)

    def interrupt(self) -> None:
        """The MLC's M2x019 (rising edge). With M96 P_ in force and the program running, the axes
        stop along the path from this cycle on and the interrupt program runs from where they stand.
        In feed hold, an M/S/T wait or a single-block stop the trigger is latched and taken as soon
        as the channel runs again (cycle start, the finish). Otherwise (no M96, M97, idle, M02/M30,
        an interrupt already running) it does nothing."""
        if self.m96 is None or self._interrupt is not None or self._m96_running \
                or self.state not in _M96_LATCHED or not self.m96.enabled():
            return
        aux = self.pending_aux
        if aux is not None and aux.kind == "M" and aux.value in (2, 30):
            return  # the program has ended: nothing to go back to
        self._interrupt = "pending"  # kept through a hold, an M/S/T wait or a block stop

    def _interrupt_step(self) -> None:
        pl = self.planner
        if self.state in _M96_LATCHED and self.state is not RunState.RUNNING:
            self._interrupt = "pending"  # latched; a stop begun is taken up again on resumption
            return
        if self.state is not RunState.RUNNING:  # a reset or an alarm came first
            self._interrupt = None
            return
        if self._interrupt == "pending":
            act = pl.active
            if self._skip_move is not None or self._limit_alarm is not None \
                    or (act is not None and act.kind == "thread"):
                return  # G31 and spindle-locked threads cannot stop on their path: taken after them
            pl.hold()
            pl.end_dwell()  # a dwell is no motion to brake: the interrupt program starts at once
            self._interrupt = "stopping"
            return
        if not pl.halted:
            return
        # At rest: the suspended block and what was read ahead leave the planner (look-ahead flushed)
        self._interrupt = None
        stop = dict(zip(pl.axes, pl.position.tolist()))
        held: list[Event] = []
        for b in pl.queue:  # a corner blend's block carries its incoming move again (motion decision 42)
            if not held or b.move is not held[-1]:
                held.append(b.move)
        held += [e for e in (self._deferred, self.end) if e is not None]
        self._deferred, self.end = None, None
        pl.stop()
        self.events = interrupt_stream(self, held, stop, self.events)

    # ---- faults -----------------------------------------------------------------------
    def raise_alarm(self, alarm: Alarm) -> None:
        """Any alarm, from the program, a drive or the bus: controlled stop, then ALARM."""
        self.alarms.append(alarm)
        if self.state is not RunState.ALARM:
            self.planner.stop()
            self.state = RunState.STOPPING if not self.planner.idle else RunState.ALARM
            self.pending_aux = None

    def emergency_stop(self, alarm: Alarm) -> None:
        """E-stop: setpoints freeze this cycle; the bench commands the drives' own quick stop, which
        does the braking (stop category 1)."""
        self.emergency = True
        self.alarms.append(alarm)
        self._interrupt_tap("emergency stop")  # N§3.13 G84 note (6)
        self.planner.abort()
        self.state = RunState.ALARM
        self.pending_aux = None

    # ---- the tapping interruption (N§3.13.2 G84 note (6), nc.tap_interrupt) -----------------------------
    def _interrupt_tap(self, cause: str) -> None:
        """A tapping move is active (or a retraction runs): keep its record, raise 0x0270 + 0x0C09 (M26-1)."""
        rt = self._retract
        if rt is not None:  # the retraction itself interrupted: the status stays, from where the axis stands
            if cause != "reset":  # (a reset brakes it: `reset`)
                self._retract = None
                self.planner.reset_position(dict(zip(self.planner.axes, self.planner.position.tolist())))
                self.alarms += interruption_alarms(rt.record, cause)
            return
        blk = self.planner.active
        if blk is None or not (TAP_TAGS[0] in blk.move.tags or TAP_TAGS[1] in blk.move.tags):
            return
        here = dict(zip(self.planner.axes, self.planner.output.tolist()))
        rec = record_of(blk.move, here, self.spindle_rpm, cause)
        if rec is not None:
            self.tap.record = rec
            self.alarms += interruption_alarms(rec)

    def tap_retract(self, line: int = 0, program: str | None = None, how: str = "G84.48") -> bool:
        """G84.48 (at rest, its Sync drained) or M2x707: the drilling axis back to R with the spindle reversed and
        locked to the pitch; the status ends when R is reached. Nothing without the status (M26-3). False: refused
        (alarm raised)."""
        rec = self.tap.record
        if rec is None or self._retract is not None:
            return True
        pl = self.planner
        i = pl.axes.index(rec.axis)
        try:
            self._retract = plan_retraction(rec, float(pl.position[i]), pl.cfg.limit(rec.axis), line, how)
        except NcAlarm as exc:
            exc.alarm.program = exc.alarm.program or program
            self.raise_alarm(exc.alarm)
            return False
        return True

    @property
    def tap_retraction(self) -> Retraction | None:
        """The retraction running now: the spindle drive follows its setpoint in position mode (mlc.machine)."""
        return self._retract

    @property
    def rigid_tapping(self) -> bool:
        """M3x707 (M26-5): from a G74/G84 tapping stroke's start until the next motion block that is no tapping
        stroke starts or the program stops (its reversals and its tail through the position filter included), and
        while the G84.48 / M2x707 retraction runs."""
        if self._retract is not None:
            return True
        blk = self.planner.active
        if blk is not None:
            mv = blk.move
            if mv is self._tap_mv:  # the move of the last scan: its answer (a scan per cycle, issue 17)
                return self._tap_line is not None
            self._tap_mv = mv
            tags = mv.tags  # () for a plain move: one test
            self._tap_line = mv.line if tags and (TAP_TAGS[0] in tags or TAP_TAGS[1] in tags) else None
            return self._tap_line is not None
        return self._tap_line is not None and self.state in _M96_LATCHED  # running, held, waiting on M/S/T

    def _retract_step(self) -> Setpoint:
        rt = self._retract
        assert rt is not None
        pl = self.planner
        i = pl.axes.index(rt.record.axis)
        rt.step(pl.cfg.cycle)
        pl.position[i] = pl.output[i] = rt.axis_position()
        if rt.done and rt.braking:  # stopped by a reset: the status holds, from where the axis stands
            self._retract = None
            pl.reset_position(dict(zip(pl.axes, pl.position.tolist())))
        elif rt.done:
            pl.position[i] = pl.output[i] = rt.record.r_level  # at R exactly
            self._retract = None
            pl.reset_position(dict(zip(pl.axes, pl.position.tolist())))
            self.tap.clear(rt.how)
            if self.on_retracted is not None:
                self.on_retracted(dict(zip(pl.axes, pl.position.tolist())))
        return Setpoint(pl.position.copy(), rt.line or pl.line, abs(rt.v), None)

    # ---- per cycle --------------------------------------------------------------------
    def step(self) -> Setpoint:
        if self._retract is not None:
            return self._retract_step()
        if self._interrupt is not None:
            self._interrupt_step()
        fed, self._fed = self._fed, False
        if self.state is _RUNNING and self._interrupt is None and not fed:
            self._feed_planner()
        try:
            sp = self.planner.step()
        except NcAlarm as exc:
            self.raise_alarm(exc.alarm)
            sp = self.planner.step()
        self._update_css(sp)
        state = self.state  # what changes it below happens once the queue has run out (`idle`)
        if state is _RUNNING:
            if self.planner.idle:
                if self.single_block and (self._block_moves or self._next_ev is not None):
                    self.state = _BLOCK_STOP
                    # a motion block's stop: a code on its line still belongs to it (`G01 X10 M08`, M22-2)
                    self._stop_line = self.planner.line if self._block_moves else -1
                elif self.end is not None and self.pending_aux is None:
                    self.state = _FINISHED
        elif state is _STOPPING:
            if self.planner.idle:
                self.state = _ALARM
        elif state is _RESETTING:
            if self.planner.idle:
                self.state = _IDLE
        return sp

    def _feed_planner(self) -> None:
        """Read events into the look-ahead queue until it is full or the channel must wait.

        M/S/T codes and preview stops are barriers: motion before them runs out to rest first.
        """
        pl = self.planner
        reads = READS_PER_CYCLE
        budget = self.statement_budget
        if budget is not None:
            if budget.spent:
                budget.held_cycles += 1  # the last cycle ended with macro statements still to run
            budget.new_cycle()
        # Nothing comes before the queue has run out to rest: its tail is a stop (nc.motion.shares).
        pl.closed = self.end is not None or self._deferred is not None or self._limit_alarm is not None
        src = self.events
        if src is self._ahead and src is not None and src.plain and self.state is _RUNNING and self._feed_cap is None \
                and self.end is None and self._limit_alarm is None and self._deferred is None and not self.single_block:
            # plain moves read ahead (hil.stretch_reads.Ahead: no G31, limits checked, no statement): the loop
            # below would only push them, with nothing else to check between two (issue 17)
            plain = src.plain
            while reads and plain and not pl.full:
                ev = self._checked = plain.popleft()
                if self.handed_back and self._read_ahead(ev):
                    return
                pl.push(ev)
                self._block_moves += 1
                reads -= 1
        while self.state is _RUNNING and self.end is None and not pl.full:
            if self._limit_alarm is not None:
                if pl.idle:  # the legal moves before it have run out: the offending one never starts
                    alarm, self._limit_alarm = self._limit_alarm, None
                    self.raise_alarm(alarm)
                return
            if self._deferred is not None:
                if not pl.idle:
                    return
                ev, self._deferred = self._deferred, None
                if isinstance(ev, Aux):
                    self._issue(ev)
                    return
                if type(ev) is MainLoop and self._main_loop(ev):
                    return
                if self._skip_move is not None:
                    self._skip_done()
                if type(ev) is Sync and ev.reason == "G84.48":
                    self.tap_retract(ev.line, ev.program)
                    return  # the retraction runs from the next cycle; the program reads on after it
                if type(ev) is Sync and ev.group is not None:  # G05: motion has drained, its group applies here
                    if not self._switch_group(ev):
                        return
                    pl = self.planner
                continue  # a Sync: motion has drained, read on
            if self.single_block and self._block_moves:
                pl.release_run()  # nothing more is read: a run held back runs now (nc.motion.spline_feed)
                return
            if self._next_ev is not None:  # the block after a single-block stop at an M/S/T-only block
                if self.single_block and self._aux_line is not None:
                    return
                ev, self._next_ev = self._next_ev, None
                self._aux_line = None
            elif reads == 0:
                return  # the rest next cycle
            else:
                try:
                    ev = next(self.events)  # type: ignore[arg-type]
                except StopIteration:
                    self.end = ProgramEnd(0, "", 0)
                    pl.closed = True
                    return
                except NcAlarm as exc:
                    self.raise_alarm(exc.alarm)
                    return
                except Exception as exc:  # a bug must still stop the machine with an alarm
                    self.raise_alarm(internal_error(exc))
                    return
                if self._aux_line is not None and self.single_block and getattr(ev, "line", None) != self._aux_line:
                    # an M/S/T-only block has run, its handshake finished: stop before the next block (M22-2);
                    # a code on the same line (`M03 S1000`) is the same block and is read on
                    self._next_ev = ev
                    return
            if type(ev) is Move or isinstance(ev, Move):  # the usual event first (Move has no subclass)
                if self.soft_limits is not None and ev is not self._checked \
                        and (crossing := self.soft_limits.check(ev)) is not None:
                    self._limit_alarm = crossing
                    continue
                if self._feed_cap is not None:
                    ev = capped(ev, self._feed_cap)
                if "G31" in ev.tags:
                    self._skip_move = ev
                    self.skip_latched = None
                if self.handed_back and self._read_ahead(ev):
                    return
                pl.push(ev)
                self._block_moves += 1
                reads -= 1
            elif isinstance(ev, Busy):
                if len(pl.blocks) < 2:
                    pl.release_run()  # the queue runs dry while the interpreter works: what is held runs
                return  # the statement budget is spent: the interpreter reads on next cycle
            elif isinstance(ev, Aux):
                if pl.idle:
                    self._issue(ev)
                    return
                self._deferred = ev
                pl.closed = True
            elif isinstance(ev, ProgramEnd):
                self.end = ev
                pl.closed = True
            elif type(ev) is MainLoop:  # an M code: motion before it runs out to rest, then M2x026 decides
                if not pl.idle:
                    self._deferred = ev
                    pl.closed = True
                elif self._main_loop(ev):
                    return
            elif isinstance(ev, Sync):
                if not pl.idle:
                    self._deferred = ev
                    pl.closed = True
                elif self._skip_move is not None:
                    self._skip_done()
                elif ev.reason == "G84.48":
                    self.tap_retract(ev.line, ev.program)
                    return
                elif ev.group is not None:
                    if not self._switch_group(ev):
                        return
                    pl = self.planner

    def _read_ahead(self, mv: Move) -> bool:
        """The first move after an MLC axis came back (decision M26-30): True (alarm raised, the move never starts)
        where it starts elsewhere than the axis stands, read by the preview before the hand-back (NC5 §3.2.2 (2):
        the preview interpolates as if the axes had not been switched; an M code that halts it, N1.118/N1.119, after
        the one that hands the axis back avoids that). Planned from its stale start it would step the axis back
        in one cycle (a setpoint jump the drive would meet as a following-error or overspeed fault)."""
        back, self.handed_back = self.handed_back, {}
        for axis, pos in back.items():
            x = mv.start.get(axis)
            if x is not None and abs(x - pos) > 1e-6:
                self.raise_alarm(Alarm(
                    0x141C, f"line {mv.line} was read ahead before axis {axis} came back from the MLC: it starts at "
                            f"{axis}{x:.4f}, the axis stands at {pos:.4f} (NC5 §3.2.2 (2): put an M code that halts the "
                            f"preview, N1.118/N1.119, after the one that hands the axis back)",
                    line=mv.line or None, block=mv.block or None, program=mv.program, axis=axis))
                return True
        return False

    def _switch_group(self, ev: Sync) -> bool:
        """G05 P at rest (its Sync drained: the queue empty, the filter settled): the planner rebuilt with the
        group's settings, P0 the original ones (N§3.8.2 "immediately apply"). A group the channel does not hold
        is 0x120D at the G05 block; False then (the channel stops)."""
        n = ev.group or 0
        cfg = self.param_groups.get(n)
        if cfg is None:
            if n == 0:
                return True  # no groups: the settings in force are the original ones
            self.raise_alarm(Alarm(0x120D, f"parameter group {n} is not set on this bench "
                                           f"([param_groups.{n}] in the bench file)",
                                   line=ev.line, block=ev.block, program=ev.program or None))
            return False
        if cfg is not self.planner.cfg:
            self.planner = rebuilt(self.planner, cfg)
            self._feed_cap = cfg.max_feed
        self.group_log.append((ev.line, n))
        return True

    def _main_loop(self, ev: MainLoop) -> bool:
        """The main program's M99 reached, the axes at rest: with M2x026 M99 Call Stop ON the program ends here
        (N App. B: "slow down to stop and then stop all process when executing M99"; M3x047 follows the end code
        99), else it runs again. True when it ended."""
        if not self.m99_call_stop:
            return False
        self.end = ProgramEnd(ev.line, ev.block, 99)
        self.planner.closed = True
        return True

    def _update_css(self, sp: Setpoint) -> None:
        """G96: the active move's surface speed at the current X diameter; between moves the last
        S decides (an S under G96 is m/min, any other S ends it). The S aux of `G96 S_` carries the
        work centre, so the speed is right before the first move (motion decisions 30)."""
        mv = sp.move
        if mv is not None and mv.css is None:  # no G96 on the move (every cycle of a mill): `css_state`'s
            self._css_surface = self.css_rpm = None  # answer, without the call
            return
        self._css_surface, self._css_origin, self.css_rpm = self.css_state(mv, sp.positions)

    def css_state(self, mv: Move | None, positions: Any) -> tuple[float | None, float | None, float | None]:
        """(surface speed, work centre, rpm) as `_update_css` leaves them after a setpoint of move `mv` at
        `positions`, the channel unchanged (a stretch asks it for each of its samples, hil/stretch.py)."""
        surface, origin = self._css_surface, self._css_origin
        if mv is not None:
            surface = mv.css
            if surface is None:
                return None, origin, None
            origin = x_origin(mv, "X", self.css_diameter)
        axes = self.planner.axes
        if surface is None or origin is None:
            return surface, origin, None
        if "X" not in axes:
            return surface, origin, 0.0
        # G00: the speed at the rapid's end point, not chased along it (decision motion 70, catalogue A40; Fanuc)
        x = mv.end.get("X", 0.0) if mv is not None and mv.kind == "rapid" else float(positions[axes.index("X")])
        return surface, origin, css_rpm_at(x, origin, surface, self.spindle_max)

    @property
    def threading(self) -> bool:
        """A spindle-locked thread runs or waits in the look-ahead (G32/G34/G92/G76)."""
        pl = self.planner
        return pl._thread is not None or pl.threads_queued > 0  # counted, not a scan of the queue

    @property
    def spindle_wait(self) -> bool:
        """A thread waits for the spindle's measured speed to settle at its command (decisions 33)."""
        return self.planner.spindle_wait

    @property
    def spindle_factor(self) -> float:
        """The spindle override the drive's speed gets: D2x026, but 100 % for threads, so every pass
        runs at the programmed speed and meets the thread in phase (NC5 threading note (1))."""
        return 1.0 if self.threading else self.spindle_override

    def _css_now(self) -> float | None:
        """The G96 rpm at the current X (the last setpoint's), None without a surface speed."""
        axes = self.planner.axes
        if self._css_surface is None or self._css_origin is None or "X" not in axes:
            return self.css_rpm
        x = float(self.planner.output[axes.index("X")])
        return css_rpm_at(x, self._css_origin, self._css_surface, self.spindle_max)

    def _issue(self, aux: Aux) -> None:
        # S takes effect when it is issued (moves before it are done), not when it is read ahead
        if aux.kind == "S" and aux.args.get("hold"):
            # G97 alone: the rpm G96 has now becomes the G97 speed (Fanuc; motion decisions 31)
            rpm = self._css_now()
            if rpm is not None:
                aux.value = rpm
        if aux.kind == "S" and aux.args.get("max"):
            self.spindle_max = aux.value
        elif aux.kind == "S" and aux.args.get("css"):
            self._css_surface = aux.value
            self._css_origin = aux.args.get("x0", self._css_origin)
        elif aux.kind == "S":
            self._css_surface = None
        if aux.kind == "S" and not aux.args.get("max"):
            self.spindle_rpm = aux.value
        self.pending_aux = aux
        if self.single_block:
            if aux.line == self._stop_line:
                self._stop_line = -1  # the tail of the motion block the channel stopped after
            else:
                self._aux_line = aux.line  # stop once its handshake is done and the next block is read (M22-2)
        if aux.wait and aux.line:
            # an M/S/T block is the current block while the NC waits on it (its MLC finish, an M00 hold): the
            # trace's line and `--at line=N` name it, until the next block starts (decisions bench B56, B79)
            self.planner.line = aux.line
        if aux.wait:
            self.state = RunState.WAIT_AUX


# M96: where a trigger is taken (RUNNING) or kept until the channel runs again (docs/decisions/mlc.md)
_M96_LATCHED = (RunState.RUNNING, RunState.WAIT_AUX, RunState.HOLD, RunState.BLOCK_STOP)


def _on_path(mv: Move, latched: dict[str, float]) -> dict[str, float]:
    """The G31 line's point where the latched axes were: the path parameter comes from the latched
    axis that travels furthest (best resolution), the other axes follow the straight line."""
    moving = {a: mv.end[a] - mv.start.get(a, mv.end[a]) for a in mv.end}
    key = max((a for a in latched if a in moving), key=lambda a: abs(moving[a]), default=None)
    if key is None or abs(moving[key]) < 1e-12:
        return {a: latched.get(a, mv.start.get(a, v)) for a, v in mv.end.items()}
    u = (latched[key] - mv.start[key]) / moving[key]
    u = min(max(u, 0.0), 1.0)
    out = {a: mv.start.get(a, mv.end[a]) + moving[a] * u for a in mv.end}
    out.update({a: v for a, v in latched.items() if a in out})
    return out


def skip_hook(interp) -> Callable[[dict[str, float], dict[str, float]], None]:
    """Channel.on_skip for an Interpreter: #21048…/#21064… read the latch, and the next block
    starts from where the axes stopped (not from the programmed G31 end point)."""
    def record(latched: dict[str, float], stop: dict[str, float]) -> None:
        interp.record_skip(latched)
        interp.position.update({a: v for a, v in stop.items() if a in interp.position})
    return record
