"""The bench cycle: receive feedback → MLC scan → NC channel step → send setpoints, once per cycle.

In lock-step mode the link advances simulated time by exactly one cycle per exchange, so a run
is deterministic and faster than real time.

Why one file of ~630 lines: `BenchRunner` is the cycle, and the stop path (quick stop, standstill,
disable at rest, shutdown) runs inside that same cycle on the same state (masters, PDO images,
channel, MLC, trace, stop flags); kept together, the order a cycle and a stop do things in can be
read in one place. What is not that state lives beside it: stretches (stretch.py, stretch_bulk.py),
signals (stop_signals.py), the MLC bridge (mlc_bridge.py), homing (drive_homing.py), the trace.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from fieldbus.cia402 import Cia402Master, State, Target
from fieldbus.link import BusError, BusLink, SimLink
from fieldbus.pdo import RxPdo, TxPdo
from hil.bench import Bench
from hil.bus_work import BusWork
from hil.clock import CycleTiming, LockStepClock, RealTimeClock
from hil.cycle_lean import OVERSPEED, RESET_CYCLES, WARM_AHEAD_NS, WARM_MIN_NS, factors, feedback, row, setpoints, warm
from hil import fit_ahead, mlc_axes, retentive, servo_relays
from hil.drive_homing import home_axes
from hil.mlc_bridge import drive_status
from hil import stretch_ahead
from hil.bus_ahead import BusAhead
from hil.stretch import Stretcher, ahead_wanted, wanted as stretch_wanted
from hil.trace import TraceSource, TraceWriter, trace_columns
from hil.write_guard import TraceGuard
from mlc.basic import BasicMlc
from nc.alarm_table import MAX_TIME, TRACE_WRITE
from nc.alarms import Alarm, NcAlarm, internal_error
from nc.budget import StatementBudget
from nc.channel import Channel, RunState, skip_hook
from nc.interp import Interpreter
from nc.interrupt import m96_link
from nc.motion import Planner
from nc.motion.css import spindle_speed
from nc.motion.spline_feed import load_fit
from nc.moves import Event, Move
from nc.profiles import make_profile
from nc.program import Program, parse_program
from nc.softlimits import SoftLimits

MODE_CSP = 8
MODE_CSV = 9
MAX_TIME_ALARM = MAX_TIME  # deltahil's own range 0xDE00-0xDEFF (nc/alarm_table.py)
STANDSTILL_TIMEOUT = 10.0  # s the stop path waits for the axes to stand before it disables anyway
# An axis stands when its position feedback (0x6064) has not changed for REST_CYCLES cycles and its
# velocity feedback reads 0. Velocity alone cannot say it: Delta drives report 0x606C in 0.1 rpm of
# the motor, which reads 0 below 1 rpm (2,133 counts/s at 1,280,000 counts/rev).
REST_CYCLES = 3
LIMIT_HYSTERESIS = 0.05  # mm (deg): how far off a limit switch an axis must get before a new hit counts
FROZEN_S = 0.2  # s of unchanged feedback from a moving drive that mean it left the bus


@dataclass
class RunResult:
    cycles: int = 0
    sim_time: float = 0.0
    program_time: float = 0.0
    enable_cycles: int = 0
    power_up_resets: list[tuple[str, int]] = field(default_factory=list)  # (drive, its error code) reset at power-up
    max_ferr: dict[str, float] = field(default_factory=dict)
    final: dict[str, float] = field(default_factory=dict)
    alarms: list[Alarm] = field(default_factory=list)
    finished: bool = False
    realtime: bool = False
    timing: dict[str, dict[str, float]] = field(default_factory=dict)  # jitter/latency/exec percentiles, s
    overruns: int = 0
    granted: str = ""  # what the system granted the real-time loop
    stopped_by: str | None = None  # the signal (SIGINT, SIGTERM, SIGHUP, SIGQUIT) whose stop ended the run
    stretched: int = 0  # cycles run in stretches (hil/stretch.py), not stepped one by one
    fits_ahead: tuple[int, int] | None = None  # B86: fitted windows (taken from the second process, fitted in a cycle)
    param_groups: list[tuple[int, int]] = field(default_factory=list)  # (line, group) of each G05 applied (L25-1)

    @property
    def ok(self) -> bool:
        return self.finished and not self.alarms


class BenchRunner:
    def __init__(self, bench: Bench, link: BusLink, trace: TraceWriter | None = None, mlc: BasicMlc | None = None,
                 on_cycle: Callable[["BenchRunner"], None] | None = None, *,
                 clock: LockStepClock | RealTimeClock | None = None, progress: object | None = None) -> None:
        self.bench = bench
        self.link = link
        self.trace = trace
        self.mlc = mlc or BasicMlc(max_rpm=min((s.max_rpm for s in bench.spindles), default=6000.0),
                                   cycle_time=bench.cycle)
        self.on_cycle = on_cycle
        self.axes = bench.axis_names
        n_axes, n_sp = len(bench.axes), len(bench.spindles)
        self.masters = [Cia402Master() for _ in range(n_axes + n_sp)]
        self.rx = [RxPdo(mode=MODE_CSP) for _ in range(n_axes)] + [RxPdo(mode=MODE_CSV) for _ in range(n_sp)]
        for rx in self.rx[n_axes:]:
            rx.touch_probe_function = 0x0001  # latch the spindle encoder index (thread sync)
        self.tx: list[TxPdo] = [TxPdo() for _ in self.rx]
        self._probe_axes = [i for i, ax in enumerate(bench.axes) if ax.drive.probe_position is not None]  # G31
        self._rest = [0] * len(self.rx)  # cycles each drive's feedback has stood still (see REST_CYCLES)
        self._last_position: list[int | None] = [None] * len(self.rx)
        self.scales = [a.scaling for a in bench.axes] + [s.scaling for s in bench.spindles]
        self._factors = factors(self.scales)  # the cycle's unit factors, read once (hil/cycle_lean.py)
        # App. A 0x0602 overspeed protection: an axis's measured speed beyond OVERSPEED × its limit, in the
        # drive's own 0x606C units so the cycle compares integers (decisions cycles.md)
        self._overspeed = [abs(self.scales[i].velocity_to_drive(OVERSPEED * a.limits.max_velocity))
                           for i, a in enumerate(bench.axes)]
        self.result = RunResult(max_ferr={a: 0.0 for a in self.axes})
        self.channel: Channel | None = None
        self.cycle = 0
        self.time = 0.0
        self.line = 0
        self.actual = np.zeros(n_axes)
        self._alarmed_drives: set[int] = set()
        # During power-up (else None): drive -> the cycle its latched fault was reset at (decision B72)
        self._power_up_reset: dict[int, int] | None = None
        # axis -> position (counts) where its drive reported the limit switch: 0x0402 once per hit; the hit ends
        # when the axis is off the switch and LIMIT_HYSTERESIS away (a servo settling on the edge is no new hit)
        self._at_limit: dict[int, int] = {}
        self._limit_hysteresis = [abs(sc.to_counts(LIMIT_HYSTERESIS) - sc.to_counts(0.0)) for sc in self.scales]
        self._commands = np.zeros(n_axes)
        # Machine position minus drive position per axis (units); NC-side homing sets it (issue 5).
        self.origin = np.zeros(n_axes)
        # The pacer: lock-step virtual time unless a real-time clock is given.
        self.clock = clock or LockStepClock(bench.cycle)
        # A field bus: the wait for it and the master's own work per cycle, apart (decisions E25)
        self._bus_work = BusWork.for_link(link, self.clock.realtime)
        self.timing = CycleTiming(bench.cycle, 0.0)
        self.progress = progress  # anything with update(runner) and close(); see hil.progress
        # Extra trace columns (MLC signals ...): append TraceSources before the run starts and open
        # the trace with `trace_columns()`.
        self.trace_sources: list[TraceSource] = []
        self._seen_alarms: set[int] = set()
        self._planner_failed = False
        self._braking = False  # every drive was told its quick stop (E-stop, failed planner)
        # axes the MLC's servo relays hold OFF (bit i; servo_relays.RESYNC: a re-enable whose position the NC is
        # still to take), M22-1
        self._servo_off = 0
        self._mlc_axes = 0  # bit i: axis i under MLC control or switching (hil/mlc_axes.py)
        self._winding_down = False  # the run is over; the stop path brings everything to rest
        self._bus_closed = False
        self.stop_request: str | None = None  # a signal's name (hil/stop_signals.py): stop, then end
        self.unreferenced: frozenset[str] = frozenset()  # axes without origin (hil run --no-home): 0x0A08
        self.max_time_name = "the bench's max_time"  # what set bench.max_time, for 0xDE03's message (B57)
        self.retain: str | None = None  # hil run --retain FILE: the retentive # variables (hil/retentive.py)
        self._retained = None  # the variables loaded from it, saved back when the run ends
        self._overrun_alarmed = False
        self._hooks: tuple | None = None  # (link, mlc, what they offer the cycle): asked once, see _cycle
        self._bus_ahead = False  # real time on the sim bus: a stepped cycle's exchange runs before its tick
        self._stretcher: Stretcher | None = None  # run_events' (hil/stretch.py), for _settle too (B38)
        self._ahead: BusAhead | None = None  # real time on a field bus: work ahead in the slack (B60)
        # Fitted windows worked out by a second process (B86): "auto" in real time, "wait" (lock-step tests: the
        # run waits for each window), "off"; None: hil.fit_ahead.mode()
        self.fit_ahead: str | None = None
        self._fit_ahead = None
        self._cut: KeyboardInterrupt | None = None  # a second signal while waiting for standstill (B95)
        self.disabling = False  # the shutdown's last cycles, disabling the drives at standstill (B95)

    def trace_columns(self) -> list[str]:
        extra = [c for src in self.trace_sources for c in src.columns]
        return trace_columns(self.axes, [s.name for s in self.bench.spindles], extra)

    # ---- public ---------------------------------------------------------------------------
    def run_program(self, program: Program) -> RunResult:
        paced = isinstance(self.clock, RealTimeClock)
        if self.trace is not None:  # a trace that cannot be written: alarm 0xDE04, stop, no half trace (B97)
            TraceGuard(self.trace, self._trace_failed)
        self._bus_ahead = paced and type(self.link) is SimLink and (stretch_wanted(realtime=True) or ahead_wanted())
        if paced:
            _preload(self.bench)
        elif type(self.link) is not SimLink:  # lock-step on a real bus: a stall would trip its watchdog
            load_fit()  # (a spline fit's modules and scipy imports, ≈ 0.18 s; the sim bus waits for its first use)
        gc_before: tuple[int, ...] | None = None
        try:
            # Everything the program needs is built before the drives are enabled: once cycles
            # run (paced in real time), a cycle has no room for it.
            profile = make_profile(self.bench.profile, self.axes, self.bench.params)
            interp = Interpreter(profile)
            interp.unreferenced = self.unreferenced
            if self.retain is not None:  # --retain: the retentive # variables of the last run (App. A 0x140B)
                retentive.load(self.retain, interp.vars)
                self._retained = interp.vars
            interp.budget = StatementBudget.for_profile(profile)  # macro statements per cycle (decisions B2)
            self._interp = interp  # G31 skip hands the latch back to it (issue 5)
            from hil.servo_link import BusServoAccess  # G10 L40-L46 → SDO / Modbus on this bench (issue 8)

            interp.servo.handler = BusServoAccess(self.link, [self._name(i) for i in range(len(self.masters))],
                                                  getattr(self, "servo_modbus", None))
            self.profile = profile  # G10 L21 soft limits live in its params (issue 8)
            if hasattr(self.mlc, "attach_interpreter"):  # #25000–#25511 (issue 8), block skip M2x010 (M21-1)
                self.mlc.attach_interpreter(interp)
            elif hasattr(self.mlc, "attach_variables"):  # MLC ↔ #25000–#25511 exchange (issue 8)
                self.mlc.attach_variables(interp.vars)
            planner = self.make_planner()
            self._start_fit_ahead(interp, program, planner, paced)
            if paced:
                _quiet_gc()
            else:  # B42: what is built so far (modules, the parsed program) frozen out of the collector's walks
                gc.freeze()  # for the run: in a 2nd CAM run in one process a generation-2 walk cost ≈ 9 µs a cycle
                gc_before = _rare_gc()  # B150: young collections rare while the cycles run, not off
            if not self.power_up() or not home_axes(self):  # axes with a bench `homing` table: drive homing
                return self._finish()
            interp.take_position(dict(zip(self.axes, self.actual.tolist())))
            if self._fit_ahead is not None:
                self._fit_ahead.begin(dict(zip(self.axes, self.actual.tolist())))
            self.run_events(interp.run(program), planner)
        except BusError as exc:
            self._alarm(self._placed(exc.alarm))
            # A bus alarm naming a drive (CANopen EMCY) is that drive's alarm: its fault bit is not raised again.
            self._alarmed_drives.update(i for i in range(len(self.masters)) if self._name(i) == exc.alarm.axis)
        except NcAlarm as exc:
            self._alarm(exc.alarm)
        except Exception as exc:  # a bug in the NC or the planner: it must not take the stop with it
            self._end_reason = "internal error"
            blk = self.channel.planner.active if self.channel is not None else None
            mv = blk.move if blk is not None else None  # the block being executed is where it happened
            self._alarm(internal_error(exc, mv.line or None, mv.block or None, mv.program) if mv is not None
                        else internal_error(exc, self.line or None))
            self._quick_stop()
        except BaseException:  # a second Ctrl-C: the trace's end record says the run was cut
            self._end_reason = "interrupted"
            raise
        finally:
            try:
                self._shutdown()
            finally:  # the scheduling given back even when the shutdown fails (a hook raising every cycle)
                self.clock.stop()
            if self._retained is not None:
                try:
                    retentive.save(self.retain, self._retained)
                except OSError as exc:  # the retentive memory cannot be written: the next run would lose it
                    self.result.alarms.append(Alarm(retentive.RETENTIVE_ERROR, f"retentive variables {self.retain}: "
                                                                                f"cannot be written ({exc.strerror})"))
            if self._fit_ahead is not None:
                if paced:
                    self.clock.idle_work = None
                self.result.fits_ahead = self._fit_ahead.close()
                self._fit_ahead = None
            if paced:
                gc.enable()
            if gc_before is not None:
                gc.set_threshold(*gc_before)
            gc.unfreeze()  # (B42: what was frozen for the run collectable again once it is over)
        if self._cut is not None:  # a second signal during the wait for standstill (B95): the caller's Ctrl-C
            raise self._cut
        return self._finish()

    def _start_fit_ahead(self, interp: Interpreter, program: Program, planner: Planner, paced: bool) -> None:
        """B86: in real time, a bench whose planner fits runs gets them worked out ahead by a forked child."""
        mode = self.fit_ahead or fit_ahead.mode()
        if planner._runs is None or mode == "off" or (mode == "auto" and not paced):
            return
        # Where the axes will stand, as far as known before power-up: a simulated axis's power-on position (a real
        # drive's may differ: the child starts again from where `begin` says)
        guess = {a.name: float(a.start) for a in self.bench.axes}
        self._fit_ahead = fit_ahead.start(interp, program, planner.cfg, guess, wait=mode == "wait")
        if self._fit_ahead is not None:
            planner._runs.memo = self._fit_ahead.memo
            if paced:  # its windows decoded a span at a time in the slacks (B98)
                self.clock.idle_work = self._fit_ahead.memo.work_part
            if mode == "auto":  # paced cycles have no time to wait: the first windows now
                self._fit_ahead.prefetch(PREFETCH_S)

    def power_up(self) -> bool:
        """Bring every drive to operation enabled, one state-machine step per cycle."""
        self.clock.prepare()  # real time asked for before the bus is in OP: its slaves' watchdogs run from there (E23)
        self.link.open()
        self._opened = True  # a link that failed to open is not cycled at shutdown (no 2nd alarm)
        self.clock.start(self.link)
        for m in self.masters:
            m.request(Target.ENABLED)
        limit = max(1, int(round(self.bench.enable_timeout / self.bench.cycle)))
        resets = self._power_up_reset = {}  # feedback() resets a fault the drive had before the run, once (B72)
        try:
            for _ in range(limit):
                self._exchange()
                if all(m.enabled for m in self.masters):
                    self.result.enable_cycles = self.cycle
                    return True
                if any(m.faulted and not (i in resets and self.cycle - resets[i] <= RESET_CYCLES)
                       for i, m in enumerate(self.masters)):
                    break
        finally:
            self._power_up_reset = None
        n_axes = len(self.axes)
        faulted = any(m.faulted for m in self.masters)  # the wait stopped at a fault: name the faulted drives
        for code, what, idx in ((0x0A07, "servo not ready", range(n_axes)),  # App. A: the axis is not servo ON
                                (0x0C06, "spindle not enabled", range(n_axes, len(self.masters)))):
            bad = [i for i in idx if not self.masters[i].enabled and (self.masters[i].faulted or not faulted)]
            if bad:
                states = ", ".join(f"{self._name(i)}: {self.masters[i].state.value}" for i in bad)
                self._alarm(Alarm(code, f"{what}: {states} after {self.cycle} cycles", axis=self._name(bad[0])))
        return False

    def make_planner(self) -> Planner:
        return Planner(self.bench.motion_config(), dict(zip(self.axes, self.actual.tolist())),
                       spindle_rpm=self.spindle_actual_rpm, spindle_angle=self.spindle_actual_angle,
                       spindle_index=self.spindle_index_angle, spindle_command=self.spindle_command_rpm)

    def run_events(self, events: Iterator[Event], planner: Planner | None = None) -> None:
        """Run events through a channel until it ends; a planner made before power-up (make_planner)
        takes over the axes' actual positions here."""
        if planner is None:
            planner = self.make_planner()
        else:
            planner.reset_position(dict(zip(self.axes, self.actual.tolist())))
        self.channel = ch = Channel(planner)
        if self.bench.param_groups:  # G05 P1-P20 switch to these, P0 back to the planner's own (language L25-1)
            ch.param_groups = {**self.bench.motion_configs(), 0: planner.cfg}
        ch.soft_limits = SoftLimits.for_bench(self.bench, getattr(self, "profile", None))
        ch.css_diameter = "X" in getattr(getattr(self, "profile", None), "diameter_axes", ("X",))  # G96 D
        if getattr(self, "_interp", None) is not None:  # G31 skip (issue 5)
            ch.on_skip = skip_hook(self._interp)
            ch.m96 = m96_link(self._interp)  # M2x019 program interruption
            ch.statement_budget = self._interp.budget
        for a in self.result.alarms:
            ch.alarms.append(a)
        ch.load(events)
        ch.cycle_start()
        t0 = self.time
        max_cycles = int(self.bench.max_time / self.bench.cycle)
        give_up = max_cycles + int(STANDSTILL_TIMEOUT / self.bench.cycle)
        stopping = False
        stretcher = Stretcher.for_runner(self)  # quiet cycles a stretch at a time (issue 17, decision B20)
        # real time on a field bus: the next cycle's refill and feed reads worked out in the slack (B60)
        self._ahead = bus_ahead = BusAhead.for_runner(self) if stretcher is None else None
        self._stretcher = stretcher  # the settle after the program takes stretches too (B38)
        try:  # the time the program ran, also when a bus alarm ends it from inside a cycle
            while ch.busy and self.cycle < give_up:
                if self.stop_request is not None and not stopping:
                    stopping = True  # along the path, jerk-limited, then flush: the NC's reset
                    ch.reset()
                if stretcher is not None and not stopping and stretcher.run(max_cycles - 1 - self.cycle):
                    continue  # it ended before max_cycles: the check below is for a stepped cycle
                # real time: this cycle's planner refill computed now, in the slack (decision B21)
                # ... unless the cycle before was long or the tick is near: then this cycle does it itself (B34)
                skip = stretcher is not None and stretcher.paced and not stopping and stretcher.skip_ahead()
                whole = not skip and not stopping and stretcher is not None and stretch_ahead.wanted(self)
                ahead = stretcher.ahead() if stretcher is not None and not stopping and not skip and not whole else None
                if skip:
                    self._exchange(None, bus_ahead=False)
                elif whole:  # the basic MLC: the cycle's whole channel step ahead, after its exchange (B46)
                    self._exchange(None, ahead=lambda tx: stretch_ahead.step_ahead(stretcher, tx))
                elif bus_ahead is not None and not stopping:
                    self._exchange(bus_ahead.step())
                elif ahead is None:
                    self._exchange()
                else:
                    self._exchange(ahead)
                if self.cycle == max_cycles:  # an alarm like any other: the channel stops along the path
                    self._end_reason = "max_time"
                    aux = ch.pending_aux  # an M/S/T block the NC waits on is where it stands (B57)
                    where = dict(line=aux.line, block=aux.block or None, program=aux.program) if aux is not None and aux.line \
                        else dict(line=self.line or None)
                    ch.raise_alarm(Alarm(MAX_TIME_ALARM, f"run exceeded {self.max_time_name} of {self.bench.max_time:g} s",
                                         **where))
        finally:
            self.result.program_time = self.time - t0
            self.result.param_groups = list(ch.group_log)
        self.result.finished = ch.state is RunState.FINISHED
        self._settle()
        self.result.stretched = stretcher.cycles if stretcher is not None else 0  # the settle's too (B38)

    # ---- spindle feedback for the planner (issue 5: feed per rev, CSS, threading) -----------
    def spindle_command_rpm(self) -> float:
        """The first spindle drive's signed speed command: the MLC's direction and speed, the G96 rpm
        under G96, times the spindle override (100 % in threads), within G50/G92 S and the spindle's
        max_rpm (motion decisions 30, 32). Feed per rev and threads use the measured speed instead."""
        ch = self.channel
        rpm = self.mlc.spindle.signed_rpm
        if ch is None:
            return rpm
        if ch.state is RunState.ALARM or ch.tap.record is not None:
            return 0.0  # the tapping interrupt status holds the spindle (0x0C09, decision M26-2)
        top = self.bench.spindles[0].max_rpm if self.bench.spindles else float("inf")
        return spindle_speed(rpm, ch.css_rpm, ch.spindle_max, top, ch.spindle_factor)

    def spindle_actual_rpm(self) -> float:
        """The first spindle drive's measured speed (signed rpm); the MLC's command without a spindle."""
        n = len(self.axes)
        if len(self.scales) <= n:
            return abs(self.spindle_command_rpm())
        return self.scales[n].drive_to_rpm(self.tx[n].velocity_actual)

    def spindle_actual_angle(self) -> float:
        """The first spindle's measured angle, cumulative degrees (position_actual, not wrapped)."""
        n = len(self.axes)
        return self.scales[n].to_units(self.tx[n].position_actual) if len(self.scales) > n else 0.0

    def spindle_index_angle(self) -> float:
        """Angle of the spindle encoder index from the drive's touch probe (0x60B8 bit 0 armed at
        power-up, 0x60B9 bit 1 latched, 0x60BA position); 0 until the index has been seen."""
        n = len(self.axes)
        if len(self.scales) <= n or not self.tx[n].touch_probe_status & 0x0002:
            return 0.0
        return self.scales[n].to_units(self.tx[n].touch_probe_pos1)

    def home_input(self, axis: str) -> tuple[bool, float] | None:
        """Home switch (0x60FD bit 2) and actual machine position of an axis; None without a switch."""
        i = self.axes.index(axis)
        if self.bench.axes[i].drive.home_switch is None:
            return None
        return bool(self.tx[i].digital_inputs & 0x4), float(self.actual[i])

    def shift_origin(self, axis: str, shift: float) -> None:
        """NC-side homing: machine coordinates of the axis move by `shift` against the drive counts."""
        i = self.axes.index(axis)
        self.origin[i] += shift
        self.actual[i] += shift
        self._commands[i] += shift

    def _skip_probe(self, ch: Channel) -> None:
        """G31 (issue 5): arm touch probe 1 (0x60B8 bit 0) on the axes whose drive has a probe while
        a skip move is pending; a latch (0x60B9 bit 1, position 0x60BA) is the skip input."""
        armed = ch.skip_armed
        latched: dict[str, float] = {}
        for i in self._probe_axes:
            ax = self.bench.axes[i]
            if armed and self.rx[i].touch_probe_function & 1 and self.tx[i].touch_probe_status & 0x0002:
                latched[ax.name] = self.scales[i].to_units(self.tx[i].touch_probe_pos1) + self.origin[i]
            self.rx[i].touch_probe_function = 0x0001 if armed else 0
        if latched:
            ch.skip(latched)

    # ---- the cycle ------------------------------------------------------------------------
    def _exchange(self, step: Callable[[Channel], object] | None = None, bus_ahead: bool = True,
                  ahead: Callable[[list[TxPdo]], Callable[[Channel], object] | None] | None = None) -> None:
        # Real time on the in-process bus: this cycle's drive models run before its wake-up, in the slack
        # (decision B21; not with bus_ahead False, B34); nothing between here and the tick reads or writes the
        # PDOs or the drives
        tx = self.link.exchange(self.rx) if self._bus_ahead and bus_ahead else None
        if tx is not None and ahead is not None:
            step = ahead(tx)  # the channel step on this feedback, ahead too where nothing before it can tell (B46)
        if tx is not None:
            self.clock.idle()  # B98: the lowest-rank work ahead, before the warm-up's reads (the tick does it too)
            left = self.clock.left_ns() - int(self.clock.config.busy_wait * 1e9) - WARM_AHEAD_NS
            if left > 0:  # sleep to just before the clock's own spin, so nothing runs between the reads and the tick
                self.clock.sleep(left * 1e-9)
            if self.clock.left_ns() > WARM_MIN_NS:
                warm(self, len(self.axes))  # reads only: the caches hold what the cycle reads first (B43)
        self.timing = self.clock.tick()
        if self._bus_work is not None:
            self._bus_work.tick()
        if self.timing.overrun:
            self._overrun()
        self._cycle(tx if tx is not None else self.link.exchange(self.rx), step)

    def _cycle(self, tx: list[TxPdo], step: Callable[[Channel], object] | None = None) -> None:
        """One cycle from its feedback on (a stretch, hil/stretch.py, hands in feedback it computed and, as
        `step`, the planner sample the channel step would return)."""
        self.tx = tx
        self.cycle += 1
        self.time += self.bench.cycle
        n_axes = len(self.axes)
        feedback(self, tx, n_axes)  # masters, alarms, actual positions (hil/cycle_lean.py)
        ch = self.channel if not self._planner_failed else None  # a failed NC is not stepped again
        hooks = self._hooks
        if hooks is None or hooks[0] is not self.link or hooks[1] is not self.mlc:  # what they offer, asked once
            hooks = self._hooks = (self.link, self.mlc, callable(getattr(self.link, "status", None)),
                                   hasattr(self.mlc, "bus_feedback"), hasattr(self.mlc, "bus_status"),
                                   callable(getattr(self.mlc, "spindle_drive", None)),
                                   getattr(self.mlc, "link", None) if hasattr(getattr(self.mlc, "link", None),
                                                                              "servo_off") else None)
        if ch is not None:
            # The link's state is read once per cycle: the drive status and the bus relays share it.
            status = self.link.status() if hooks[2] else None
            if hooks[3]:  # drive status for the MLC's special M/D (issue 8)
                self.mlc.bus_feedback(drive_status(self, status))
            if hooks[4] and status is not None:
                self.mlc.bus_status(status)  # M30000 / EIO relays from the bus state (issue 6)
            self.mlc.scan(ch)
            self._skip_probe(ch)
            sp = ch.step() if step is None else step(ch)
            relays = hooks[6]
            last = self._commands.tolist() if relays is not None and (relays.servo_off or self._servo_off) else None
            self._commands[:] = sp.positions  # type: ignore[attr-defined]
            if not self._winding_down:
                self.line = sp.line or self.line  # type: ignore[attr-defined]
            if relays is not None and (relays.mlc_axes or self._mlc_axes):
                mlc_axes.step(self, ch, relays)  # NC / MLC axis switching, the MLC's axis moves (M26-20)
            if last is not None:
                servo_relays.obey(self, ch, relays, last)  # the MLC's servo relays (decision M22-1)
            if ch.emergency and not self._braking:
                self._begin_quick_stop()  # E-stop: stop category 1, the drives brake on their own ramp
            elif self._braking and not ch.emergency and not self._planner_failed:
                self._reenable(ch)  # E-stop released and reset: servo on again where the axes stand
        following = ch is not None and not self._braking
        setpoints(self, following, n_axes)  # hil/cycle_lean.py
        winding = self._winding_down
        for k in range(n_axes, len(self.scales)):
            sc = self.scales[k]
            if winding:
                rpm = 0.0  # the run is over: spindles ramp down before their drives are disabled
            elif k == n_axes and ch is not None:  # G96 speed, override, G50/G92 S clamp (issue 5; decisions A39, 32)
                rpm = self.spindle_command_rpm()  # the speed is computed once, not also as below
            else:
                rpm = self.mlc.spindle.signed_rpm if (ch is not None and ch.state is not RunState.ALARM) else 0.0
            self.rx[k].target_velocity = sc.rpm_to_drive(rpm)
            if k == n_axes and ch is not None and hooks[5] and not winding:  # spindle ↔ C axis, M19: CSV ↔ CSP (issue 8)
                rx = self.rx[n_axes]
                rx.mode, deg, vel = self.mlc.spindle_drive(self)
                if deg is not None:
                    rx.target_position = sc.to_counts(deg)
                if vel is not None:
                    rx.target_velocity = sc.rpm_to_drive(vel)
        if self._servo_off >> n_axes:  # a spindle the MLC holds servo OFF gets no speed (M2x012, decision M23-2)
            servo_relays.hold_spindles(self)
        self.clock.written()  # the outputs the next exchange sends: the end of the cycle's work (decision B21)
        bus_work = self._bus_work
        if bus_work is not None and bus_work.realtime:  # where the clock ends the cycle's work: here in real time
            bus_work.written(self.cycle)
        if self.trace is not None:
            self.trace.write(self._row())
            self._row_cycle = self.cycle
        if self.on_cycle is not None:
            self.on_cycle(self)
        if self.progress is not None:
            self.progress.update(self)
        self.clock.done()
        if bus_work is not None and not bus_work.realtime:  # (lock-step: at done)
            bus_work.written(self.cycle)

    def _new_alarms(self) -> str:
        """Codes of the alarms raised since the previous row (by the bench or by the channel)."""
        ch_alarms = self.channel.alarms if self.channel is not None else []
        if not self.result.alarms and not ch_alarms:
            return ""  # the usual row: nothing to look through
        pool = self.result.alarms + ch_alarms
        new = [a for a in pool if id(a) not in self._seen_alarms]
        self._seen_alarms.update(id(a) for a in new)
        return ";".join(dict.fromkeys(a.code_text for a in new))

    def _overrun(self) -> None:
        """The previous cycle ran past this cycle's deadline: warn (counted) or alarm, per the bench."""
        if self.bench.realtime.overrun == "alarm" and not self._overrun_alarmed:
            self._overrun_alarmed = True
            self._alarm(Alarm(0x141F, f"cycle overrun: cycle {self.cycle} ran past the {self.bench.cycle * 1e3:g} ms "
                                      "period", line=self.line or None))

    def _row(self) -> list:
        return row(self, len(self.axes))  # hil/cycle_lean.py

    # ---- endings ---------------------------------------------------------------------------
    def _alarm(self, alarm: Alarm) -> None:
        if self.channel is not None:
            self.channel.raise_alarm(alarm)
        self.result.alarms.append(alarm)

    def _placed(self, alarm: Alarm) -> Alarm:
        """E35: a bus alarm (the link lost, a node gone silent) names where the program stood, as a drive's own
        alarm does: the block being executed (B100), else the trace's current line."""
        if alarm.line is not None:
            return alarm
        blk = self.channel.planner.active if self.channel is not None else None
        mv = blk.move if blk is not None else None
        if mv is not None and mv.line:
            return replace(alarm, line=mv.line, block=mv.block or None, program=mv.program)
        return replace(alarm, line=self.line) if self.line else alarm

    def _trace_failed(self, exc: OSError) -> None:
        """B97: the trace's first failed write (hil/write_guard.py) is an alarm; the channel stops along the path."""
        self._alarm(Alarm(TRACE_WRITE, f"trace {getattr(self.trace, 'path', '')} cannot be written "
                                       f"({exc.strerror or exc}): the run stops, the partial trace is removed",
                          line=self.line or None))

    def _begin_quick_stop(self) -> None:
        """Command every enabled drive's quick stop (CiA 402: it brakes on its own ramp, 0x6085). Until a
        drive takes it, its setpoint goes on at the speed it had (see _exchange)."""
        self._coast = [int(round(sc.drive_to_counts_per_s(tx.velocity_actual) * self.bench.cycle))
                       for tx, sc in zip(self.tx, self.scales)]
        self._braking = True
        for m in self.masters:
            if m.enabled:
                m.request(Target.QUICK_STOP)

    def _reenable(self, ch: Channel) -> None:
        """After an E-stop is released and reset: once the axes stand, enable the drives again and
        let the NC take over the actual position (the axes braked past the frozen setpoint)."""
        if not all(self._at_rest(i) for i in range(len(self.tx))):
            return
        ch.planner.reset_position(dict(zip(self.axes, self.actual.tolist())))
        self._braking = False
        for i, m in enumerate(self.masters):
            if not self._servo_off >> i & 1:  # an axis the MLC holds servo OFF stays off (M22-1)
                m.request(Target.ENABLED)

    def _quick_stop(self) -> None:
        """The planner itself failed: leave it alone and command every drive's quick stop; _shutdown
        waits for standstill, then disables."""
        if not getattr(self, "_opened", False):
            return
        self._planner_failed = True
        self._begin_quick_stop()
        for i, (rx, step) in enumerate(zip(self.rx[: len(self.axes)], self._coast)):
            rx.target_position += step  # the update the failed cycle did not make
            self._commands[i] = self.scales[i].to_units(rx.target_position) + self.origin[i]
        if self.trace is not None and getattr(self, "_row_cycle", None) != self.cycle:
            self.trace.write(self._row())  # the failed cycle's row: one row per cycle, alarm included
            self._row_cycle = self.cycle

    def _at_rest(self, i: int) -> bool:
        """Drive i stands (`stands`, on its rest counter and this cycle's feedback)."""
        return stands(self._rest[i], self.tx[i].following_error, self.masters[i].enabled)

    def _settle(self) -> None:
        """Keep cycling on the final setpoints until the axes stand still (or the settle time ends). Quiet cycles a
        stretch at a time (decision bench B38): a stretch ends after the first cycle the axes stand still."""
        total = int(self.bench.settle_time / self.bench.cycle)
        stretcher, done = self._stretcher, 0
        if stretcher is not None:
            stretcher.settling = True
        try:
            while done < total:
                c0 = self.cycle
                if stretcher is not None and stretcher.run(total - done):
                    done += self.cycle - c0
                else:
                    self._exchange()
                    done += 1
                if all(self._at_rest(i) for i in range(len(self.axes))):
                    break
        finally:
            if stretcher is not None:
                stretcher.settling = False

    def _standstill(self) -> None:
        """Cycle until every axis stands (the channel's stop along the path, or the drives' quick
        stop, runs meanwhile), at most STANDSTILL_TIMEOUT: drives are disabled only at standstill."""
        # A drive whose feedback froze for FROZEN_S (it left the bus: same position, same non-zero
        # speed) is not waited for: it brakes on its own fault reaction, unseen.
        self._winding_down = True
        self.line = 0  # the rows after the program name no line: the bench is bringing things to rest
        frozen = {i: 0 for i in range(len(self.tx))}
        gone = max(1, int(FROZEN_S / self.bench.cycle))
        last = [(tx.position_actual, tx.velocity_actual) for tx in self.tx]
        for _ in range(int(STANDSTILL_TIMEOUT / self.bench.cycle)):
            if all(self._at_rest(i) or frozen[i] >= gone for i in range(len(self.tx))):
                return
            self._exchange()
            for i, tx in enumerate(self.tx):
                now = (tx.position_actual, tx.velocity_actual)
                frozen[i] = frozen[i] + 1 if now == last[i] else 0
                last[i] = now

    def _shutdown(self) -> None:
        """Wait for standstill, then disable every drive in order (operation enabled → ready →
        switch on disabled), close the bus and finish the trace. A second signal (the run was
        interrupted) disables at once; so does one while waiting for standstill, its KeyboardInterrupt kept for
        run_program to raise once the run is wound up (B95)."""
        try:
            try:
                if getattr(self, "_opened", False) and getattr(self, "_end_reason", None) != "interrupted":
                    try:
                        self._standstill()
                    except KeyboardInterrupt as exc:  # no more waiting: disabled now
                        self._end_reason, self._cut = "interrupted", exc
                self.disabling = True  # standing: a further signal no longer cuts this short (hil/stop_signals.py)
                for m in self.masters:
                    m.request(Target.DISABLED)
                for _ in range(20 if getattr(self, "_opened", False) else 0):
                    self._exchange()
                    if all(m.state in (State.SWITCH_ON_DISABLED, State.READY_TO_SWITCH_ON, State.FAULT)
                           for m in self.masters):
                        break
            except BusError as exc:
                self.result.alarms.append(self._placed(exc.alarm))
            except KeyboardInterrupt as exc:  # one more signal in the disable's own cycles: the bus closes now
                self._end_reason, self._cut = "interrupted", exc
        finally:  # the bus closed and the trace finished whatever cut the above short (a third signal)
            try:
                self.link.close()
                self._bus_closed = True
            finally:
                self.clock.stop()
                if self.trace is not None:
                    self.trace.close(end=self._end_record())
                if self.progress is not None:
                    self.progress.close()

    def request_stop(self, reason: str) -> None:
        """Stop the run under control at the next cycle (a signal, or a caller's own reason)."""
        if self.stop_request is None:
            self.stop_request = reason
            self.result.stopped_by = reason

    def _end_record(self) -> dict:
        """How the run ended, for the trace's metadata: reason, first alarm, last cycle."""
        pool = self.result.alarms + (self.channel.alarms if self.channel is not None else [])
        # "aborted": the NC left the program without an alarm, a reset flushed it (decision B11)
        done = "completed" if self.result.finished or self.channel is None else "aborted"
        reason = getattr(self, "_end_reason", None) or self.stop_request or ("alarm" if pool else done)
        return {"reason": reason, "alarm": pool[0].code_text if pool else None,
                "alarm_line": pool[0].line if pool else None, "cycle": self.cycle, "t": round(self.time, 9),
                "complete": reason != "interrupted", "bus": "closed" if self._bus_closed else "open",
                **({"warnings": [w.as_dict() for w in self.warnings]} if getattr(self, "warnings", None) else {})}

    def _finish(self) -> RunResult:
        r = self.result
        r.cycles = self.cycle
        r.sim_time = self.time
        r.final = dict(zip(self.axes, self.actual.tolist()))
        c = self.clock
        r.realtime = c.realtime
        r.overruns = c.overruns
        r.granted = str(c.granted)
        r.timing = {"jitter": c.jitter.summary(), "exec": c.exec.summary()}
        if isinstance(c, RealTimeClock):
            r.timing["latency"] = c.latency.summary()
            r.timing["between"] = c.between.summary()  # work in the periods' slack (decision B21)
        if self._bus_work is not None:
            r.timing.update(self._bus_work.summary())  # bus wait, master work (decision E25)
        if self.channel is not None:
            for a in self.channel.alarms:
                if a not in r.alarms:
                    r.alarms.append(a)
        return r

    def _name(self, i: int) -> str:
        n = len(self.axes)
        return self.axes[i] if i < n else self.bench.spindles[i - n].name


