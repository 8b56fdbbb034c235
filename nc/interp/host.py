"""What the interpreter's helper modules (corners, preview, data setting, servo port, system
variables) see of the interpreter: a Protocol, so they are typed without importing
nc.interp.interpreter back (no import circle, issue 16)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from nc.interp.state import Frames, ModalState
    from nc.interp.tools import ToolTable
    from nc.interp.variables import Variables
    from nc.moves import Event, Move
    from nc.profiles import Profile
    from nc.program.blocks import Block


class InterpHost(Protocol):
    profile: Profile
    axes: tuple[str, ...]
    state: ModalState
    frames: Frames
    position: dict[str, float]
    tools: ToolTable
    vars: Variables
    block: Block | None
    program_name: str
    preview_log: Any
    on_statement: Any
    corner_pending: bool  # set by nc.interp.corners.expand_corners, read by the program counter

    def to_work(self, machine: dict[str, float]) -> dict[str, float]: ...
    def to_machine(self, work: dict[str, float]) -> dict[str, float]: ...
    def work_position(self) -> dict[str, float]: ...
    def emit_line(self, work: dict[str, float], feed: float | None = None, tags: tuple[str, ...] = (),
                  **kw: Any) -> Move: ...
    def emit_arc(self, work: dict[str, float], center_work: dict[str, float], cw: bool, **kw: Any) -> Move: ...
    def _execute(self, raw: Block) -> Iterator[Event]: ...
