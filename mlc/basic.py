"""The smallest machine logic that still does what the program asks: spindle on/off/direction
and speed from M03/M04/M05 and S, and a finish for every M/S/T code on the next scan."""

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
            if code in (3, 4):
                self.spindle.direction = 1 if code == 3 else -1
            elif code in (5, 2, 30):
                self.spindle.direction = 0
        self.log.append((self.cycle, aux.kind, aux.value))
        channel.finish_aux()