def stands(rest: int, following_error: int, enabled: bool) -> bool:
    """A drive stands: feedback unchanged for REST_CYCLES and, while it follows the NC's setpoint, no following
    error left (a drive braking on its own quick stop has none to meet). BenchRunner._at_rest, and a settle
    stretch's end (hil/stretch.py, B38)."""
    return rest >= REST_CYCLES and (following_error == 0 or not enabled)


PREFETCH_S = 1.0  # B86: before a real-time run's power-up, the child's first windows are waited for this long at most


# B150: a lock-step run's young generation collected every 50,000 new container objects instead of 700 (CPython's
# default): the run makes ≈ 10 containers a block that reference counting frees, and the collector's 70-odd young and
# 6 middle walks of a 5,000-block CAM run cost ≈ 2.5 % of its instructions for almost no cyclic garbage (_quiet_gc);
# left on, not off, so that a run that does make cycles (a user's script or MLC) still has them collected.
LOCKSTEP_GEN0 = 50_000


def _rare_gc() -> tuple[int, ...] | None:
    """Raise the collector's young threshold for a lock-step run; the thresholds it had, to restore at the end (None:
    the collector is off, left as the caller has it)."""
    if not gc.isenabled():
        return None
    before = gc.get_threshold()
    gc.set_threshold(max(before[0], LOCKSTEP_GEN0), *before[1:])
    return before


