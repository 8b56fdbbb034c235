"""Servo (drive) parameters from a program: G10 L40/L41/L45/L46 with #20023 / #20024 (NC5 App. B.3.4.1).

- ``G10 L40 I_ P_ D_``      read Delta servo parameter P<P>-<D> of the drive at station I
- ``G10 L41 I_ P_ D_ R_``   write R into it
- ``G10 L45 I_ P_ D_``      read CoE / CANopen object P (index, decimal), sub-index D, of station I
- ``G10 L46 I_ P_ D_ R_``   write R into that object

After each one #20023 holds the value read (after a write: read back from the drive) and #20024
the execution result, 0 when it succeeded.  The manual names the addresses I/P/D and the variables
only; the write word R, the station numbering and the result codes are decisions
(docs/decisions/mlc.md, "servo parameters from a program").

`nc` knows no bus: the bench installs ``ServoPort.handler`` (a callable taking a `ServoAccess`
and returning a `ServoReply`).  G10 stops preview, so by the time the handler runs every motion
block before it has finished; the interpreter then reads on with the reply in #20023/#20024.
Without a handler (offline ``hil path``) nothing is sent: a read leaves #20023 vacant and puts
`RESULT_OFFLINE` in #20024, a write is only listed (``ServoPort.log``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

from nc.alarms import NcAlarm

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.host import InterpHost
    from nc.program.blocks import Block

SERVO_ALARM_SYNTAX = 0x0252  # App. A: usage error of G10 L40 / L41 (servo parameter read / write)
SERVO_L = {40: ("param", False), 41: ("param", True), 45: ("object", False), 46: ("object", True)}
RESULT_OK = 0
RESULT_NO_ANSWER = -1  # the drive did not answer (timeout, bus down)
RESULT_OFFLINE = -2  # no bus behind the interpreter (hil path): nothing was sent
PARAM_GROUPS = range(0, 10)  # Pn-xx: n 0-9 (ASDA-A3 uses P0-P8)
PARAM_NUMBERS = range(0, 128)  # xx 0-127 (Modbus address 0x100*n + 2*xx stays inside the group)


@dataclass(frozen=True)
class ServoAccess:
    """One G10 L4x request, in bus-neutral terms."""

    station: int  # I: 1 = the bench's first drive (axes in order, then spindles)
    kind: Literal["param", "object"]
    index: int  # parameter group n (Pn-xx), or the object index
    sub: int  # parameter number xx, or the sub-index
    value: int | None = None  # the value to write; None for a read
    line: int = 0
    block: str = ""

    @property
    def write(self) -> bool:
        return self.value is not None

    @property
    def label(self) -> str:
        return f"P{self.index}-{self.sub:02d}" if self.kind == "param" else f"object 0x{self.index:04X}:{self.sub}"

    def describe(self) -> str:
        what = f"write {self.label} = {self.value}" if self.write else f"read {self.label}"
        return f"{what} on station {self.station}"


@dataclass(frozen=True)
class ServoReply:
    value: int | None  # the value read (read back after a write); None when the access failed
    result: int = RESULT_OK  # #20024: 0, an SDO abort code, a Modbus exception code, or RESULT_*
    message: str = ""  # why it failed, for the alarm text

    @property
    def ok(self) -> bool:
        return self.result == RESULT_OK


ServoHandler = Callable[[ServoAccess], ServoReply]


@dataclass
class ServoPort:
    """The interpreter's side of servo parameter access: the handler, #20023/#20024 and a log."""

    handler: ServoHandler | None = None
    value: float | None = 0.0  # #20023
    result: float = 0.0  # #20024
    log: list[tuple[ServoAccess, ServoReply]] = field(default_factory=list)
    # A refused access raises 0x0252 (default); with False it only sets #20024 and the program reads on.
    alarm_on_error: bool = True


def _int_word(block: "Block", letter: str, span: range, what: str) -> int:
    w = block.get(letter)
    if w is None:
        raise NcAlarm(SERVO_ALARM_SYNTAX, f"G10 L{int(block.get('L').value)} needs {letter} ({what})")
    if w.value != int(w.value) or int(w.value) not in span:
        raise NcAlarm(SERVO_ALARM_SYNTAX, f"{letter}{w.value:g} ({what}) must be an integer "
                                          f"{span.start}-{span.stop - 1}")
    return int(w.value)


def parse_access(block: "Block", L: int) -> ServoAccess:
    """The request a G10 L40/L41/L45/L46 block makes; 0x0252 for any syntax error."""
    kind, write = SERVO_L[L]
    station = _int_word(block, "I", range(1, 256), "station address")
    if kind == "param":
        index = _int_word(block, "P", PARAM_GROUPS, "parameter group")
        sub = _int_word(block, "D", PARAM_NUMBERS, "parameter number")
    else:
        index = _int_word(block, "P", range(0, 0x10000), "object index")
        sub = _int_word(block, "D", range(0, 0x100), "sub-index")
    value = None
    if write:
        value = _int_word(block, "R", range(-2**31, 2**31), "value")
    elif block.get("R") is not None:
        raise NcAlarm(SERVO_ALARM_SYNTAX, f"G10 L{L} reads; R is only for L{L + 1}")
    return ServoAccess(station, kind, index, sub, value, block.line, block.text.strip())


def servo_g10(ip: "InterpHost", block: "Block", L: int) -> None:
    """Run one G10 L4x: ask the bench (motion before it has finished: G10 stopped preview)."""
    req = parse_access(block, L)
    port = ip.servo
    if port.handler is None:
        reply = ServoReply(None, RESULT_OFFLINE, "no bus (offline): nothing was sent")
    else:
        reply = port.handler(req)
    port.log.append((req, reply))
    port.value = None if reply.value is None else float(reply.value)
    port.result = float(reply.result)
    if not reply.ok and reply.result != RESULT_OFFLINE and port.alarm_on_error:
        raise NcAlarm(SERVO_ALARM_SYNTAX, f"servo parameter {req.describe()} failed: {reply.message} "
                                          f"(#20024 = {reply.result})")
