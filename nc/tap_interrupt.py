"""An interrupted rigid tap and its recovery (NC5 G command guide §3.13.2 G74/G84 note (6), manual line 3136).

"If an unexpected interruption occurs in the tapping process, including reset, emergency stop ... the system
will record the current tapping execution data and return the alarms [0x0270 Axis movement prohibition during
tapping interruption] and [0x0C09 Spindle movement prohibition during tapping interruption]. ... the G84.48
command can be executed through the MDI mode to command the spindle and Z axis to exit in reverse and return to
the tapping R point". App. B: M2x080 "Canceling Tapping Interrupt Status", M2x707 "1st Spindle Retraction After
Tapping", M3x707 "1st Spindle Is in The Rigid Tapping" (decisions mlc M26-1 … M26-9).

- `TapRecord`: what the NC keeps of the interrupted tap (hole, R, where the drilling axis stood, pitch, hand,
  spindle, G94/G95, the cycle's line).
- `TapStatus`: the interrupt status itself; it outlives the channel's program (the next MDI block sees it).
- `Retraction`: the exit along the thread: ONE jerk-limited profile u(t) (ruckig, 1 DoF) of the drilling axis'
  travel back to R; the spindle's position setpoint turns `deg_per_mm` × u against the tapping hand, so the
  axis/spindle ratio is the pitch in every cycle, the ramps included (a rigid tap, not a feed at a speed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ruckig import ControlInterface, InputParameter, Ruckig, Trajectory

from nc.alarms import Alarm, NcAlarm
from nc.exit_release import release_at_exit
from nc.moves import Aux, Event, Move, MoveList

TAP_TAGS = ("tap", "tap_out")  # the tapping moves of a G74/G84 (and lathe G84/G88) hole (nc.cycles.holes)
# The spindle's limits while it follows the axis in position mode (deg/s², deg/s³): 100 rev/s² (6000 rpm/s),
# the usual order of a servo spindle's rigid-tapping acceleration; the axis' own limits apply too (M26-4)
SPINDLE_ACCELERATION = 36000.0
SPINDLE_JERK = 3.6e6


@dataclass
class TapRecord:
    """The tapping execution data kept at the interruption (machine coordinates)."""

    axis: str  # the drilling axis (Z on a G17 mill)
    hole: dict[str, float]  # the other axes: where the hole is
    r_level: float  # the R point the retraction returns to
    bottom: float  # the depth the interrupted stroke was going to
    reached: float  # where the drilling axis' setpoint stood when the tap was interrupted
    pitch: float | None  # mm per spindle revolution (G95: F; G94: F / S); None when S was 0 under G94
    hand: int  # spindle sense tapping in: +1 (M03, G84), -1 (M04, G74)
    per_rev: bool  # the cycle ran under G95 (else G94)
    feed: float  # the cycle's F as programmed (mm/min under G94, mm/rev under G95)
    rpm: float  # the spindle speed S of the cycle
    cause: str  # "emergency stop" | "reset"
    stroke: str  # "tap" (going in) or "tap_out" (coming out) when it was interrupted
    spindle: int = 1  # which spindle (the channel's first: M2x707 / M3x707 are the 1st spindle's)
    line: int | None = None
    block: str | None = None
    program: str | None = None

    @property
    def speed(self) -> float:
        """The tapping feed, mm/s (the retraction's top speed)."""
        return (self.feed * abs(self.rpm) if self.per_rev else self.feed) / 60.0


def record_of(move: Move, position: dict[str, float], rpm: float, cause: str) -> TapRecord | None:
    """The record of tapping move `move` interrupted with the axes' setpoints at `position`; None when `move` is
    no tapping move."""
    tags = move.tags
    stroke = next((t for t in TAP_TAGS if t in tags), None)
    if stroke is None:
        return None
    axis = max(move.end, key=lambda a: abs(move.end[a] - move.start.get(a, move.end[a])))
    r_level = move.start[axis] if stroke == "tap" else move.end[axis]
    bottom = move.end[axis] if stroke == "tap" else move.start[axis]
    feed = float(move.feed or 0.0)
    if move.per_rev:
        pitch: float | None = feed
    else:
        pitch = feed / abs(rpm) if abs(rpm) > 1e-9 else None  # N§3.13.2 note (5): G94 F = lead x S
    hand = -1 if "G74" in tags else 1
    return TapRecord(axis, {a: v for a, v in position.items() if a != axis}, r_level, bottom, position[axis],
                     pitch, hand, move.per_rev, feed, rpm, cause, stroke, line=move.line or None,
                     block=move.block or None, program=move.program)


def interruption_alarms(rec: TapRecord, cause: str | None = None) -> list[Alarm]:
    """0x0270 and 0x0C09 at the tapping cycle's line (`cause`: what interrupted, the record's by default)."""
    where = dict(line=rec.line, block=rec.block, program=rec.program)
    cause = cause or rec.cause
    return [Alarm(0x0270, f"axis movement prohibited: the {cause} interrupted a tapping cycle with "
                          f"{rec.axis} at {rec.reached:.4f} (N§3.13 G84 note 6: G84.48 retracts to R "
                          f"{rec.r_level:.4f}, M2x080 cancels)", **where),
            Alarm(0x0C09, f"spindle movement prohibited: the {cause} interrupted a tapping cycle", **where)]


@dataclass
class TapStatus:
    """The tapping interrupt status of a channel: held from the interruption until G84.48 / M2x707 has retracted
    or M2x080 has cancelled it. `log`: (how it ended, the record) for each status that ended."""

    record: TapRecord | None = None
    log: list[tuple[str, TapRecord]] = field(default_factory=list)

    @property
    def holds(self) -> bool:
        return self.record is not None

    def clear(self, how: str) -> None:
        if self.record is not None:
            self.log.append((how, self.record))
            self.record = None


def guarded(events, status: TapStatus):
    """The program's events, refused while `status` holds: an axis move is 0x0270, a spindle start (M03/M04)
    0x0C09, at the block that asks for it (N§3.13.2 note (6)). Once G84.48 has retracted, they pass."""
    for ev in events:
        if status.record is not None:
            if (type(ev) is Move and ev.kind != "dwell") or type(ev) is MoveList:
                mv = ev if type(ev) is Move else ev.items[0]
                raise NcAlarm(0x0270, "axis movement prohibited during the tapping interruption: retract with "
                                      "G84.48 (or M2x707), or cancel with M2x080", line=mv.line or None,
                              block=mv.block or None, program=mv.program)
            if type(ev) is Aux and ev.kind == "M" and int(ev.value) in (3, 4):
                raise NcAlarm(0x0C09, "spindle movement prohibited during the tapping interruption: retract with "
                                      "G84.48 (or M2x707), or cancel with M2x080", line=ev.line or None,
                              block=ev.block or None, program=ev.program)
        yield ev


@dataclass
class Retraction:
    """The exit of an interrupted tap: the drilling axis from where it stands to R, the spindle against the
    tapping hand, both from one profile u(t) (mm of axis travel)."""

    record: TapRecord
    start: float  # the drilling axis where the retraction begins
    length: float  # |R - start|
    sense: float  # +1 / -1: the axis' direction toward R
    deg_per_mm: float  # spindle degrees per mm of u (signed: against the tapping hand)
    traj: Trajectory
    limits: tuple[float, float, float] = (0.0, 0.0, 0.0)  # velocity, acceleration, jerk of u
    line: int = 0
    how: str = "G84.48"  # what asked for it: "G84.48" or "M2x707"
    braking: bool = False  # a reset stops it short of R: the status stays
    t: float = 0.0
    u: float = 0.0
    v: float = 0.0
    angle0: float | None = None  # the spindle's angle at u = 0 (taken by the spindle drive's first cycle)

    @property
    def done(self) -> bool:
        return self.t >= self.traj.duration

    def step(self, cycle: float) -> float:
        """The next cycle's u (mm from the start toward R)."""
        self.t = min(self.t + cycle, self.traj.duration)
        pos, vel, _ = self.traj.at_time(self.t)
        end = self.done and not self.braking
        self.u, self.v = (self.length if end else min(max(pos[0], 0.0), self.length)), vel[0]
        return self.u

    def brake(self) -> None:
        """A reset during the retraction: axis and spindle brake together, still locked, within the same limits
        (jerk-limited, ruckig's velocity interface to rest)."""
        if self.braking or self.done:
            return
        pos, vel, acc = self.traj.at_time(self.t)
        inp = InputParameter(1)
        inp.control_interface = ControlInterface.Velocity
        inp.current_position, inp.current_velocity, inp.current_acceleration = [pos[0]], [vel[0]], [acc[0]]
        inp.target_velocity, inp.target_acceleration = [0.0], [0.0]
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = [self.limits[0]], [self.limits[1]], [self.limits[2]]
        traj = Trajectory(1)
        Ruckig(1).calculate(inp, traj)
        self.traj, self.t, self.braking = traj, 0.0, True

    def axis_position(self) -> float:
        return self.start + self.sense * self.u

    def spindle_setpoint(self, actual_angle: float) -> float:
        """The spindle's position setpoint (cumulative degrees) this cycle; `actual_angle`: its measured angle,
        read once when the spindle takes the retraction over (it stands there: the status holds it at 0 rpm)."""
        if self.angle0 is None:
            self.angle0 = actual_angle - self.deg_per_mm * self.u
        return self.angle0 + self.deg_per_mm * self.u


def plan_retraction(rec: TapRecord, here: float, axis_limits, line: int = 0, how: str = "G84.48") -> Retraction:
    """The retraction of `rec` from `here` (the drilling axis now) to R within the axis' limits, the spindle's
    (SPINDLE_*) and the tapping speed (M26-4). Raises NcAlarm 0x0270 when the record has no pitch."""
    if rec.pitch is None or rec.pitch <= 0:
        raise NcAlarm(0x0270, "the interrupted tap has no pitch to retract along (S was 0 under G94): cancel the "
                              "tapping interruption with M2x080", line=line or rec.line)
    length = abs(rec.r_level - here)
    sense = 1.0 if rec.r_level >= here else -1.0
    mm_per_deg = rec.pitch / 360.0
    vmax = min(rec.speed if rec.speed > 0 else axis_limits.max_velocity, axis_limits.max_velocity)
    acc = min(axis_limits.max_acceleration, SPINDLE_ACCELERATION * mm_per_deg)
    jerk = min(axis_limits.max_jerk, SPINDLE_JERK * mm_per_deg)
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [length], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vmax], [acc], [jerk]
    traj = Trajectory(1)
    otg.calculate(inp, traj)
    # exit in reverse: the spindle turns against the hand it tapped in with, one pitch per revolution
    rt = Retraction(rec, here, length, sense, -rec.hand * 360.0 / rec.pitch, traj, (vmax, acc, jerk),
                    line=line or (rec.line or 0), how=how)
    release_at_exit(rt, "traj")  # a native object in the bench's reference cycles (decision B83)
    return rt