def _quiet_gc() -> None:
    """No cyclic garbage collection while cycles are paced. A generation-2 collection took ≈ 10 ms
    and a generation-1 ≈ 1.4 ms in the middle of a CAM program (20 ms overruns at a 2 ms cycle),
    while a whole run leaves almost no cyclic garbage (0 objects on a CAM program, ≤ 0.02 per cycle
    on the lathe examples: reference counting frees the rest); what there is is collected when the
    run ends. Everything built so far is frozen out of later collections."""
    gc.collect()
    gc.freeze()
    gc.disable()


def _preload(bench: Bench) -> None:
    """Before cycles are paced, import every module the NC, MLC and bench may import on first use, run
    a tiny program offline through the interpreter and planner on this bench's settings and index
    the App. B signal names: first-use imports (cutter compensation stream, preview window, the MLC
    bridge …) and first calls (ruckig calculators, sampling, signal lookups) cost milliseconds and
    overran the first program cycle."""
    import importlib
    import pkgutil

    import hil
    import mlc
    import nc
    from nc.motion.offline import run

    for pkg in (nc, mlc, hil):
        for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
            if info.name.endswith("__main__"):
                continue
            try:
                importlib.import_module(info.name)
            except ImportError:  # an optional part this machine lacks is not used on this bench either
                pass
    here = {a: 0.0 for a in bench.axis_names}
    first = bench.axis_names[0]
    profile = make_profile(bench.profile, bench.axis_names, bench.params)
    text = f"G00 {first}0.01\nG00 {first}0\nM30\n"  # G00 reads the same in every profile
    rapids = [ev for ev in Interpreter(profile, here).run(parse_program(text, name="warm-up")) if isinstance(ev, Move)]
    feeds = [replace(mv, kind="line", feed=600.0) for mv in rapids]
    run([*feeds, *rapids], bench.motion_config(), here, keep=False)
    from mlc.signals import _by_name

    _by_name(1)
    load_fit()  # imported on first use otherwise (nc/motion/spline_feed.py)
