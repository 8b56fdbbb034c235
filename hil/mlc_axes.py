"""NC ↔ MLC axis switching and the MLC's own axis moves on the bench (NC5 App. B.2, decisions M26-20 … M26-27).

Per axis i of the channel (its i-th [[axes]] entry), the MLC writes

    M2x432+i  NC / MLC Axis Switching    ON: the MLC controls the axis, OFF: the NC does
    M2x416+i  MLC Axis Control Mode      ON: speed mode, OFF: position mode
    M2x464+i  MLC Axis Command Type      ON: D2x256+2i is incremental
    M2x448+i  Trigger Axis' Movement     position mode: the rising edge starts a move; speed mode: the level runs
    D2x256+2i Target Position (f32, mm / deg), D2x288+2i Target Velocity (f32, mm/min; rotary: rpm)

and the NC answers M3x432+i (Switch to MLC Axis Finished) and M3x448+i (Target Reached; speed mode: speed
reached). The switch takes the axis where the NC's command of it stands (a switch asked while the NC moves the
axis waits for it to stand, M26-21); back to the NC once the MLC axis stands and the NC's queue is empty, and then
the NC's position of the axis (the interpreter's and the planner's) is where the MLC left it (M26-23). A program
that moves an axis under MLC control is App. A 0x141C (M26-22). The moves themselves: nc/mlc_axis.py (ruckig).

`BenchRunner._cycle` calls `step` only while `ChannelLink.mlc_axes` (the M2x432+i levels) or `_mlc_axes` (an axis
still under MLC control or switching) is non-zero: otherwise its cost is those two int tests a cycle. A stretch never
starts meanwhile (hil/stretch.py `_quiet`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from nc.alarms import Alarm
from nc.channel import RunState
from nc.mlc_axis import MlcAxis, velocity_units
from nc.motion.profile import solve_velocity

AXIS_TYPE_ERROR = 0x141C  # App. A: "Setting error of the axis type. … such as NC axis or PLC axis" (M26-22)
NC, SWITCHING, MLC, RETURNING = 0, 1, 2, 3
_STOPPED = (RunState.STOPPING, RunState.ALARM, RunState.RESETTING)


@dataclass
class MlcAxes:
    """What the bench keeps per axis between cycles (created at the first switch request)."""
    axes: list[MlcAxis]
    rotary: list[bool]
    state: list[int] = field(default_factory=list)
    nc_last: list[float | None] = field(default_factory=list)  # the NC's command of the axis, last cycle
    trigger: list[bool] = field(default_factory=list)  # M2x448+i as last seen (the rising edge starts a move)
    velocity: list[float] = field(default_factory=list)  # speed mode: D2x288+2i the running speed was set from
    log: list[tuple[int, str, str]] = field(default_factory=list)  # (cycle, axis, what)
    resets: int = 0  # ChannelLink.resets as last seen

    def __post_init__(self) -> None:
        n = len(self.axes)
        self.state, self.nc_last = [NC] * n, [None] * n
        self.trigger, self.velocity = [False] * n, [0.0] * n


def _make(r: Any) -> MlcAxes:
    axes = [MlcAxis(a.name, a.limits, r.bench.cycle) for a in r.bench.axes]
    return MlcAxes(axes, [a.units == "deg" for a in r.bench.axes])


def step(r: Any, ch: Any, link: Any) -> None:
    """One cycle, after the NC's commands are in `r._commands`: the axes under MLC control get the MLC's setpoints."""
    st: MlcAxes | None = getattr(r, "_mlc_ax", None)
    if st is None:
        st = r._mlc_ax = _make(r)
    mem, want = link.mem, link.mlc_axes
    m, b2, b3, d2 = mem.m, 20000 + 1000 * link.x, 30000 + 1000 * link.x, 20000 + 1000 * link.x
    cmds = r._commands
    active = 0
    reset = link.resets != st.resets  # an NC reset since the last cycle: every MLC axis's move stops
    st.resets = link.resets
    for i, ax in enumerate(st.axes):
        s = st.state[i]
        asked = bool(want >> i & 1)
        if s == NC and not asked:
            continue
        nc = float(cmds[i])
        if s == NC:
            s = SWITCHING
            st.nc_last[i] = None
        if s == SWITCHING:
            if not asked:
                s = NC  # asked back before it switched: nothing happened
            elif st.nc_last[i] == nc and not r._braking:
                # the NC's command of the axis stands: the MLC takes it there (M26-21)
                ax.hold(nc)
                st.trigger[i] = bool(m[b2 + 448 + i])  # a trigger already ON is no edge
                s = MLC
                m[b3 + 432 + i] = 1
                st.log.append((r.cycle, r.axes[i], "mlc"))
            else:
                st.nc_last[i] = nc
                st.state[i] = s
                active |= 1 << i
                continue
        if s in (MLC, RETURNING):
            last = st.nc_last[i]
            if last is not None and nc != last and ch.state is RunState.RUNNING:
                r._alarm(Alarm(AXIS_TYPE_ERROR, f"axis {r.axes[i]} is an MLC axis (M2{link.x}{432 + i} ON): "
                                                f"the program cannot move it", line=r.line or None, axis=r.axes[i]))
            st.nc_last[i] = nc
            if reset or r._winding_down:
                ax.stop()  # a reset, the run's end: a controlled stop where it is (M26-24)
                st.trigger[i] = bool(m[b2 + 448 + i])
            else:
                _drive(r, ch, st, i, ax, m, b2, d2, mem)
            cmds[i] = ax.step()
            m[b3 + 448 + i] = 1 if ax.reached else 0
            if s == MLC and not asked:
                s = RETURNING
            elif s == RETURNING and asked:
                s = MLC
            if s == RETURNING and not ax.moving and ch.planner.idle:
                _hand_back(r, ch, link, i, ax.p)
                m[b3 + 432 + i] = m[b3 + 448 + i] = 0
                st.log.append((r.cycle, r.axes[i], "nc"))
                s = NC
        st.state[i] = s
        if s != NC:
            active |= 1 << i
    r._mlc_axes = active


def _drive(r: Any, ch: Any, st: MlcAxes, i: int, ax: MlcAxis, m: Any, b2: int, d2: int, mem: Any) -> None:
    """The MLC's request of this cycle for axis i (under MLC control), and the NC's stops."""
    if r._braking or ch.emergency:
        ax.hold(float(r.actual[i]))  # E-stop: the drive's quick stop brakes it; the move is given up (M26-24)
        st.trigger[i] = bool(m[b2 + 448 + i])
        return
    trig = bool(m[b2 + 448 + i])
    rising = trig and not st.trigger[i]
    st.trigger[i] = trig
    if ch.state in _STOPPED:
        ax.stop()  # an NC alarm: a controlled stop where it is (M26-24)
        return
    rotary = st.rotary[i]
    if m[b2 + 416 + i]:  # speed mode: the trigger's level runs the axis at D2x288+2i
        if trig:
            v = velocity_units(mem.f32(d2 + 288 + 2 * i), rotary)
            if rising or v != st.velocity[i] or ax.stopping:
                st.velocity[i] = v
                ax.run_at(v)
            if ax.v != 0.0 and not ax.stopping:
                _speed_limit(r, ch, i, ax)
        elif ax.moving and not ax.stopping:
            ax.stop()
        return
    if ax.goal is None and ax.moving and not ax.stopping:
        ax.stop()  # speed mode left while running: stop first
    if rising:
        target = float(mem.f32(d2 + 256 + 2 * i))
        if m[b2 + 464 + i]:
            target += ax.goal if ax.goal is not None else ax.p  # incremental: from the last target (M26-25)
        v = velocity_units(mem.f32(d2 + 288 + 2 * i), rotary)
        alarm = _outside(ch, r.axes[i], target, target)
        if alarm is not None:
            r._alarm(alarm)  # a target past a software limit: App. A 0x0A01/0x0A03, the move is not started
        elif ax.move_to(target, v):
            st.log.append((r.cycle, r.axes[i], f"move {target:g}"))


def _outside(ch: Any, axis: str, lo: float, hi: float, what: str = "target") -> Alarm | None:
    """The software-limit alarm (App. A 0x0A01 1st segment, 0x0A03 2nd) when [lo, hi] leaves the axis's window."""
    lims = getattr(ch, "soft_limits", None)
    if lims is None:
        return None
    for segment, code in ((1, 0x0A01), (2, 0x0A03)):
        if segment == 1 and axis in lims.disabled:
            continue
        low, high = lims.window(axis, segment)
        side = ("+", hi, high) if high is not None and hi > high + 1e-9 else \
            ("-", lo, low) if low is not None and lo < low - 1e-9 else None
        if side is not None:
            return Alarm(code, f"software limit {segment} {side[0]} of MLC axis {axis}: the {what} {side[1]:.4f} is "
                               f"past the limit {side[2]:.4f} (machine coordinates)", axis=axis)
    return None


