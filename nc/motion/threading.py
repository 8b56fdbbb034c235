"""Spindle-synchronised threading: thread moves locked to the spindle's ACTUAL angle.

A run of consecutive thread moves (a thread and its chamfer pull-out, say) is one *chain*. The
chain starts from rest; it is armed on its first cycle: from the spindle's actual speed ω0 it
solves ONE jerk-limited ramp (ruckig, 1 DoF) from rest to the locked speed lead·ω0/360 along the
thread's major axis. That ramp ends D behind where a spindle-locked axis would be, so the ramp
starts 360·D/lead degrees *before* the sync angle (index + Q): after the ramp the axis is exactly
where lead × revolutions since the sync angle puts it (acceleration-lag compensation). The ramp
runs on spindle angle, not on time, so every pass with the same spindle speed meets the thread
at the same phase. Locked, the major-axis travel u integrates lead(n)·Δn per cycle (G34: the lead
grows by K per revolution). The last move of the chain brakes to rest at its end point with one
jerk-limited profile, started when the remaining distance is what braking needs.

Feed override, feed hold and dry run do not act on a thread (the override is forced to 100 %).
A chain arms only once the spindle's measured speed has settled at its command (`SpindleSettle`,
motion decisions 33): the ramp is planned on that speed, so it must not be still changing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nc.alarms import NcAlarm
from nc.motion.block import Block
from nc.motion.lookahead import MARGIN, change_distance
from nc.motion.profile import Piecewise, solve_position, solve_velocity
from nc.motion.thread_corners import ThreadCorner, make_corner


# A thread arms when the measured speed has stayed within SETTLE_BAND of the command (0.1 %, at least
# SETTLE_MIN_RPM) for SETTLE_CYCLES cycles in a row. M3x704 "speed reached" (2 %) only ends M03;
# a spindle 2 % short still accelerates through the ramp, which was planned on one speed.
SETTLE_BAND = 1e-3
SETTLE_MIN_RPM = 0.1
SETTLE_CYCLES = 10


@dataclass
class SpindleSettle:
    """Counts the cycles the spindle's measured speed has been at its commanded speed."""

    cycles: int = 0

    def update(self, rpm: float, command: float) -> None:
        at = abs(command) >= 1.0 and abs(rpm - command) <= max(SETTLE_BAND * abs(command), SETTLE_MIN_RPM)
        self.cycles = self.cycles + 1 if at else 0

    def ready(self, command: float) -> bool:
        """A stopped spindle never settles: arming then raises its own alarm (not rotating)."""
        return abs(command) < 1.0 or self.cycles >= SETTLE_CYCLES


def major_factor(b: Block) -> float:
    """Path length per unit of travel along the thread's major axis (the axis the lead is on)."""
    assert b.seg is not None
    major = float(np.max(np.abs(b.seg.end - b.seg.start)))
    return b.length / major if major > 1e-12 else 1.0


@dataclass
class ThreadState:
    direction: float  # +1 / -1: the spindle's sense of rotation
    omega: float  # |deg/s| at arming
    sync_angle: float  # cumulative spindle angle (deg) of index + Q the chain is locked to
    ramp_start: float  # cumulative angle where the ramp starts (sync_angle less the lag)
    ramp: Piecewise  # major-axis travel u(t) from rest to the locked speed
    ramp_time: float
    u: float = 0.0  # major-axis travel since the chain start
    u_block: float = 0.0  # u where the current block began
    n_block: float = 0.0  # revolutions (since sync) where the current block began
    locked: bool = False
    last_angle: float = 0.0
    brake: Piecewise | None = None  # path profile of the final stop
    brake_t: float = 0.0
    brake_in_u: bool = False  # an alarm's stop: `brake` is major-axis travel u, run on along the chain (motion 63)
    stop_after: float | None = None  # an alarm's stop waits for u to pass this corner's end (motion 63)
    stop_limits: tuple[float, float] = (0.0, 0.0)  # its limits on u: acceleration, jerk
    s: float = 0.0  # path position in the current block
    v: float = 0.0  # path speed (finite difference)
    stopping: bool = False  # a reset brakes the thread where it is
    halted: bool = False
    corners: list[ThreadCorner] = field(default_factory=list)  # rounded corners inside the chain
    cornered: int = -1  # the chain block index whose corner to the next block is known
    block_no: int = 0  # index of the current block within the chain


