"""Checks on what a `hil script` passes to the `Machine` API (decision bench B80).

A duration of -1 s, NaN or infinity, a fractional number of MPG detents or a jog direction of 0 would
otherwise run one cycle, raise a bare ValueError/OverflowError from deep inside, or never end; each is
refused here with the call and the value, as a `ScriptError` (`hil script` names the script's line)."""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import Any


class ScriptError(Exception):
    """A script asked for something the bench cannot do (unknown axis, timeout, a bad argument …)."""


def seconds(call: str, value: Any, positive: bool = False) -> float:
    """A simulated duration: a finite real number, >= 0 (or > 0 where 0 could never be met)."""
    if isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value) \
            and (value > 0 if positive else value >= 0):
        return float(value)
    raise ScriptError(f"{call}: {value!r} is not a duration: simulated seconds, a finite number "
                      f"{'> 0' if positive else '>= 0'}")


def whole(call: str, what: str, value: Any, low: int, high: int | None = None, span: str | None = None) -> int:
    """An integer argument within [low, high] (a bool or 2.5 is none: they hide a mistake)."""
    if isinstance(value, Integral) and not isinstance(value, bool) and value >= low \
            and (high is None or value <= high):
        return int(value)
    span = span or (f"{low}-{high}" if high is not None else f">= {low}")
    raise ScriptError(f"{call}: {what} {value!r} must be a whole number {span}")


def number(call: str, what: str, value: Any) -> float:
    """A finite real number (a speed, a value to write)."""
    if isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    raise ScriptError(f"{call}: {what} {value!r} must be a finite number")


def text(call: str, what: str, value: Any) -> str:
    if isinstance(value, str):
        return value
    raise ScriptError(f"{call}: {what} {value!r} must be a string")