def _speed_limit(r: Any, ch: Any, i: int, ax: MlcAxis) -> None:
    """Speed mode: the axis stops short of a software limit it runs towards, and the limit's alarm is raised
    (M26-25). A cheap generous estimate of where a stop begun next cycle would end first; only near a limit the
    exact one (ruckig's velocity interface from the current state, as `MlcAxis.stop` will plan it)."""
    v, a, lim = ax.v, ax.a, ax.limits
    ahead = v + 2.0 * a * lim.max_acceleration / lim.max_jerk if v * a > 0 else v
    rough = ax.p + 2.0 * (ahead * abs(ahead) / (2.0 * lim.max_acceleration) + ahead * lim.max_acceleration
                          / lim.max_jerk + 2.0 * ahead * ax.cycle)
    if _outside(ch, r.axes[i], min(ax.p, rough), max(ax.p, rough)) is None:
        return
    prof = solve_velocity(ax.p, v, a, 0.0, lim.max_acceleration, lim.max_jerk)
    end = prof.at(prof.duration)[0] + 2.0 * v * ax.cycle  # the stop begins next cycle: a cycle's travel, twice
    alarm = _outside(ch, r.axes[i], min(ax.p, end), max(ax.p, end), "stop point")
    if alarm is not None:
        ax.stop()
        r._alarm(alarm)


def _hand_back(r: Any, ch: Any, link: Any, i: int, position: float) -> None:
    """The NC's position of axis i is where the MLC left it: planner, interpreter and manual motion (M26-23)."""
    manual = getattr(link, "manual", None)
    if manual is not None and r.axes[i] in manual.axes:
        manual.hold_at(r.axes[i], position)  # a JOG/INC/MPG after the hand-back starts there
    pl = ch.planner
    pl.position[i] = pl.output[i] = position
    ch.handed_back[r.axes[i]] = position  # the next move must start here (read ahead before it: 0x141C, M26-30)
    if pl.filter is not None:
        pl.filter.reset(pl.position)
    interp = getattr(r, "_interp", None)
    if interp is not None and r.axes[i] in interp.position:
        interp.position[r.axes[i]] = position
        interp.last_target = interp.work_position()