def arm(b: Block, angle: float, rpm: float, index: float, line: int) -> ThreadState:
    """Plan the chain's start from the spindle's actual angle and speed."""
    mv = b.move
    if abs(rpm) < 1.0:
        raise NcAlarm(0x0C02, "thread: the spindle is not rotating", line=line, block=mv.block, program=mv.program)
    lead = float(mv.lead or 0.0)
    if lead <= 0.0:
        raise NcAlarm(0x1001, "thread without a positive lead", line=line, block=mv.block, program=mv.program)
    d = 1.0 if rpm > 0 else -1.0
    omega = abs(rpm) * 6.0  # deg/s
    f = major_factor(b)
    v_u = lead * omega / 360.0
    if v_u * f > b.cap_hard * 1.0001:
        raise NcAlarm(0xB01D, f"thread: {lead:g} mm/rev at {abs(rpm):.0f} rpm needs {v_u * f * 60:.0f} mm/min, "
                              f"above the axes' {b.cap_hard * 60:.0f} mm/min", line=line, block=mv.block,
                      program=mv.program)
    ramp = solve_velocity(0.0, 0.0, 0.0, v_u, b.a / f, b.j / f)
    t_r = ramp.duration
    lag = v_u * t_r - float(ramp.sample(np.array([t_r]))[0][0])  # how far the ramp ends behind the lock
    lag_deg = 360.0 * lag / lead
    sync = index + float(mv.start_angle or 0.0)
    # the first sync angle whose ramp start still lies ahead of the spindle
    k = math.floor((d * (angle - sync) + lag_deg) / 360.0) + 1
    sync += d * 360.0 * k
    return ThreadState(d, omega, sync, sync - d * lag_deg, ramp, t_r, last_angle=angle)


def advance(st: ThreadState, b: Block, angle: float, T: float, last_in_chain: bool) -> float | None:
    """This cycle's path position in block b, or None when the block is done (s = length)."""
    mv = b.move
    lead = float(mv.lead or 0.0)
    f = major_factor(b)
    if st.brake is not None:
        st.brake_t += T
        s = float(st.brake.sample(np.array([st.brake_t]))[0][0])
        if st.brake_in_u:
            if not last_in_chain and (s - st.u_block) * f >= b.length - 1e-9:
                # the stop needs more room than this block has left: it runs on into the chain's next block
                st.brake_t -= T  # whose call in this cycle advances the clock again
                return _set(st, b.length, T, True, b)
            st.u, s = s, (s - st.u_block) * f  # u: where the chain's corners are read from
        if st.brake_t >= st.brake.duration - 1e-12:
            if st.stopping:  # a reset: rest wherever the stop ended
                st.halted = True
                return _set(st, min(s, b.length), T, False, b)
            return _set(st, b.length, T, True, b)
        return _set(st, min(s, b.length), T, False, b)
    n = st.direction * (angle - st.sync_angle) / 360.0  # revolutions since the sync angle
    if not st.locked:
        t = st.direction * (angle - st.ramp_start) / st.omega
        if t <= 0.0:
            st.last_angle = angle
            return _set(st, 0.0, T, False, b)
        if t < st.ramp_time:
            st.u = float(st.ramp.sample(np.array([t]))[0][0])
        else:
            st.locked = True
            st.u = lead * n
    else:
        n0 = st.direction * (st.last_angle - st.sync_angle) / 360.0
        k = float(mv.lead_change or 0.0)
        mid = 0.5 * (n0 + n) - st.n_block
        du = (lead + k * mid) * (n - n0)
        st.u += du  # G34: lead grows by K per revolution within the block
        if st.stop_after is not None and st.u >= st.stop_after:  # past the corner: the deferred stop starts
            st.stop_after = None
            _brake(st, st.u, du / T, 0.0)
    st.last_angle = angle
    s = (st.u - st.u_block) * f
    if s >= b.length - 1e-9 and not last_in_chain:
        return _set(st, b.length, T, True, b)
    if last_in_chain and st.locked and st.brake is None:  # (a deferred alarm stop may have started above)
        v = st.v if st.v > 0.0 else lead * st.omega / 360.0 * f
        need = change_distance(v, 0.0, MARGIN * b.a, MARGIN * b.j)
        if b.length - s - v * T <= need:
            st.brake = solve_position(s, v, 0.0, b.length, 0.0, 1.01 * v + 1e-6, b.a, b.j)
            if st.brake is None:
                raise NcAlarm(0x0000, "thread: the pull-out stop cannot be planned", line=mv.line, block=mv.block,
                              program=mv.program)
            st.brake_t = 0.0
    return _set(st, min(s, b.length), T, False, b)


