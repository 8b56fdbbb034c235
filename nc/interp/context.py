"""The host API a canned-cycle handler (issue 4, `nc.cycles`) gets from the interpreter.

The interpreter owns the program counter, modal state, variables and coordinate frames; a cycle
handler owns only geometry.  For every block whose group-01/09 code is a cycle G code, the
interpreter calls::

    nc.cycles.dispatch.run_cycle(host, code, block) -> Iterator[Event]

where ``host`` is a :class:`CycleHost` (the running `Interpreter`), ``code`` is the cycle's
*function name* independent of the lathe type (see :data:`CYCLE_NAMES`), and ``block`` is the block
with every macro expression already evaluated (``Word.value`` are plain floats).  A modal cycle
(lathe G90/G92/G94, milling G73/G74/G76/G81–G89, lathe hole cycles) is called again for every
following block that carries axis words, with that block, until G80 or another group-01 code;
``host.cycle_modal`` keeps the words of the block that started the cycle so a handler can take
omitted arguments (R, Q, P, F, K …) from there.

If ``nc.cycles.dispatch`` cannot be imported the interpreter raises 0x021D "not supported".

Positions: ``host.position`` is the machine position (lathe X as a radius), ``host.work_position()``
the programmed one (X as a diameter in diameter mode).  ``host.to_machine(work)`` converts a
programmed position to machine coordinates through the active work offset, G52, G92/G50 and the
diameter rule.  ``host.emit_*`` build Moves that carry line/block/program/plane/feed correctly and
advance ``host.position``; a handler yields what they return.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Protocol

from nc.alarms import NcAlarm

if TYPE_CHECKING:  # pragma: no cover - typing only
    from nc.interp.state import ModalState
    from nc.moves import Event, Move
    from nc.profiles import Profile
    from nc.program.blocks import Block, Word

# the code tables live in nc.cycles.codes (a leaf: nc.cycles.dispatch reads them without importing
# this module back); re-exported here for their old users
from nc.cycles.codes import LATHE_CYCLES, MILL_CYCLES, MODAL_CYCLES  # noqa: E402,F401


class CycleHost(Protocol):
    """What a cycle handler may use.  `nc.interp.Interpreter` implements it."""

    profile: "Profile"
    state: "ModalState"  # modal state (read; a handler must not change groups)
    position: dict[str, float]  # machine position now (lathe X radius)
    program_name: str
    cycle_modal: dict[str, float]  # words of the block that started the active modal cycle
    block: "Block"  # the block being executed (same object handed to run_cycle)

    def work_position(self) -> dict[str, float]: ...
    def to_machine(self, work: dict[str, float]) -> dict[str, float]: ...
    def to_work(self, machine: dict[str, float]) -> dict[str, float]: ...
    def distance(self, word: "Word", axis: str | None = None) -> float:
        """Word value in mm: decimal-point rule (N8.018 Bit10), inch (G20), no diameter halving."""
    def target(self, block: "Block") -> dict[str, float]:
        """Programmed end point of the block's axis words (X/U, Z/W …, G90/G91) in work coordinates."""
    def feed(self, block: "Block | None" = None) -> float:
        """Modal F in mm/min or mm/rev (alarm 0x1001 if none)."""
    def contour_blocks(self, p: int, q: int) -> list["Block"]:
        """Blocks from N p to N q of the current program (expressions evaluated), 0x0264 if missing."""
    def contour_moves(self, blocks: list["Block"], start: dict[str, float] | None = None) -> list["Move"]:
        """Interpret contour blocks on a copy of the state (no side effects, ,C/,R expanded)."""
    def emit_rapid(self, work: dict[str, float], tags: tuple[str, ...] = ()) -> "Move": ...
    def emit_line(self, work: dict[str, float], feed: float | None = None, tags: tuple[str, ...] = (),
                  per_rev: bool | None = None) -> "Move": ...
    def emit_arc(self, work: dict[str, float], center_work: dict[str, float], cw: bool,
                 feed: float | None = None, tags: tuple[str, ...] = ()) -> "Move": ...
    def emit_thread(self, work: dict[str, float], lead: float, lead_change: float = 0.0,
                    start_angle: float = 0.0, tags: tuple[str, ...] = ()) -> "Move": ...
    def emit_dwell(self, seconds: float, tags: tuple[str, ...] = ()) -> "Move": ...
    def emit_aux(self, kind: str, value: float) -> "Event": ...


RunCycle = Callable[[CycleHost, str, "Block"], Iterator["Event"]]
_MISSING = object()
_cache: Any = None


def cycle_runner() -> RunCycle | None:
    """`nc.cycles.dispatch.run_cycle` if issue 4's package is present, else None (imported once)."""
    global _cache
    if _cache is None:
        try:
            mod = importlib.import_module("nc.cycles.dispatch")
            _cache = getattr(mod, "run_cycle", _MISSING)
        except ImportError:
            _cache = _MISSING
    return None if _cache is _MISSING else _cache


def run_cycle(host: CycleHost, code: str, block: "Block") -> Iterator["Event"] | list["Event"]:
    runner = cycle_runner()
    if runner is None:
        raise NcAlarm(0x021D, f"cycle {code} is not supported in this build (nc.cycles missing)")
    return runner(host, code, block)
