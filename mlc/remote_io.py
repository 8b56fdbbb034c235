"""Remote I/O modules as MLC devices: which X inputs and Y outputs a module's points occupy.

NC5 App. B names the EIO stations (node 501…520, connection relays M30032…M30051, in EtherCAT
connection order) and four analog words per module (D20200+4k out, D30200+4k in), but not how the
digital points of a station appear in the MLC (ambiguity D11). Our decision (docs/decisions/mlc.md,
"Remote I/O"): station k's digital inputs are X devices and its outputs Y devices, point p at
``x + p`` / ``y + p``; by default each station takes the next free block of whole 16-point words,
in station order (station 1 from X0 / Y0).

Every scan the MLC reads each module's inputs into its X range **before** the NC and the user scan
run, and hands the Y range to the module **after** the user scan (see `Mlc.scan`). A module whose
connection relay is OFF reads all-zero inputs (the safe state), whatever it last sent.

A module's bus side is an `IoPort`: `read_inputs(dt)` → (digital bits, analog words) and
`write_outputs(digital, analog)`, with `connected`. `virtual_bus.io.IoModule` (in-process),
`fieldbus.ethercat.io.EthercatIoPort` and `fieldbus.canopen.io.CanopenIoPort` are the three.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from mlc.memory import XY_SIZE

POINTS_MAX = 64  # digital points per direction a station may declare (CiA 401 fits 8 bytes per PDO)
STATIONS_MAX = 20  # EIO nodes 501…520 (M30032…M30051)
FIRST_NODE = 501


@runtime_checkable
class IoPort(Protocol):
    connected: bool

    def read_inputs(self, dt: float) -> tuple[int, list[int]]: ...

    def write_outputs(self, digital: int, analog: list[int]) -> None: ...


@dataclass(frozen=True)
class IoMap:
    """One remote station: `inputs` points at X`x`…, `outputs` points at Y`y`…."""

    name: str
    inputs: int
    outputs: int
    x: int
    y: int
    station: int = 0  # 0-based: EIO node 501 + station, relay M30032 + station

    @property
    def node(self) -> int:
        return FIRST_NODE + self.station

    @property
    def input_mask(self) -> int:
        return (1 << self.inputs) - 1

    @property
    def output_mask(self) -> int:
        return (1 << self.outputs) - 1

    def describe(self) -> str:
        xs = f"X{self.x}–X{self.x + self.inputs - 1}" if self.inputs else "no inputs"
        ys = f"Y{self.y}–Y{self.y + self.outputs - 1}" if self.outputs else "no outputs"
        return f"{self.name} (EIO node {self.node}): {xs}, {ys}"


def next_block(used_up_to: int) -> int:
    """The first 16-aligned device number at or after `used_up_to`."""
    return (used_up_to + 15) // 16 * 16


def overlaps(maps: Sequence[IoMap]) -> list[str]:
    """Messages for stations whose X or Y ranges overlap, or run past X/Y1023."""
    out = []
    for kind in ("X", "Y"):
        spans = sorted((m.x, m.x + m.inputs, m.name) if kind == "X" else (m.y, m.y + m.outputs, m.name)
                       for m in maps)
        spans = [s for s in spans if s[1] > s[0]]
        for (a0, a1, an), (b0, b1, bn) in zip(spans, spans[1:]):
            if b0 < a1:
                out.append(f"{bn}: {kind}{b0}–{kind}{b1 - 1} overlaps {an} ({kind}{a0}–{kind}{a1 - 1})")
        for a0, a1, an in spans:
            if a1 > XY_SIZE:
                out.append(f"{an}: {kind}{a0}–{kind}{a1 - 1} runs past {kind}{XY_SIZE - 1}")
    return out
