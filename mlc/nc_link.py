"""The NC side of Delta's special M/D interface for one channel, driven by the real `nc.channel`.

Every scan the NC first reads what the MLC wrote in its previous scan (commands: modes, cycle
start, feed hold, reset, E-stop, overrides, the M/S/T finish, jog/INC/MPG/home relays) and applies
it to the channel and the manual-motion generator, then publishes its status (mode bits, running,
hold, strobes with their code data, drive and bus status). The MLC user scan runs after that and
sees the status of this cycle. The decisions behind the handshake are in docs/decisions/mlc.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mlc.manual_alarms import HardLimitLatch, home_mode, servo_off_stop, servo_refused, tap_locked
from mlc.drive_status import DriveStatus, write_drive_outputs
from mlc.memory import DeviceMemory
from mlc.signals import d2, d3, m2, m3
from nc.alarms import Alarm
from nc.softlimits import ManualLimitLatch
from nc.channel import Channel, RunState
from nc.manual import ManualMotion
from nc.moves import Aux

AUTO, EDIT, MDI, MPG, JOG, RAPID, INC, HOME = range(8)
MODE_NAMES = ("AUTO", "EDIT", "MDI", "MPG", "JOG", "RAPID", "INC", "HOME")
MANUAL_MODES = (MPG, JOG, RAPID, INC, HOME)
_MODE_BITS = {k: bytes(1 if j == k else 0 for j in range(8)) for k in range(8)}  # mode → M3x000…M3x007
_NO_MODE = bytes(8)
SYSTEM_M = {0, 1, 2, 30, 98, 99}  # never handed to the MLC (NC5 §3.8.1)
ESTOP_ALARM = 0x0401
SPINDLE_ALARM = 0x0C0A


@dataclass
class ChannelLink:
    mem: DeviceMemory
    x: int = 1  # channel digit
    axes: tuple[str, ...] = ("X", "Z")
    manual: ManualMotion | None = None
    unit: float = 0.001  # N9.013: the INC/MPG unit (mm per count of D2x014 / per detent × ratio)
    jog_speed: float = 1000.0 / 60.0  # N2.030: JOG speed at 100 %, mm/s
    spindle_max_rpm: float = 6000.0
    tool_range: tuple[int, int] = (0, 9999)  # T codes inside the magazine range get a strobe (B.2.2.1)
    mode: int = AUTO
    variables: Any = None  # the interpreter's variable store, for #25000–#25511 and #20020
    interp: Any = None  # the interpreter: its block skip switch follows M2x010 (decision M21-1)
    alarms: list[Alarm] = field(default_factory=list)  # raised by this layer (E-stop, user alarms …)
    # handshake state
    _handed: Aux | None = None  # the code the strobe currently stands for
    _strobe: int | None = None  # index 64/65/66 of the raised strobe
    _system_hold: Aux | None = None  # M00 / M01 waiting for cycle start
    _last_done: Aux | None = None  # the code this layer completed last (held, so its id is never reused)
    _prev: dict[int, bool] = field(default_factory=dict)  # previous level of edge-triggered relays
    _mpg_last: int | None = None
    _estop: bool = False
    _reset_pending: bool = False
    _alarms_seen: set[int] = field(default_factory=set)
    _var_cache: dict = field(default_factory=dict)
    _var_plan: tuple | None = None  # (exchange, legacy, ((lo, kind, first, count), …)): fixed per exchange
    _drive_split: tuple | None = None  # (drives list, its length, axes + spindles (32 at most), spindles (8 at most)): mlc/drive_status.py
    _cmd_levels: bytes | None = None  # M2x000…M2x019 of the last cycle whose edges fired nothing
    # the servo relays (decision M22-1), obeyed by the runner (hil/servo_relays.py): bit i = axis i asked OFF, by
    # M2x012 OFF (`servo_all`) or its M2x272+i
    servo_off: int = 0
    servo_all: bool = False
    _servo_levels: bytes | None = None  # M2x272… of the channel's axes as last read
    # NC / MLC axis switching (hil/mlc_axes.py): bit i = M2x432+i ON, the MLC asks for axis i
    mlc_axes: int = 0
    _mlc_levels: bytes | None = None  # M2x432… of the channel's axes as last read
    resets: int = 0  # NC resets taken (M2x004 edges): an MLC axis's move stops at each (decision M26-24)
    _servo_refused: int = 0  # bit i: a manual command of axis i, held OFF, was refused with 0x0A07 (M23-1)
    _spindle_levels: bytes = bytes(8)  # M2x711, M2x727, … as the last scan saw them (== their `_prev`)
    _tap_levels: bool = False  # M2x080 or M2x707 was ON last scan (their edges are looked for then)
    _tap_refused: bool = False  # a manual command was refused under the tapping interrupt status (until a reset)
    _program_end: int | None = None
    _mode_switch_cycles: int = 0
    handshake_log: list[tuple[int, str, float]] = field(default_factory=list)  # (cycle, kind, value)
    limit_latch: ManualLimitLatch = field(default_factory=ManualLimitLatch)  # App. A 0x0A01-0x0A04 in manual
    hard_limits: HardLimitLatch = field(default_factory=HardLimitLatch)  # App. A 0x0402 / 0x0A06 in manual
    drives: list[DriveStatus] | None = None  # this cycle's drive status (Mlc.bus_feedback)
    cycle: int = 0

    # ---- helpers --------------------------------------------------------------------------------
    # Called dozens of times per scan: the relay address (m2/m3) is computed inline and the bit read
    # or written in the byte array itself.
    def _m2(self, i: int) -> bool:
        return bool(self.mem.m[20000 + 1000 * self.x + i])

    def _set3(self, i: int, on: bool) -> None:
        self.mem.m[30000 + 1000 * self.x + i] = 1 if on else 0

    def _rising(self, address: int) -> bool:
        now = bool(self.mem.m[address])
        before = self._prev.get(address, False)
        self._prev[address] = now
        return now and not before

    def _raise(self, ch: Channel | None, alarm: Alarm) -> None:
        self.alarms.append(alarm)
        if ch is not None:
            ch.raise_alarm(alarm)

    # ---- NC reads the MLC's outputs ----------------------------------------------------------------
    def nc_inputs(self, ch: Channel) -> None:
        self.cycle += 1
        b2 = 20000 + 1000 * self.x  # M2x000
        m = self.mem.m
        # the usual scan asks neither: E-stop low now and before, no mode switch counting down or asked for
        if m[b2 + 13] or self._estop:
            self._estop_input(ch)
        if self._mode_switch_cycles or self.mem.words[b2] != self.mode:
            self._mode_input(ch)
        levels = m[b2:b2 + 20]
        if levels == self._cmd_levels:  # M2x000…M2x019 as last cycle, which fired nothing: no edge
            if self._handed is not None:  # no code handed over: no finish to wait for
                self._finish_input(ch)
        else:
            fired = False
            if self._rising(b2 + 4):
                self._reset(ch)
                fired = True
            if self._rising(b2 + 1):
                self._feed_hold(ch)
                fired = True
            if self._rising(b2):
                self._cycle_start(ch)
                fired = True
            self._finish_input(ch)
            if self._rising(b2 + 19):
                fired = True
                if callable(getattr(ch, "interrupt", None)):
                    ch.interrupt()  # M2x019: M96 program interruption (nc.interrupt)
            # kept only when no handler ran in between: then `_prev` holds exactly these levels
            self._cmd_levels = None if fired else bytes(levels)
            if self.servo_all is bool(levels[12]):  # M2x012 changed: the mask below is worked out again
                self.servo_all, self._servo_levels = not levels[12], None
        per_axis = m[b2 + 272:b2 + 272 + len(self.axes)]  # M2x272+i: one slice compare per scan
        if per_axis != self._servo_levels:
            self._servo_levels = bytes(per_axis)
            self.servo_off = sum(1 << i for i, on in enumerate(per_axis) if on or self.servo_all)
        switch = m[b2 + 432:b2 + 432 + len(self.axes)]  # M2x432+i: one slice compare per scan
        if switch != self._mlc_levels:
            self._mlc_levels = bytes(switch)
            self.mlc_axes = sum(1 << i for i, on in enumerate(switch) if on)
        self._overrides(ch)
        if m[b2 + 80] or m[b2 + 707] or self._tap_levels:
            self._tap_input(ch)
        self._spindle_alarm(ch)
        self._user_alarms(ch)
        self._exchange_variables(ch)
        if self.manual is not None:
            self._manual(ch)

    def _estop_input(self, ch: Channel) -> None:
        on = bool(self.mem.m[20013 + 1000 * self.x])  # M2x013
        if on and not self._estop:
            alarm = Alarm(ESTOP_ALARM, "emergency stop signal is triggered (M2x013)")
            self.alarms.append(alarm)
            ch.emergency_stop(alarm)
            if self.manual is not None:
                self.manual.halt()
            self._drop_handshake()
        self._estop = on

    def _mode_input(self, ch: Channel) -> None:
        want = self.mem.words[20000 + 1000 * self.x]  # D2x000
        self._mode_switch_cycles = max(0, self._mode_switch_cycles - 1)
        if want == self.mode or want > HOME:
            return
        # A running program or a moving manual axis keeps its mode (decision D8).
        if ch.busy or (self.manual is not None and self.manual.busy):
            return
        self.mode = want
        self._mode_switch_cycles = 1
        if want in MANUAL_MODES and self.manual is not None:
            self.manual.take_over(ch.planner.position)
        if want == MPG:
            self._mpg_last = None

    def _reset(self, ch: Channel) -> None:
        self.resets += 1
        self._drop_handshake()
        self._program_end = None
        if self.manual is not None:
            self.manual.stop()
        reset = getattr(ch, "reset", None)
        if callable(reset):
            reset()
        else:
            ch.planner.stop()
            ch.pending_aux = None
            ch._deferred_aux = None
            ch.events = None
            ch.end = None
            ch.alarms.clear()
            ch.state = RunState.IDLE
        if not self._estop and hasattr(ch, "emergency"):
            ch.emergency = False  # E-stop released, then reset: the bench enables the drives again
        self.alarms.clear()
        self._alarms_seen.clear()
        self._servo_refused = 0
        self._tap_refused = False
        self._reset_pending = True
        for alarm in self.limit_latch.reset() + self.hard_limits.reset():  # still on a limit: reset does not clear
            self._raise(ch, alarm)

    def _feed_hold(self, ch: Channel) -> None:
        hold = getattr(ch, "feed_hold", None)
        if callable(hold):
            hold()
        if self.manual is not None and self.mode in MANUAL_MODES:
            self.manual.stop()

    def _cycle_start(self, ch: Channel) -> None:
        if self._estop or self.mode not in (AUTO, MDI):
            return
        self._program_end = None
        self._reset_pending = False
        if self._system_hold is not None:  # M00 / M01 released by cycle start (ambiguity C9)
            aux, self._system_hold = self._system_hold, None
            self._set3(37, False)
            self._set3(38, False)
            self._complete(ch, aux)
            ch.released_by_cycle_start()
            return
        aux = ch.pending_aux
        if aux is not None and aux is not self._last_done and aux.kind == "M" \
                and (aux.value == 0 or (aux.value == 1 and self._m2(9))):
            # the NC holds at M00/M01 since its last step; this scan's outputs would publish M3x037/M3x038.
            # A press in this very scan releases it too, as the NC itself is on hold (decision bench B56)
            self._complete(ch, aux)
            ch.released_by_cycle_start()
            return
        ch.cycle_start()  # starts, resumes after feed hold, or runs the next single block

    def _finish_input(self, ch: Channel) -> None:
        if self._handed is None:
            return
        if ch.pending_aux is not self._handed:  # reset / alarm flushed the code: abort the handshake
            self._drop_handshake()
            return
        if self._m2(16):
            self.handshake_log.append((self.cycle, "FIN", self._handed.value))
            aux = self._handed
            self._drop_handshake()
            self._complete(ch, aux)

    def _complete(self, ch: Channel, aux: Aux) -> None:
        self._last_done = aux
        if ch.pending_aux is aux:
            ch.finish_aux()

    def _drop_handshake(self) -> None:
        if self._strobe is not None:
            self._set3(self._strobe, False)
        self._strobe = None
        self._handed = None
        if self._system_hold is not None:
            self._system_hold = None
            self._set3(37, False)
            self._set3(38, False)

    def _overrides(self, ch: Channel) -> None:
        """Overrides and program-flow switches are levels: applied whenever they differ from the channel."""
        w, m, b2 = self.mem.words, self.mem.m, 20000 + 1000 * self.x
        # written out, not a loop over (name, value) tuples: five compares every cycle
        v: float | bool = min(w[b2 + 2], 150) / 100.0  # 0–150 %
        if getattr(ch, "feed_override", v) != v:
            ch.feed_override = v
        v = w[b2 + 4] / 100.0
        if getattr(ch, "rapid_override", v) != v:
            ch.rapid_override = v
        v = w[b2 + 26] / 100.0  # D2x026, applied by the NC (decisions 32)
        if getattr(ch, "spindle_override", v) != v:
            ch.spindle_override = v
        v = bool(m[b2 + 5])
        if getattr(ch, "dry_run", v) != v:
            ch.dry_run = v
        v = bool(m[b2 + 8])
        if getattr(ch, "single_block", v) != v:
            ch.single_block = v
        v = bool(m[b2 + 26])  # M2x026 M99 Call Stop: a level, read when the main program's M99 is (M25-1)
        if getattr(ch, "m99_call_stop", v) != v:
            ch.m99_call_stop = v
        ip = self.interp  # M2x010: '/' blocks the interpreter reads from now on are skipped (decision M21-1)
        if ip is not None and ip.block_skip != (v := bool(m[b2 + 10])):
            ip.block_skip = v

    def _tap_input(self, ch: Channel) -> None:
        """App. B M2x080 "Canceling Tapping Interrupt Status" (rising edge: the status ends, nothing moves) and
        M2x707 "1st Spindle Retraction After Tapping" (rising edge: the G84.48 retraction, the channel idle in
        AUTO/MDI, no E-stop). Decisions M26-6, M26-7."""
        b2 = 20000 + 1000 * self.x
        cancel, retract = self._rising(b2 + 80), self._rising(b2 + 707)
        self._tap_levels = bool(self.mem.m[b2 + 80] or self.mem.m[b2 + 707])
        tap = getattr(ch, "tap", None)
        if tap is None or not tap.holds or self._estop:
            return
        if cancel and ch.tap_retraction is None:
            tap.clear("M2x080")
        elif retract and not ch.busy and ch.state is not RunState.ALARM and self.mode in (AUTO, MDI) \
                and (self.manual is None or not self.manual.busy):
            ch.tap_retract(how="M2x707")

    def _spindle_alarm(self, ch: Channel) -> None:
        m, prev = self.mem.m, self._prev
        first = m2(self.x, 711)
        levels = m[first:first + 16 * 8:16]
        if levels == self._spindle_levels:
            return  # the same levels as the last scan: no edge, and `_prev` already holds them
        self._spindle_levels = bytes(levels)
        for a in range(first, first + 16 * 8, 16):  # M2x711, M2x727, … (spindles 1–8)
            k = (a - first) // 16
            if not m[a] and not prev.get(a, False):
                continue  # low now and before: no edge, nothing to remember (what _rising would find)
            if self._rising(a):
                self._raise(ch, Alarm(SPINDLE_ALARM, f"MLC activated the alarm of spindle {k + 1}"))

    def _user_alarms(self, ch: Channel) -> None:
        if not self._alarms_seen and self.mem.no_alarms():
            return  # none active, none before: the usual case (DeviceMemory.no_alarms)
        active = set(self.mem.active_alarms())
        for n in sorted(active - self._alarms_seen):
            self._raise(ch, Alarm(f"A{n}", f"MLC user-defined alarm A{n}"))
        self._alarms_seen = active

    def _exchange_variables(self, ch: Channel) -> None:
        """#25000–#25255 mirror the MLC's M2x128…/D2x128… (re-sent only when they change);
        #25256–#25511 reach M3x128…/D3x128… as the program writes them (`on_write` hook).
        #20020 macro alarms are raised by the interpreter itself."""
        v = self.variables
        ex = getattr(v, "mlc", None)
        if ex is None:
            return
        if ex.on_write is None:
            ex.on_write = self._variable_written
        mem, cache = self.mem, self._var_cache
        legacy = getattr(ex, "legacy", False)
        plan = self._var_plan
        if plan is None or plan[0] is not ex or plan[1] != legacy:  # the devices of the ranges, named once
            ranges = []
            for (lo, hi, is_bit) in ex.input_ranges:
                dev = ex.device(lo, self.x)
                ranges.append((lo, dev[0], int(dev[1:]), hi - lo + 1))
            plan = self._var_plan = (ex, legacy, tuple(ranges))
        for lo, kind, first, count in plan[2]:
            raw = mem.m[first:first + count] if kind == "M" else mem.word_bytes(first, count)
            key = (lo, kind)
            if cache.get(key) == raw:
                continue
            cache[key] = bytes(raw)
            for k in range(count):
                ex.set_input(lo + k, float(mem.bit(first + k)) if kind == "M" else float(mem.s16(first + k)))

    def _variable_written(self, number: int, value: float) -> None:
        ex = self.variables.mlc
        dev = ex.device(number, self.x)
        n = int(dev[1:])
        if dev[0] == "M":
            self.mem.set_bit(n, value != 0)
        else:
            self.mem.set_s16(n, max(-32768, min(32767, int(value))))  # truncated toward zero (B.3.6.4)

    # ---- manual motion ----------------------------------------------------------------------------
    def _manual(self, ch: Channel) -> None:
        mm, x = self.manual, self.x
        assert mm is not None
        limits = getattr(ch, "soft_limits", None)
        # The windows matter only to manual moves and their latches: not computed every automatic cycle.
        if limits is not None and not (self.mode in MANUAL_MODES or mm.clamped or self.limit_latch.latched):
            limits = None
        windows = {}
        m, b2 = self.mem.m, 20000 + 1000 * x
        for i, a in enumerate(self.axes):
            st = mm.axes[a]
            st.lock_pos = bool(m[b2 + 336 + i])
            st.lock_neg = bool(m[b2 + 352 + i])
            st.soft_limit_disabled = False  # M2x368 turns off the 1st segment only (the window below)
            if limits is not None:  # the bench's soft_limits and G10 L21 clamp the manual moves too
                windows[a] = low, high = self.limit_latch.window(limits, a, not self._m2(368 + i))
                st.soft_min, st.soft_max = (low[0] if low else None), (high[0] if high else None)
        if self.mlc_axes:  # an axis the MLC asks for takes no manual command: both ways interlocked (M26-29)
            for i, a in enumerate(self.axes):
                if self.mlc_axes >> i & 1:
                    mm.axes[a].lock_pos = mm.axes[a].lock_neg = True
        if self.drives is not None:
            for alarm in self.hard_limits.step(mm, self.axes, self.drives):
                self._raise(ch, alarm)
        if self._estop or self.mode not in MANUAL_MODES or ch.busy:
            return
        if ch.tap.record is not None:  # an interrupted tap: no manual motion (0x0270, decision M26-2)
            tap_locked(self, ch)
            return
        off = self.servo_off  # axes the MLC holds servo OFF take no manual command (App. A 0x0A07, M23-1)
        if off or self._servo_refused:
            servo_off_stop(self, ch, mm, off)
        pct = self.mem.u16(d2(x, 6))
        jog = self.jog_speed * pct / 100.0
        if self.mode in (JOG, RAPID):
            for i, a in enumerate(self.axes):
                fwd, rev = self._m2(384 + i), self._m2(400 + i)
                if off >> i & 1:
                    if fwd or rev:
                        servo_refused(self, ch, i, "JOG")
                    continue
                speed = jog if self.mode == JOG else mm.cfg.limit(a).max_velocity * self.mem.u16(d2(x, 4)) / 100.0
                mm.jog(a, (1 if fwd else 0) - (1 if rev else 0), speed)
        elif self.mode == INC:
            step = self.mem.u32(d2(x, 14)) * self.unit
            for i, a in enumerate(self.axes):
                fwd, rev = self._rising(m2(x, 384 + i)), self._rising(m2(x, 400 + i))
                if off >> i & 1:
                    if fwd or rev:
                        servo_refused(self, ch, i, "an INC step")
                    continue
                if fwd:
                    mm.move_by(a, step, jog)
                if rev:
                    mm.move_by(a, -step, jog)
        elif self.mode == MPG:
            count = self.mem.u16(d3(0, 4))
            if self._mpg_last is None:
                self._mpg_last = count
            delta = (count - self._mpg_last + 0x8000) % 0x10000 - 0x8000  # 16-bit counter wraps
            self._mpg_last = count
            i = self.mem.u16(d2(x, 8))
            if delta and i < len(self.axes) and off >> i & 1:
                servo_refused(self, ch, i, "MPG pulses")
            elif delta and i < len(self.axes):
                mm.move_by(self.axes[i], delta * self.mem.u16(d2(x, 9)) * self.unit)
        elif self.mode == HOME:
            home_mode(self, ch, mm)  # the home triggers, and App. A 0x1603 (mlc/manual_alarms.py)
        pos = mm.step()
        for i, a in enumerate(self.axes):
            if a in windows and (a in mm.clamped or a in self.limit_latch.latched):
                alarm = self.limit_latch.update(a, float(pos[i]), *windows[a], a in mm.clamped)
                if alarm is not None:
                    self._raise(ch, alarm)
        if ch.planner.idle:
            ch.planner.position[:] = pos

    # ---- NC publishes its status -------------------------------------------------------------------
    def nc_outputs(self, ch: Channel, drives: list[DriveStatus] | None = None) -> None:
        x, mem = self.x, self.mem
        m = mem.m
        b3 = 30000 + 1000 * x  # M3x000: the relays below are written straight into the bit array
        mode = self.mode
        m[b3:b3 + 8] = _MODE_BITS.get(mode, _NO_MODE)  # M3x000…M3x007: one slice, not eight writes
        m[b3 + 32] = 1 if self._mode_switch_cycles > 0 else 0
        if ch.pending_aux is not None:  # nothing to hand over otherwise (the usual cycle)
            self._handshake_output(ch)
        if ch.css_rpm is not None:
            self._css_output(ch)
        state = ch.state
        held = state is RunState.HOLD
        running = state in (RunState.RUNNING, RunState.WAIT_AUX) and self._system_hold is None
        m[b3 + 16] = 1 if running else 0
        m[b3 + 17] = 1 if held else 0
        m[b3 + 18] = 1 if m[20000 + 1000 * x + 13] else 0  # M3x018 follows the E-stop input M2x013
        if self._reset_pending and ch.planner.idle:
            m[b3 + 19] = 1
        elif not self._reset_pending:
            m[b3 + 19] = 0
        m[b3 + 31] = 1 if getattr(ch, "interrupt_active", False) else 0  # M3x031: M96 in execution
        m[b3 + 707] = 1 if getattr(ch, "rigid_tapping", False) else 0  # M3x707: rigid tapping (decision M26-5)
        m[b3 + 25] = 1 if state is RunState.ALARM or self.alarms and any(not isinstance(a.code, str) for a in self.alarms) else 0
        m[b3 + 40] = 0 if mem.no_alarms() else 1  # any user alarm active
        block_stop = state is RunState.BLOCK_STOP
        m[b3 + 24] = m[b3 + 39] = 1 if block_stop else 0
        if state is RunState.FINISHED and ch.end is not None and self._program_end is None:
            self._program_end = ch.end.code
        end = self._program_end
        m[b3 + 21] = 1 if end is not None and end != 99 else 0
        m[b3 + 22] = 1 if end == 2 else 0
        m[b3 + 23] = 1 if end == 30 else 0
        m[b3 + 47] = 1 if end == 99 else 0  # M3x047: stopped at M99 by M2x026, until cycle start or reset (M25-1)
        m[30080 + x - 1] = 1  # M3008x: this channel exists
        if drives is not None:
            self._drive_outputs(drives, ch)
        if self.manual is not None:
            mm, pos = self.manual, ch.planner.position
            pos = pos.tolist() if isinstance(pos, np.ndarray) else pos  # plain floats: no numpy scalar per axis
            for i, ax in enumerate(self.axes):
                st = mm.axes[ax]
                m[b3 + 320 + i] = 1 if st.homed else 0
                m[b3 + 336 + i] = 1 if st.home_done else 0
                m[b3 + 352 + i] = 1 if abs(pos[i]) < 1e-6 else 0
        mem.set_u32(b3 + 320, len(ch.planner.queue))  # D3x320

    def _handshake_output(self, ch: Channel) -> None:
        aux = ch.pending_aux
        if aux is None or aux is self._handed or aux is self._system_hold or aux is self._last_done:
            return
        x, mem = self.x, self.mem
        if aux.kind == "G900":
            p, q = int(aux.args.get("P", 0)), aux.args.get("Q", 0.0)
            if 30200 <= p <= 30399:  # out of range is ignored (ambiguity C5)
                mem.set_bit(p, q != 0)
            self._complete(ch, aux)
            return
        if aux.kind == "M" and int(aux.value) in SYSTEM_M:
            code = int(aux.value)
            if code == 0 or (code == 1 and self._m2(9)):
                self._system_hold = aux
                self._set3(37 if code == 0 else 38, True)
                self.handshake_log.append((self.cycle, f"M{code:02d}", aux.value))
            else:
                self._complete(ch, aux)
            return
        if self._m2(11):  # M, S, T lock: the code is not handed over, the block's motion still runs
            self._complete(ch, aux)
            return
        if aux.kind == "T" and not (self.tool_range[0] <= int(aux.value) <= self.tool_range[1]):
            self._complete(ch, aux)
            return
        if aux.kind == "S" and aux.args.get("max"):  # G50/G92 S: a speed limit the NC keeps, no S code
            self._complete(ch, aux)
            return
        if self._m2(16):
            return  # the previous finish is still ON: the next strobe waits for it to drop
        if aux.kind == "M":
            mem.set_u32(d3(x, 48), int(aux.value))
            self._strobe = 64
        elif aux.kind == "S":
            rpm = abs(aux.value)
            mem.set_u32(d3(x, 50), int(round(rpm)))
            mem.set_f32(d3(x, 24), rpm)
            self._strobe = 65
        else:
            mem.set_u32(d3(x, 52), int(aux.value))
            mem.set_u16(d3(x, 37), int(aux.value))
            self._strobe = 66
        self._handed = aux
        self._set3(self._strobe, True)
        self.handshake_log.append((self.cycle, aux.kind, aux.value))

    def _css_output(self, ch: Channel) -> None:
        """Under G96 the speed command D3x024 is the rpm the drive is given (the surface speed at the
        current X, within G50/G92 S and the spindle maximum), from the S strobe on and every scan as
        X moves; D3x050 keeps the S word in m/min (motion decisions 30)."""
        if ch.css_rpm is not None:
            self.mem.set_f32(d3(self.x, 24), min(ch.css_rpm, self.spindle_max_rpm))

    _drive_outputs = write_drive_outputs  # mlc/drive_status.py: the drive status relays and words

    def commanded_rpm(self, k: int = 0) -> float:
        """Signed spindle speed the MLC relays ask for: direction M2x704/M2x705, speed from S (D3x024) or
        from D2x024 when M2x710 is ON. The spindle override D2x026 is not in it: the NC applies it
        with the G96 speed and the clamps (`nc.motion.css.spindle_speed`, motion decisions 32)."""
        x, mem = self.x, self.mem
        m, base = mem.m, 20704 + 1000 * x + 16 * k  # M2x704 + 16k
        fwd = bool(m[base])
        if fwd == bool(m[base + 1]):
            return 0.0
        src = (mem.u32(20024 + 1000 * x) if m[base + 6] else mem.f32(30024 + 1000 * x)) if k == 0 else 0.0  # D2x024, D3x024
        rpm = min(abs(src), self.spindle_max_rpm)
        return rpm if fwd else -rpm

