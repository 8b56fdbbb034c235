"""An exception in a user's MLC program, as the NC reports it: deltahil alarm 0xDE02 naming the file,
the line and the user's own traceback (frames in deltahil's code are left out: they are not the
user's to fix). Not 0x0000 "NC internal error": the controller is fine, the MLC program is not."""

from __future__ import annotations

import traceback
from pathlib import Path

from nc.alarm_table import MLC_PROGRAM_ERROR
from nc.alarms import Alarm

_OURS = Path(__file__).resolve().parents[1]  # the deltahil checkout / site-packages root


def _is_ours(filename: str) -> bool:
    try:
        p = Path(filename).resolve()
    except OSError:
        return False
    return any(p.is_relative_to(_OURS / pkg) for pkg in ("mlc", "nc", "hil", "fieldbus", "virtual_bus"))


def mlc_program_alarm(exc: BaseException, module_file: str | None) -> Alarm:
    """0xDE02 for `exc` raised in a user's MLC scan; `module_file` is the program's file."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if not _is_ours(f.filename)]
    here = next((f for f in reversed(frames) if module_file and f.filename == module_file), frames[-1] if frames else None)
    where = f"{here.filename} line {here.lineno}" if here else (module_file or "the MLC program")
    tb = "".join(traceback.format_list(frames)).rstrip()
    msg = f"MLC program error in {where}: {type(exc).__name__}: {exc}"
    if tb:
        msg += "\nTraceback (the MLC program's frames):\n" + tb
    return Alarm(MLC_PROGRAM_ERROR, msg)
