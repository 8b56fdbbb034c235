"""The smallest machine logic that still does what the program asks: spindle on/off/direction
and speed from M03/M04/M05 and S, and a finish for every M/S/T code on the next scan.

M00 is the NC's hold, not a code to finish (NC5 §3.8.1.1): it holds until the simulated operator presses
Cycle Start `m00_resume` seconds later (`hil run --m00-resume`), as on the Delta MLC. M01 holds only with
the optional-stop switch M2x009 ON (§3.8.1.2), which this MLC has not: it runs on (decision bench B78)."""

from __future__ import annotations

from dataclasses import dataclass, field

from nc.channel import Channel
from nc.moves import Aux


@dataclass
class SpindleCommand:
    rpm: float = 0.0  # programmed speed, always positive
    direction: int = 0  # +1 CW (M03), -1 CCW (M04), 0 stopped

    @property
    def signed_rpm(self) -> float:
        return self.rpm * self.direction


@dataclass
class BasicMlc:
    spindle: SpindleCommand = field(default_factory=SpindleCommand)
    max_rpm: float = 6000.0
    log: list[tuple[int, str, float]] = field(default_factory=list)  # (cycle, code, value) handled
    cycle: int = 0
    # Feed, rapid and spindle override (fractions): the basic MLC has no panel, so these stay as set
    # (hil.run's feed_override … options), where the Delta MLC takes them from D2x002/D2x004/D2x026.
    overrides: tuple[float, float, float] = (1.0, 1.0, 1.0)
    m00_resume: float | None = 0.5  # s the operator takes to press Cycle Start after M00 (None: never)
    cycle_time: float = 0.001  # the bench's cycle, s: the hold is timed in scans
    _hold: Aux | None = None  # the M00 the NC holds at, and the scan it was first seen in
    _hold_scan: int = 0

    def scan(self, channel: Channel) -> None:
        self.cycle += 1
        if self.overrides != (1.0, 1.0, 1.0):
            channel.feed_override, channel.rapid_override, channel.spindle_override = self.overrides
        if channel.css_rpm is not None:  # G96: the speed command is the surface speed's rpm (as D3x024)
            self.spindle.rpm = min(channel.css_rpm, self.max_rpm)
        aux: Aux | None = channel.pending_aux
        if aux is None:
            return
        if aux.kind == "S" and aux.args.get("max"):
            pass  # G50/G92 S: a speed limit, not a speed (the channel clamps G96 with it)
        elif aux.kind == "S":
            self.spindle.rpm = min(abs(aux.value), self.max_rpm)
        elif aux.kind == "M":
            code = int(aux.value)
            if code == 0 and not self._released(aux):
                return  # held: the NC waits for Cycle Start, not for a finish
            if code in (3, 4):
                self.spindle.direction = 1 if code == 3 else -1
            elif code in (5, 2, 30):
                self.spindle.direction = 0
        self.log.append((self.cycle, aux.kind, aux.value))
        channel.finish_aux()

    def _released(self, aux: Aux) -> bool:
        """The operator's Cycle Start on an M00 hold, `m00_resume` s after the first scan that saw it."""
        if self._hold is not aux:
            self._hold, self._hold_scan = aux, self.cycle
        if self.m00_resume is None or (self.cycle - self._hold_scan) * self.cycle_time < self.m00_resume - 1e-12:
            return False
        self._hold = None
        return True