def _set(st: ThreadState, s: float, T: float, done: bool, b: Block) -> float | None:
    if done:  # no position this cycle in b: the chain's next block gives it, from the last one (next_block)
        return None
    st.v = (s - st.s) / T if s >= st.s else 0.0
    st.s = s
    return s


def slope(b: Block) -> np.ndarray:
    """dP/du of a thread block: the axes' travel per unit of major-axis travel."""
    assert b.seg is not None
    return (b.seg.end - b.seg.start) * (major_factor(b) / b.length) if b.length > 0 else np.zeros(len(b.seg.end))


def add_corner(st: ThreadState, b: Block, nb: Block, acc: np.ndarray, jerk: np.ndarray) -> None:
    """Register the rounded corner from b into the chain's next block nb (once per junction)."""
    if st.cornered >= st.block_no or b.seg is None or nb.seg is None \
            or b.seg.kind != "line" or nb.seg.kind != "line":
        return
    st.cornered = st.block_no
    du_b, du_n = b.length / major_factor(b), nb.length / major_factor(nb)
    u_c = st.u_block + du_b
    v = float(b.move.lead or 0.0) * st.omega / 360.0
    room = min(0.5 * du_b, 0.5 * du_n, u_c - st.u)  # never reach back past where the chain already is
    c = make_corner(u_c, slope(b), slope(nb), v, acc, jerk, room)
    if c is not None:
        st.corners = [k for k in st.corners if k.u + k.w > st.u] + [c]


def next_block(st: ThreadState, b: Block, nb: Block) -> None:
    """The chain runs on from b into the next thread block nb: carry the travel over."""
    st.block_no += 1
    f_b, f_nb = major_factor(b), major_factor(nb)
    u_last = st.u_block + st.s / f_b  # the last cycle's position, on u
    st.u_block += b.length / f_b
    st.u = max(st.u, st.u_block)
    st.n_block = st.direction * (st.last_angle - st.sync_angle) / 360.0
    # st.s: the last cycle's position in nb's path length (before nb's start): this cycle's speed is then its
    # real one, not 0 (a stop asked in the cycle a chain changed blocks found the planner "at rest" and froze
    # the axes at 27 mm/s: motion 63)
    st.s = (u_last - st.u_block) * f_nb


def stop(st: ThreadState, chain: list[Block]) -> None:
    """Reset or alarm during a thread: a jerk-limited stop from the current state, planned on the major-axis
    travel u, so that it runs on through the chain's next blocks where the current block (chain[0]) ends first
    (motion 63). In the ramp the state is the ramp's own, its acceleration included. A stop that would brake
    inside a rounded corner of the chain (shaped for the locked speed, its jerk near the limit already) runs on
    locked through the corner and brakes after it. Before, the stop was planned in the current block's path
    length from a = 0 and cut at its end: an alarm near a thread's end stopped the axes within 2-3 cycles
    (acceleration ×3.5, jerk ×77 the limits)."""
    st.stopping = True
    if st.brake is not None or st.stop_after is not None:
        return
    b = chain[0]
    f = major_factor(b)
    v, a = st.v / f, 0.0
    t = st.direction * (st.last_angle - st.ramp_start) / st.omega
    if not st.locked and 0.0 < t < st.ramp_time:
        _, v, a = st.ramp.at(t)  # the ramp is on u already
    # u's limits: every block's path limits over its path length per u, the tightest of the chain's
    st.stop_limits = (min(nb.a / major_factor(nb) for nb in chain), min(nb.j / major_factor(nb) for nb in chain))
    u0 = st.u_block + st.s / f
    _brake(st, u0, v, a)
    end = float(st.brake.at(st.brake.duration)[0])  # type: ignore[union-attr]
    ahead = [k for k in st.corners if k.u + k.w > u0]
    if st.locked and ahead and end > min(k.u - k.w for k in ahead):
        st.brake, st.brake_in_u = None, False
        st.stop_after = max(k.u + k.w for k in ahead)


def _brake(st: ThreadState, u0: float, v: float, a: float) -> None:
    st.brake = solve_velocity(u0, v, a, 0.0, *st.stop_limits)
    st.brake_t = 0.0
    st.brake_in_u = True
