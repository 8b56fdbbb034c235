"""CAN bus load of a cyclic CiA 402 set-up: SYNC + RPDOs + TPDOs every cycle, plus heartbeats.

A classic CAN data frame with an 11-bit identifier and n data bytes takes at most 55 + 10·n bit
times on the wire: 47 + 8n frame bits, worst-case bit stuffing ⌊(33 + 8n)/4⌋ and 3 bits of
interframe space (Davis, Burns, Bril, Lukkien 2007). At 1 Mbit/s an 8-byte frame is 135 µs,
so 1 ms with three ASDA drives is 175 % of the bus (anchors.md §0) — the check says so.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from fieldbus.canopen.objects import pdo_frames
from fieldbus.pdo import PdoLayout

DEFAULT_BITRATE = 1_000_000
WARN_LOAD = 0.70


class BusBudgetError(ValueError):
    """The configuration needs more than the whole bus."""


def frame_bits(n_bytes: int) -> int:
    """Worst-case bit times of one standard-identifier data frame including interframe space."""
    return 55 + 10 * n_bytes


@dataclass(frozen=True)
class BusLoad:
    bitrate: int
    cycle: float
    frames_per_cycle: int
    bits_per_cycle: int  # SYNC + RPDOs + TPDOs
    heartbeat_bits_per_s: float

    @property
    def bits_per_s(self) -> float:
        return self.bits_per_cycle / self.cycle + self.heartbeat_bits_per_s

    @property
    def load(self) -> float:
        return self.bits_per_s / self.bitrate

    def min_cycle(self, limit: float = 1.0) -> float:
        """Shortest cycle at which this set-up stays at or under `limit` of the bus."""
        return self.bits_per_cycle / (limit * self.bitrate - self.heartbeat_bits_per_s)

    def describe(self) -> str:
        return (f"CAN bus load {self.load * 100:.1f} % of {self.bitrate / 1000:g} kbit/s: "
                f"{self.frames_per_cycle} frames ({self.bits_per_cycle} bit worst case) every "
                f"{self.cycle * 1000:g} ms cycle + heartbeats")


def io_frame_bytes(inputs: int, outputs: int) -> list[int]:
    """Data bytes of a CiA 401 station's PDOs per cycle: RPDO1 = the output bytes (on every SYNC),
    TPDO1 = the input bytes. A change-of-state TPDO is counted as one per cycle too: the master
    reads inputs once a cycle, and the budget is for the worst case (inputs changing every cycle)."""
    return [(n + 7) // 8 for n in (outputs, inputs) if n > 0]


def bus_load(layouts: Sequence[PdoLayout], cycle: float, bitrate: int = DEFAULT_BITRATE,
             heartbeat_period: float = 0.0, io: Sequence[tuple[int, int]] = ()) -> BusLoad:
    """`io`: (input points, output points) of each remote I/O station on the same bus."""
    bits = frame_bits(0)  # SYNC without counter
    frames = 1
    for layout in layouts:
        for f in pdo_frames(layout.rx) + pdo_frames(layout.tx):
            bits += frame_bits(sum(e.bits for e in f) // 8)
            frames += 1
    for inputs, outputs in io:
        for n_bytes in io_frame_bytes(inputs, outputs):
            bits += frame_bits(n_bytes)
            frames += 1
    producers = len(layouts) + len(io)  # every node, drive or I/O station, sends a heartbeat
    hb = producers * frame_bits(1) / heartbeat_period if heartbeat_period > 0 else 0.0
    return BusLoad(bitrate, cycle, frames, bits, hb)


def check_budget(load: BusLoad, enforce: bool) -> str | None:
    """Refuse > 100 % when the wire has a bitrate (`enforce`); otherwise return a warning text or None."""
    if load.load > 1.0:
        advice = (f"; needs a cycle of at least {load.min_cycle() * 1000:.2f} ms "
                  f"({load.min_cycle(WARN_LOAD) * 1000:.2f} ms for {WARN_LOAD:.0%}), fewer drives or I/O stations, or a faster bus")
        if enforce:
            raise BusBudgetError(load.describe() + " exceeds the bus" + advice)
        return load.describe() + " -- a real bus at this bitrate could not carry it (virtual bus, no bit timing)" + advice
    if load.load > WARN_LOAD:
        return load.describe() + f" is above {WARN_LOAD:.0%}: little room for SDO, EMCY and retransmissions"
    return None
