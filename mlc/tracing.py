"""Trace columns for named devices: `hil run --trace-signals M31064,M21016,D31048,X0,Y3,…`.

`SignalSource` is a trace source (``columns`` + ``values(runner)``): one column per device, named
by its address, holding 0/1 for a relay and the register's value read with its App. B width.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from mlc.memory import DeviceMemory
from mlc.signals import Signal, resolve


def parse_signal_list(text: str, channel: int = 1) -> list[Signal]:
    """``"M31064,M21016,D31048"`` or names (``M_STROBE,MST_FINISH``); raises DeviceError on a bad one."""
    return [resolve(s.strip(), channel) for s in text.split(",") if s.strip()]


def value_of(mem: DeviceMemory, sig: Signal) -> float | int:
    n = sig.number
    if sig.kind == "M":
        return int(mem.bit(n))
    if sig.kind == "A":
        return int(mem.alarm(n))
    if sig.kind in ("X", "Y"):  # remote I/O points (mlc/remote_io.py)
        return int(mem.get(sig.address))
    if sig.width == "f32":
        return float(mem.f32(n))
    return {"u16": mem.u16, "s16": mem.s16, "u32": mem.u32}.get(sig.width, mem.u16)(n)


class SignalSource:
    def __init__(self, mem: DeviceMemory, signals: Sequence[Signal]) -> None:
        self.mem = mem
        self.signals = list(signals)
        self.columns = [s.address for s in self.signals]

    def values(self, runner: Any = None) -> list[float | int]:
        return [value_of(self.mem, s) for s in self.signals]
