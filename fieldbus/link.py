"""The bus link seam: one `exchange` per bench cycle, whatever the wire.

`SimLink` is the in-process bus: it hands each slave its outputs, advances simulated time by
exactly one cycle, and returns the inputs (lock-step). EtherCAT and CANopen links implement the
same protocol over a real wire.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from nc.alarms import Alarm


@dataclass
class SlaveInfo:
    position: int  # 0-based position on the bus (axis order)
    name: str
    kind: str  # "drive" or "io"
    vendor_id: int = 0
    product_code: int = 0
    state: str = ""
    layout: str = ""
    drive: str = ""  # a CiA 402 drive's state from 0x6041 over SDO, with its 0x603F error code in fault (scan)


def drive_state_text(statusword: int, error_code: int) -> str:
    """'switch on disabled', 'fault 0x7500': what `hil scan` shows of a drive (its statusword and error code)."""
    from fieldbus.cia402 import State, decode_state

    st = decode_state(statusword)
    fault = st in (State.FAULT, State.FAULT_REACTION_ACTIVE)
    return st.value + (f" 0x{error_code:04X}" if fault else "")


@dataclass
class LinkStatus:
    """The bus as the NC sees it this cycle (M30000, EIO relays M30032+k, drive "connected").

    `states` holds each slave's AL state name ("OP", "SAFE-OP+ERR", "NONE" …) in the order `open()`
    listed the slaves (drives, then I/O modules)."""

    connected: bool  # every slave in OP and no bus alarm raised
    names: list[str] = field(default_factory=list)
    kinds: list[str] = field(default_factory=list)
    states: list[str] = field(default_factory=list)

    def slave_ok(self, position: int) -> bool:
        return position < len(self.states) and self.states[position] == "OP"

    @property
    def io(self) -> list[bool]:
        """One entry per I/O slave in bus (connection) order: True while it is in OP."""
        return [st == "OP" for st, k in zip(self.states, self.kinds) if k == "io"]


class BusError(Exception):
    """A bus fault the bench must turn into an alarm and a controlled stop."""

    def __init__(self, alarm: Alarm) -> None:
        self.alarm = alarm
        super().__init__(str(alarm))


@runtime_checkable
class BusLink(Protocol):
    cycle_time: float

    def open(self) -> list[SlaveInfo]: ...

    def exchange(self, outputs: Sequence[Any]) -> list[Any]: ...

    def close(self) -> None: ...


@runtime_checkable
class SimSlave(Protocol):
    """Anything SimLink can carry: takes outputs, advances dt, returns inputs."""

    name: str

    def exchange(self, rx: Any, dt: float) -> Any: ...


@dataclass
class SimLink:
    slaves: Sequence[SimSlave]
    cycle_time: float = 0.001
    time: float = 0.0
    cycles: int = 0
    infos: list[SlaveInfo] = field(default_factory=list)
    io_devices: list[Any] = field(default_factory=list)  # in-process remote I/O modules (hil/remote_io.py)
    _status: tuple[list[SlaveInfo], int, LinkStatus] | None = field(default=None, repr=False, compare=False)

    def open(self) -> list[SlaveInfo]:
        self.infos = [SlaveInfo(i, s.name, getattr(s, "kind", "drive"), 0x000001DD, 0, "OP", "sim")
                      for i, s in enumerate(self.slaves)]
        return self.infos

    def exchange(self, outputs: Sequence[Any]) -> list[Any]:
        if len(outputs) != len(self.slaves):
            raise ValueError(f"{len(outputs)} output images for {len(self.slaves)} slaves")
        inputs = [s.exchange(o, self.cycle_time) for s, o in zip(self.slaves, outputs)]
        self.time += self.cycle_time
        self.cycles += 1
        return inputs

    def close(self) -> None:
        pass

    def status(self) -> LinkStatus:
        """In-process slaves never leave the line: connected once opened. The same status every cycle
        (the runner reads it each cycle, issue 17), made again when `open` lists the slaves anew."""
        st = self._status
        if st is None or st[0] is not self.infos or st[1] != len(self.infos):
            st = self._status = (self.infos, len(self.infos), LinkStatus(
                bool(self.infos), [i.name for i in self.infos], [i.kind for i in self.infos],
                [i.state for i in self.infos]))
        return st[2]

    # SDO to a simulated slave's object dictionary (Delta servo parameters 0x2000+); same signature
    # as EthercatLink.sdo_read / sdo_write.
    def sdo_read(self, position: int, index: int, sub: int = 0, size: int = 0) -> bytes:
        return self._object_dictionary(position, index, sub).sdo_read(index, sub)

    def sdo_write(self, position: int, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        self._object_dictionary(position, index, sub).sdo_write(index, sub, data)

    def _object_dictionary(self, position: int, index: int = 0, sub: int = 0) -> Any:
        modes = getattr(self.slaves[position], "modes", None)  # CiA 402 profile-mode objects (homing, PP …)
        if modes is not None and modes.holds(index, sub):
            return modes
        od = getattr(self.slaves[position], "servo_params", None)
        if od is None:
            raise ValueError(f"slave {position} ({self.slaves[position].name}) has no object dictionary")
        return od
