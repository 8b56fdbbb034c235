"""Delta alarms as values and as the exception that carries them out of the NC.

A system alarm is a 16-bit code written ``0xHHHH`` (NC5 App. A.1). A servo pass-through alarm
is ``0xF002`` with the drive's own code as ``info``; MLC user alarms are ``A<n>``; macro alarms
raised by ``#20020 = n`` are ``MR<n>``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from nc.alarm_table import ALARM_TABLE

SERVO_ALARM = 0xF002


BLOCK_SHOWN = 200  # characters of a block (and 2x of a message) an alarm shows: a 10 MB line is named, not echoed


def clipped(block: str | None, limit: int = BLOCK_SHOWN) -> str | None:
    if block is None or len(block) <= limit:
        return block
    return f"{block[:limit]}… ({len(block)} characters)"


def alarm_name(code: int) -> str:
    entry = ALARM_TABLE.get(code)
    return entry[1] if entry else "Unlisted alarm."


@dataclass(frozen=True)
class Alarm:
    """One raised alarm: what, where in the program, and (for axis alarms) which axis."""

    code: int | str  # 0xHHHH, or "A12" / "MR5" for user and macro alarms
    message: str
    line: int | None = None
    block: str | None = None
    program: str | None = None
    axis: str | None = None
    info: int | None = None  # servo alarm sub-code for 0xF002, station for bus alarms

    @property
    def code_text(self) -> str:
        return self.code if isinstance(self.code, str) else f"0x{self.code:04X}"

    def as_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"kind": "alarm", "code": self.code_text, "line": self.line,
                             "block": clipped(self.block),
                             "message": clipped(self.message, 2 * BLOCK_SHOWN)}
        if self.program is not None:
            d["program"] = self.program
        if self.axis is not None:
            d["axis"] = self.axis
        if self.info is not None:
            d["info"] = f"0x{self.info:02X}"
        return d

    def __str__(self) -> str:
        where = ""
        if self.line is not None:
            where = f" at line {self.line}"
            if self.program:
                where = f" in {self.program}" + where
        extra = f" axis {self.axis}" if self.axis else ""
        if self.info is not None:
            extra += f" (servo alarm 0x{self.info:02X})"
        blk = f": {clipped(self.block.strip())}" if self.block else ""
        return f"ALARM {self.code_text}{extra}{where}{blk} -- {clipped(self.message, 2 * BLOCK_SHOWN)}"


class NcAlarm(Exception):
    """Raised inside the NC; the channel turns it into a stop and an `Alarm` record."""

    def __init__(self, code: int | str, message: str | None = None, *, line: int | None = None,
                 block: str | None = None, program: str | None = None, axis: str | None = None,
                 info: int | None = None) -> None:
        if message is None:
            message = alarm_name(code) if isinstance(code, int) else str(code)
        self.alarm = Alarm(code, message, line, block, program, axis, info)
        self.caller_missing = False  # set by the program store: the next `at` adds the calling block
        super().__init__(str(self.alarm))

    def at(self, line: int | None, block: str | None, program: str | None = None) -> "NcAlarm":
        """Fill in the program position if the raiser did not know it."""
        a = self.alarm
        if a.line is None:
            self.alarm = Alarm(a.code, a.message, line, block, program or a.program, a.axis, a.info)
        elif self.caller_missing and line is not None:
            # raised while loading a subprogram file: it names that file and line; add the call site
            where = f"called from line {line}" + (f" of {program}" if program else "")
            self.alarm = Alarm(a.code, f"{a.message} ({where}: {clipped((block or '').strip(), 80)})",
                               a.line, a.block, a.program, a.axis, a.info)
        elif a.program is None and program is not None:
            self.alarm = Alarm(a.code, a.message, a.line, a.block, program, a.axis, a.info)
        self.caller_missing = False
        self.args = (str(self.alarm),)
        return self


def internal_error(exc: BaseException, line: int | None = None, block: str | None = None,
                   program: str | None = None) -> Alarm:
    """0x0000 'NC internal error' for anything unexpected, so a user never sees a traceback."""
    return Alarm(0x0000, f"NC internal error: {type(exc).__name__}: {exc}", line, block, program)
