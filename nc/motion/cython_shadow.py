"""The few names of Cython's pure-Python mode the planner's compiled modules use (decision bench B115), for the
same modules run as Python without Cython installed: `import cython` fails there and this stands in. Compiled,
Cython reads the decorators as types; run as Python they do nothing. Each compiled module spells out its own
`try: import cython` (Cython recognises the literal import only: it cannot come through a shared helper)."""

from __future__ import annotations

from typing import Any, Callable

compiled = False  # Cython's own name (True, folded at compile time, where compiled)
double = float
Py_ssize_t = int
bint = bool


def locals(**_types: Any) -> Callable[[Callable], Callable]:  # noqa: A001 (Cython's name)
    return lambda fn: fn


def returns(_type: Any) -> Callable[[Callable], Callable]:
    return lambda fn: fn


def ccall(fn: Callable) -> Callable:
    return fn


def boundscheck(_flag: bool) -> Callable[[Callable], Callable]:  # a directive compiled (decision bench B163)
    return lambda fn: fn


def wraparound(_flag: bool) -> Callable[[Callable], Callable]:
    return lambda fn: fn
