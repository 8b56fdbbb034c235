"""What the cycle families share (split from nc/cycles/dispatch.py, issue 16): the block's words as
distances, the cycle memory of the modal and two-block cycles, the PathBuilder a cycle draws with and
the hand-over of its events and end position to the interpreter."""

from __future__ import annotations

import weakref
from collections.abc import Iterable, Iterator
from typing import Any

from nc.cycles.builder import PathBuilder
from nc.cycles.codes import LATHE_CYCLES, MILL_CYCLES
from nc.moves import Event
from nc.program.blocks import Block

LATHE_PLANE = ("Z", "X")

_memory: "weakref.WeakKeyDictionary[Any, dict]" = weakref.WeakKeyDictionary()


def _mem(host: Any) -> dict:
    own = getattr(host, "cycle_memory", None)
    if isinstance(own, dict):  # the interpreter's own store, so G80 can clear it (`Interpreter._set_modal`)
        return own
    try:
        return _memory.setdefault(host, {})
    except TypeError:  # not weak-referenceable: keep the memory on the host itself
        if not hasattr(host, "_cycle_memory"):
            host._cycle_memory = {}
        return host._cycle_memory


def _d(host: Any, block: Block, letter: str, default: float | None = None) -> float | None:
    w = block.get(letter)
    return host.distance(w) if w is not None else default


def _raw(block: Block, letter: str, default: float | None = None) -> float | None:
    w = block.get(letter)
    return w.value if w is not None else default


def _is_diameter(host: Any, axis: str = "X") -> bool:
    return axis in host.profile.diameter_axes


def _builder(host: Any, block: Block, plane: tuple[str, str] = LATHE_PLANE) -> PathBuilder:
    convert = getattr(host, "work_converter", None)  # the offsets hold through a cycle: precomputed
    return PathBuilder(dict(host.position), plane, block.line, block.text,
                       convert() if convert is not None else host.to_work,
                       getattr(host, "program_name", None), per_rev=bool(host.state.per_rev),
                       css=host.state.surface_speed if host.state.css else None)  # G96 holds in cycles


def _finish(host: Any, b: PathBuilder) -> list[Event]:
    host.position = dict(b.position)
    return b.events


def _stream(host: Any, b: PathBuilder, steps: Iterable[object]) -> Iterator[Event]:
    """Hand the builder's events on as the cycle makes them, one step (hole, peck, pass) at a time:
    K999999999 or P1 Q1 pecks keep memory flat and the run can be stopped meanwhile (decisions B1).
    `host.position` moves to the cycle's end once it is done, as `_finish` does."""
    for _ in steps:
        if b.events:
            yield from b.events
            b.events.clear()
    host.position = dict(b.position)
    yield from b.events
    b.events.clear()


def _has_any(block: Block, letters: str) -> bool:
    return any(block.has(c) for c in letters)


def _target(host: Any, block: Block) -> dict[str, float]:
    return host.to_machine(host.target(block))


def _modal_target(host: Any, block: Block, code: str, axes_letters: dict[str, str]) -> dict[str, float]:
    """End point of a modal lathe cycle: axes not written keep the cycle's previous end point."""
    mem = _mem(host).setdefault("single", {})
    tgt = _target(host, block)
    prev = mem.get(code)
    if prev is not None and _explicit(host, block, code) is False:
        for axis, inc in axes_letters.items():
            if not block.has(axis) and not block.has(inc):
                tgt[axis] = prev[axis]
    mem[code] = dict(tgt)
    return tgt


def _modal_taper(host: Any, block: Block, code: str) -> float:
    """R of G90/G92/G94 is modal like X and Z (Fanuc): a repeat block without R keeps it."""
    mem = _mem(host).setdefault("taper", {})
    if block.has("R"):
        mem[code] = host.distance(block.get("R"))
    elif _explicit(host, block, code):
        mem[code] = 0.0
    return mem.get(code, 0.0)


def _explicit(host: Any, block: Block, code: str) -> bool:
    """Does the block itself carry the cycle's G code (a new cycle rather than a modal repeat)?"""
    if host.profile.is_lathe:
        table = LATHE_CYCLES.get(host.profile.lathe_type or "A", {})
    else:
        table = MILL_CYCLES
    for w in block.all("G"):
        if table.get(int(round(w.value))) == code and abs(w.value - round(w.value)) < 1e-9:
            return True
    return False
