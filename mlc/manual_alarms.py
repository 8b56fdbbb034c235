"""Alarms of the manual modes: the hardware limit (App. A 0x0402, 0x0A06; met by homing 0x1601, 0x1602) and
oscillation in HOME mode (0x1603).

The drive stops the axis on its limit switch (CiA 402 statusword bit 11, 0x60FD bit 0/1) and the bench raises
0x0402 "Hardware limit signal is triggered" (hil/runner.py, decisions bench.md B16). Here the NC then holds the
manual command where the axis stands and locks the direction into the switch, so the axis can only move away.
Once the switch is left, 0x0A06 "The status of hardware limit needs to be cleared. After moving away from the
hardware limit, this alarm will be displayed. Please reset the machine." is raised; the next reset clears it. A
reset while the axis still stands on the switch leaves the limit alarm (0x0402) raised. When the NC's homing
search (HOME mode) ran into the switch, the hit is also 0x1601, and a reset on the switch shows 0x1602 ("triggered
after clearing 0x1601"); moving off and a reset clear it as above.

An axis the MLC holds servo OFF (M2x012 OFF, M2x272+i ON; decision M22-1) takes no manual command: a JOG key, an
INC press, MPG pulses or a home trigger of it is refused with App. A 0x0A07 "Servo is not ready. The axis is not
servo ON", and a manual move of it in progress when its relay falls stops jerk-limited (decision M23-1).

While a tap's interrupt status holds (N§3.13.2 G84 note (6), nc.tap_interrupt), no manual command moves an axis:
a JOG/RAPID/INC key, MPG pulses or a home trigger is refused with 0x0270 "Axis movement prohibition during tapping
interruption", once until a reset (decision mlc M26-2).

M2x264 (axes oscillation enable) is "only available on modes other than HOME and EDIT": ON in HOME mode it stops
the homing under way and refuses new ones with 0x1603 "Oscillation function is not allowed in the home mode"."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from nc.alarms import Alarm

from mlc.signals import m2

if TYPE_CHECKING:
    from mlc.nc_link import ChannelLink, DriveStatus
    from nc.channel import Channel
    from nc.manual import ManualMotion

HARD_LIMIT_SIGNAL = 0x0402
HARD_LIMIT_TO_CLEAR = 0x0A06
OSCILLATION_IN_HOME = 0x1603
LIMIT_IN_HOMING = 0x1601  # "The hardware limit is triggered during execution of home mode 4 ..."
LIMIT_AFTER_HOMING = 0x1602  # "The hardware limit alarm not cleared of the home mode 4."
SERVO_NOT_READY = 0x0A07  # App. A: "Servo is not ready. The axis is not servo ON."
PRESS = 0.01  # mm (deg) beyond the switch edge the held command stands


@dataclass
class HardLimitLatch:
    latched: dict[str, tuple[str, bool]] = field(default_factory=dict)  # axis -> (side "+"/"-", moved away)
    in_homing: set[str] = field(default_factory=set)  # axes whose homing search met the switch (0x1601 / 0x1602)
    edge: dict[str, float] = field(default_factory=dict)  # axis -> machine position where the switch stopped it

    def step(self, mm: ManualMotion, axes: tuple[str, ...], drives: list[DriveStatus]) -> list[Alarm]:
        """Before the manual step: latch a new hit (hold the command there), lock the direction into the switch,
        and raise 0x0A06 for an axis that has left it."""
        out: list[Alarm] = []
        for i, a in enumerate(axes):
            if i >= len(drives):
                break
            d = drives[i]
            held = self.latched.get(a)
            if d.limit and held is None:
                side = "-" if d.limit == 1 else "+" if d.limit == 2 else ("+" if mm.velocity[i] > 0 else "-")
                held = self.latched[a] = (side, False)
                self.edge[a] = d.machine_position
                if mm.axes[a].homing:  # the NC's homing search ran into the switch
                    self.in_homing.add(a)
                    out.append(Alarm(LIMIT_IN_HOMING, f"axis {a}: the {side} hardware limit was met during homing; "
                                                      f"check the search direction and that the axis starts off the "
                                                      f"limits", axis=a))
                # the command stays a hair inside the switch: the drive keeps the axis on it (no edge chatter)
                mm.hold_at(a, d.machine_position + (PRESS if side == "+" else -PRESS))
            elif held is not None and not held[1] and not d.limit and self._commanded_away(mm, i, a, held[0]):
                held = self.latched[a] = (held[0], True)
                out.append(Alarm(HARD_LIMIT_TO_CLEAR, f"axis {a} moved away from its {held[0]} hardware limit to "
                                                      f"{d.machine_position:.4f}; reset to clear", axis=a))
            if held is not None and not held[1]:
                st = mm.axes[a]
                if held[0] == "+":
                    st.lock_pos = True
                else:
                    st.lock_neg = True
        return out

    def _commanded_away(self, mm: ManualMotion, i: int, a: str, side: str) -> bool:
        """The switch reads off and the command is back before the edge: a move away, not the servo settling."""
        return mm.position[i] < self.edge[a] if side == "+" else mm.position[i] > self.edge[a]

    def reset(self) -> list[Alarm]:
        """A reset clears the axes that moved away; an axis still on its switch keeps the limit alarm: 0x1602 when
        homing met it (App. A: "triggered after clearing 0x1601"), else 0x0402."""
        self.latched = {a: v for a, v in self.latched.items() if not v[1]}
        self.in_homing &= set(self.latched)
        return [Alarm(LIMIT_AFTER_HOMING if a in self.in_homing else HARD_LIMIT_SIGNAL,
                      f"hardware limit {side} of axis {a}: still on the switch, move it away before reset", axis=a)
                for a, (side, _) in self.latched.items()]


def servo_refused(link: ChannelLink, ch: Channel, i: int, what: str) -> None:
    """A manual command of axis i, which the MLC holds servo OFF, is not carried out: App. A 0x0A07, raised once
    while the axis stays OFF (a held key or a turning handwheel is one refusal; a reset or the axis back ON re-arms
    it)."""
    bit = 1 << i
    if link._servo_refused & bit:
        return
    link._servo_refused |= bit
    x, a = link.x, link.axes[i]
    relay = f"M2{x}012 OFF" if link.servo_all else f"M2{x}{272 + i} ON"
    link._raise(ch, Alarm(SERVO_NOT_READY, f"servo is not ready: {what} of axis {a} refused, the MLC holds it "
                                           f"servo OFF ({relay})", axis=a))


def servo_off_stop(link: ChannelLink, ch: Channel, mm: ManualMotion, off: int) -> None:
    """Axes held OFF that a manual move still drives: stopped jerk-limited where they are (the runner disables
    each drive once its axis stands, hil/servo_relays.py)."""
    link._servo_refused &= off  # an axis back ON: its next refusal raises again
    for i, a in enumerate(link.axes):
        if off >> i & 1 and mm.moving(a):
            mm.stop(a)
            servo_refused(link, ch, i, "the manual move")


def tap_locked(link: ChannelLink, ch: Channel) -> None:
    """A manual-mode scan while the tapping interrupt status holds: nothing moves; a command asked for is 0x0270,
    raised once until a reset (a held key or a turning handwheel is one refusal, as 0x0A07's)."""
    from mlc.nc_link import HOME, MPG
    from mlc.signals import d3

    m, b2, n = link.mem.m, 20000 + 1000 * link.x, len(link.axes)
    asked = any(m[b2 + 384:b2 + 384 + n]) or any(m[b2 + 400:b2 + 400 + n])  # JOG/RAPID held, INC pressed
    if link.mode == HOME:
        asked = asked or any(m[b2 + 320:b2 + 320 + n])
    if link.mode == MPG:
        count = link.mem.u16(d3(0, 4))
        asked = asked or (link._mpg_last is not None and count != link._mpg_last)
        link._mpg_last = count  # the detents turned meanwhile are dropped, not run later
    if asked and not link._tap_refused:
        link._tap_refused = True
        link._raise(ch, Alarm(0x0270, f"axis movement prohibited during the tapping interruption: the "
                                      f"{MODE_TEXT.get(link.mode, 'manual')} command is refused; retract with G84.48 "
                                      f"(or M2x707), or cancel with M2x080"))


MODE_TEXT = {3: "MPG", 4: "JOG", 5: "RAPID", 6: "INC", 7: "HOME"}


def home_mode(link: ChannelLink, ch: Channel, mm: ManualMotion) -> None:
    """One HOME-mode cycle: a rising M2x320+i homes axis i, unless M2x264 is on (App. A 0x1603)."""
    x = link.x
    osc = link._m2(264)
    if link._rising(m2(x, 264)):
        mm.stop()
        link._raise(ch, Alarm(OSCILLATION_IN_HOME, "M2x264 oscillation enable is ON in HOME mode"))
    off = link.servo_off
    for i, a in enumerate(link.axes):
        if link._rising(m2(x, 320 + i)):
            if link.mlc_axes >> i & 1:
                continue  # the MLC's axis takes no manual command, a home trigger as a JOG (decision M26-29)
            if off >> i & 1:
                servo_refused(link, ch, i, "homing")
            elif osc:
                link._raise(ch, Alarm(OSCILLATION_IN_HOME, f"{a} homing refused: M2x264 oscillation enable is ON "
                                                           f"in HOME mode", axis=a))
            else:
                mm.home(a)
