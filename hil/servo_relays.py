"""The MLC's servo relays obeyed by the bench's drive control (decision M22-1): M2x012 "Servo ON/OFF" (OFF: every
axis of the channel) and M2x272+i "Servo OFF" of the channel's i-th axis (App. B.2.1.1 / B.2.1.8).

An axis asked OFF is disabled through its CiA 402 master (shutdown: operation enabled → ready to switch on), the
same on the simulated, EtherCAT and CANopen buses, but only where it stands: the NC never drops the torque of a
moving axis. If the NC moves it (a program or an MDI block still commands it) the channel raises App. A 0x0A07
"Servo is not ready" and stops along the path, jerk-limited (the project's one stop path); the drive is disabled
once the axis stands. Asked ON again, the drive is enabled where the axis stands and the NC takes that position.

M2x012 ("all of connected servo drives in the corresponding channel") holds the channel's spindle drives OFF too
(decision M23-2): no speed command, disabled below 1 rpm, App. A 0x0C06 if the program turns the spindle meanwhile.

The runner calls `obey` only while a relay asks an axis OFF or one just went back ON (`BenchRunner._servo_off`,
one int compare per cycle otherwise); a stretch never starts meanwhile (hil/stretch.py `_quiet`)."""

from __future__ import annotations

from typing import Any

from fieldbus.cia402 import Target
from mlc.manual_alarms import SERVO_NOT_READY
from nc.alarms import Alarm
from nc.channel import RunState

SPINDLE_NOT_ENABLED = 0x0C06  # App. A: "The spindle is not enabled. Please check if the spindle is enabled."
RESYNC = 40  # BenchRunner._servo_off bit RESYNC + i: axis i back ON, its position for the NC still to take
_STOPPED = (RunState.STOPPING, RunState.ALARM, RunState.RESETTING)


def obey(r: Any, ch: Any, link: Any, last_cmds: list[float]) -> None:
    """One cycle of the relays' effect: `link.servo_off` bit i = the MLC asks axis i OFF (`link.servo_all`: by
    M2x012); `last_cmds` the axes' commands of the cycle before (an axis whose command changed, the NC moves)."""
    prev, want = r._servo_off, link.servo_off
    cmds = r._commands.tolist()
    for i, m in enumerate(r.masters[: len(r.axes)]):
        bit = 1 << i
        if want & bit:
            moving = cmds[i] != last_cmds[i]
            if moving and ch.state not in _STOPPED:
                # the NC moves an axis the MLC turned off: controlled stop along the path, then disabled
                relay = f"M2{link.x}012 OFF" if link.servo_all else f"M2{link.x}{272 + i} ON"
                r._alarm(Alarm(SERVO_NOT_READY, f"servo is not ready: axis {r._name(i)} was turned servo OFF "
                                                f"({relay}) while the NC moves it", line=r.line or None,
                               axis=r._name(i)))
            if m.target is Target.ENABLED and not moving and r._at_rest(i) and not r._braking:
                m.request(Target.DISABLED)  # standing, its command too: shutdown (CiA 402 ready to switch on)
        elif prev & bit and not r._braking and not r._winding_down and m.target is Target.DISABLED:
            m.request(Target.ENABLED)  # back ON: enabled where it stands
            prev |= bit << RESYNC
    resync = prev >> RESYNC
    if resync:
        # once enabled: a standing NC takes the axis's actual position (a command the NC ran on before the 0x0A07
        # stop is dropped; nothing held the axis while off). A running one never moved it while it was off.
        pos = dict(zip(ch.planner.axes, ch.planner.position.tolist()))
        took = False
        for i, m in enumerate(r.masters[: len(r.axes)]):
            if resync >> i & 1 and (m.enabled or m.target is not Target.ENABLED):
                prev &= ~(1 << (RESYNC + i))
                if m.enabled and ch.planner.idle:
                    pos[r.axes[i]] = float(r.actual[i])
                    r._commands[i] = r.actual[i]
                    took = True
        if took:
            ch.planner.reset_position(pos)
    if len(r.masters) > len(r.axes) and (link.servo_all or prev & _spindle_bits(r)):
        want |= _spindles(r, ch, link, prev)
    r._servo_off = want | (prev >> RESYNC << RESYNC)


def _spindle_bits(r: Any) -> int:
    """Bits of `BenchRunner._servo_off` for the spindle drives: their master indexes, after the axes'."""
    return (1 << len(r.masters)) - (1 << len(r.axes))


def _spindles(r: Any, ch: Any, link: Any, prev: int) -> int:
    """M2x012 OFF holds the channel's spindle drives OFF too (decision M23-2), bits at their master index (so the
    E-stop's re-enable leaves them off, as an axis): disabled once turning below 1 rpm; the program's spindle asked to
    turn meanwhile (an M03/M04 with S, or one turning when the relay fell) is App. A 0x0C06 and the channel stops.
    Its speed command is 0 from the cycle the relay falls (`hold_spindles`): the drive ramps it down."""
    n, bits = len(r.axes), 0
    for k in range(n, len(r.masters)):
        m, bit = r.masters[k], 1 << k
        if link.servo_all:
            bits |= bit
            if k == n and r.mlc.spindle.signed_rpm != 0.0 and ch.state not in _STOPPED:
                r._alarm(Alarm(SPINDLE_NOT_ENABLED, f"the spindle is not enabled: spindle {r._name(k)} is servo OFF "
                                                    f"(M2{link.x}012 OFF) while the program turns it",
                               line=r.line or None, axis=r._name(k)))
            turning = abs(r.scales[k].drive_to_rpm(r.tx[k].velocity_actual)) >= 1.0
            if m.target is Target.ENABLED and not turning and not r._braking and not r.rx[k].target_velocity:
                m.request(Target.DISABLED)  # standing, its command too: shutdown (CiA 402 ready to switch on)
        elif prev & bit and not r._braking and not r._winding_down and m.target is Target.DISABLED:
            m.request(Target.ENABLED)  # back ON: enabled, the next speed command turns it
    return bits


def hold_spindles(r: Any) -> None:
    """The speed command of each spindle held OFF is 0 (called after the runner set the cycle's commands)."""
    off = r._servo_off
    for k in range(len(r.axes), len(r.rx)):
        if off >> k & 1:
            r.rx[k].target_velocity = 0
