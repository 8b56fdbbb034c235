"""Reading fields out of TOML tables with one error per bad field (bench files, campaign specs).

Every error names the file and the field path (`axes[1].counts_per_rev`) with what was expected
and what was found; the readers collect them so that all problems in a file are reported at once.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from hil.session import InputError


class BenchFileError(InputError):
    """A bench file that cannot be used; `errors` holds one `path: message` per bad field."""

    def __init__(self, source: str, errors: list[str]) -> None:
        self.errors = errors
        super().__init__("\n".join(f"{source}: {e}" for e in errors))


def kind_of(v: Any) -> str:
    """A TOML value as an error message names it."""
    if isinstance(v, bool):
        return f"{str(v).lower()} (a boolean)"
    if isinstance(v, dict):
        return "a table"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, str):
        return repr(v)
    return repr(v)


class FieldReader:
    """Takes fields out of a TOML table, recording an error per bad field instead of stopping."""

    def __init__(self) -> None:
        self.errors: list[str] = []
        self.base = Path(".")  # relative paths in the file (canopen_eds) are relative to the file

    def err(self, path: str, msg: str) -> None:
        self.errors.append(f"{path}: {msg}")

    def table(self, data: dict, key: str, path: str) -> dict:
        v = data.pop(key, {})
        if not isinstance(v, dict):
            self.err(path, f"must be a table, got {kind_of(v)}")
            return {}
        return v

    def unknown(self, data: dict, prefix: str, allowed: set[str] | None = None) -> None:
        for k in data:
            hint = ""
            if allowed:
                close = [a for a in sorted(allowed) if a[:3] == k[:3]]
                hint = f" (did you mean {close[0]!r}?)" if close else ""
            self.err(f"{prefix}{k}", f"unknown key{hint}")

    def number(self, data: dict, key: str, path: str, default: float | None, *, positive: bool = False,
               minimum: float | None = None, maximum: float | None = None) -> float | None:
        if key not in data:
            return default
        v = data.pop(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.err(path, f"must be a number, got {kind_of(v)}")
            return default
        v = float(v)
        if v != v or v in (float("inf"), float("-inf")):
            self.err(path, f"must be a finite number, got {v}")
        elif positive and v <= 0:
            self.err(path, f"must be a positive number, got {v:g}")
        elif minimum is not None and v < minimum:
            self.err(path, f"must be at least {minimum:g}, got {v:g}")
        elif maximum is not None and v > maximum:
            self.err(path, f"must be at most {maximum:g}, got {v:g}")
        else:
            return v
        return default

    def integer(self, data: dict, key: str, path: str, default: int | None, *, positive: bool = False,
                choices: tuple[int, ...] | None = None, minimum: int | None = None,
                maximum: int | None = None) -> int | None:
        if key not in data:
            return default
        v = data.pop(key)
        what = "a positive integer" if positive else "an integer"
        if isinstance(v, bool) or not isinstance(v, int):
            self.err(path, f"must be {what}, got {kind_of(v)}")
        elif positive and v <= 0:
            self.err(path, f"must be {what}, got {v}")
        elif choices is not None and v not in choices:
            self.err(path, f"must be one of {', '.join(map(str, choices))}, got {v}")
        elif minimum is not None and v < minimum:
            self.err(path, f"must be at least {minimum}, got {v}")
        elif maximum is not None and v > maximum:
            self.err(path, f"must be at most {maximum}, got {v}")
        else:
            return v
        return default

    def string(self, data: dict, key: str, path: str, default: str | None,
               choices: tuple[str, ...] | None = None) -> str | None:
        if key not in data:
            return default
        v = data.pop(key)
        if not isinstance(v, str) or not v.strip():
            self.err(path, f"must be a non-empty string, got {kind_of(v)}")
        elif choices is not None and v not in choices:
            self.err(path, f"must be one of {', '.join(repr(c) for c in choices)}, got {v!r}")
        else:
            return v
        return default

    def boolean(self, data: dict, key: str, path: str, default: bool) -> bool:
        if key not in data:
            return default
        v = data.pop(key)
        if not isinstance(v, bool):
            self.err(path, f"must be true or false, got {kind_of(v)}")
            return default
        return v

    def eds(self, data: dict, path: str, layout: Any = None, io: tuple[int, int] = (0, 0)) -> str:
        """`canopen_eds`: a device file resolved against the bench file's folder, parsed and checked
        for the objects the CANopen master uses on a drive with this PDO `layout` or on an I/O station
        with `io` = (inputs, outputs) points (fieldbus/canopen/eds_check.py); "" when absent."""
        v = self.string(data, "canopen_eds", path, None)
        if v is None:
            return ""
        from fieldbus.canopen.eds_check import drive_objects, eds_problem, io_objects

        full = (self.base / Path(v).expanduser()).resolve()
        problem = eds_problem(full, drive_objects(layout) if layout is not None else io_objects(*io))
        if problem:
            self.err(path, problem)
            return ""
        return str(full)

    def pair(self, data: dict, key: str, path: str, *, integers: bool, positive: bool) -> tuple | None:
        if key not in data:
            return None
        v = data.pop(key)
        ok_type = (lambda x: isinstance(x, int) and not isinstance(x, bool)) if integers else \
            (lambda x: isinstance(x, (int, float)) and not isinstance(x, bool))
        what = "positive integers" if integers and positive else "numbers"
        if not isinstance(v, list) or len(v) != 2 or not all(ok_type(x) for x in v):
            self.err(path, f"must be an array of two {what}, got {kind_of(v)}")
            return None
        if not all(math.isfinite(x) for x in v):
            self.err(path, f"must be finite numbers, got {v}")
            return None
        if positive and any(x <= 0 for x in v):
            self.err(path, f"must be an array of two {what}, got {v}")
            return None
        return tuple(v)


def read_text_file(path: str | Path, error: type[BenchFileError] = BenchFileError) -> str:
    """A TOML input's text, or `error` naming the file: unreadable, not UTF-8."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise error(str(path), [f"cannot be read: {exc.strerror}"]) from None
    except UnicodeDecodeError:
        raise error(str(path), ["is not UTF-8 text"]) from None
