"""Retentive # variables across runs: `hil run --retain FILE` (`hil.run(..., retain=FILE)`).

The NC5 keeps #2000-#3999 (retentive) and #4000-#11999 (extend) through power-off (N§3.11.1); lathe-2018 its
"non-volatile" #1601-#1800 and #10001-#10450. FILE stands for that memory: a JSON table {"2000": 12.0, ...} read
before the program (no file yet: all vacant, a new controller) and written when the run ends, whatever ended it
(atomically: a run cut short never leaves half a file). A FILE that is not such a table is App. A 0x140B
"Retentive # variable error" (the controller's retentive memory is corrupt): the run does not start and the file
is left as it is for the user to inspect (decisions language.md).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from nc.alarms import NcAlarm
from nc.interp.variables import Variables

RETENTIVE_ERROR = 0x140B


def load(path: str | Path, variables: Variables) -> None:
    """Fill the retentive variables from `path`; NcAlarm 0x140B when it cannot be read as their table."""
    p = Path(path)
    if not p.exists():
        return
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise NcAlarm(RETENTIVE_ERROR, f"retentive variables {p}: cannot be read ({exc})") from None
    if not isinstance(data, dict):
        raise NcAlarm(RETENTIVE_ERROR, f"retentive variables {p}: not a table of variable numbers and values")
    values: dict[int, float] = {}
    for key, value in data.items():
        n = int(key) if key.isdigit() else -1
        if not variables.is_retentive(n):
            raise NcAlarm(RETENTIVE_ERROR, f"retentive variables {p}: #{key} is not a retentive variable")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise NcAlarm(RETENTIVE_ERROR, f"retentive variables {p}: #{n} = {value!r} is not a number")
        values[n] = float(value)
    variables.values.update(values)


def unusable(path: str | Path) -> str | None:
    """Why `path` cannot hold the retentive memory at all (then the run must not start), or None. Checked before the
    drives are enabled: a save that fails only when the run ends loses the run's counts after its axes moved."""
    p = Path(path)
    if p.is_dir():
        return "is a folder, not a file"
    folder = p.parent
    if not folder.is_dir():
        return f"its folder does not exist ({folder})" if str(folder) not in ("", ".") else "its folder does not exist"
    if not os.access(folder, os.W_OK):
        return f"its folder {folder} is not writable"
    return None


def save(path: str | Path, variables: Variables) -> None:
    """Write the retentive variables that hold a value (vacant ones are left out) to `path`, atomically."""
    p = Path(path)
    data = {str(n): v for n, v in sorted(variables.values.items()) if variables.is_retentive(n)}
    tmp = p.with_name(f".{p.name}.tmp")
    try:
        tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        os.replace(tmp, p)
    except OSError:  # a full disk: the last good file stays, and no empty temporary beside it (B97)
        tmp.unlink(missing_ok=True)
        raise
