"""Constants and small records of the interpreter: limits, letter tables, the call frame, the
preview record and per-block geometry (plain data, no behaviour)."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field

from nc.profiles import Profile
from nc.program.blocks import Program


M_BEFORE_MOTION = {3, 4, 8, 19, 29}  # issued to the MLC before the block's motion starts
M_END = {2, 30}
# Codes whose axis words name a centre or the axes concerned, never a target: no motion in their block.
TRANSFORM_ARG_FUNCS = frozenset({"scale", "mirror", "mirror_off", "G68"})
CHORD_TOL_3D = 0.0005  # mm: G2.4/G3.4 chords deviate from the arc by at most 0.5 µm
# App. A 0x025F, N§3.12.5: refused while G68 rotation is on, until G69
REFUSED_UNDER_G68 = frozenset({"G54", "G55", "G56", "G57", "G58", "G59", "G28", "G29", "G30", "G2.4", "G3.4"})
# Non-modal codes whose block runs no motion of the current motion mode (the code itself moves or not).
NO_MOTION_FUNCS = frozenset({"G04", "G10", "G11", "G28", "G29", "G30", "G31", "G52", "G53", "set", "G05",
                             "G70", "G71", "G72", "G73", "G74", "G75", "G76", "G900", "G84.48"})
MAX_M_PER_BLOCK = 4
MAX_MACRO_DEPTH = 8  # G65/G66/G-M-T calls (0x0212)
MAX_SUB_DEPTH = 8  # M98 (0x022D)
MAX_IF_DEPTH = 5
MAX_WHILE_DEPTH = 3
INCREMENTAL = {"U": "X", "V": "Y", "W": "Z", "H": "C"}
ARG_LETTERS = {"A": 1, "B": 2, "C": 3, "D": 4, "E": 5, "F": 6, "H": 8, "I": 9, "J": 10, "K": 11, "M": 13,
               "Q": 17, "R": 18, "S": 19, "T": 20, "U": 21, "V": 22, "W": 23, "X": 24, "Y": 25, "Z": 26}
LETTERS = set("ABCDEFGHIJKLMNPQRSTUVWXYZ")


@dataclass
class _Geometry:
    """Per-block numbers after unit, diameter and decimal-point rules."""

    target_work: dict[str, float]
    target_machine: dict[str, float]
    moved: bool
    axes: set[str] = field(default_factory=set)


@dataclass(slots=True)
class Frame:
    program: Program
    pc: int = 0
    kind: str = "main"  # main | m98 | g65 | g66 | gcall | mcall | tcall | m96
    locals_pushed: bool = False
    repeat: int = 1
    loops: list[tuple[int, int, int | None]] = field(default_factory=list)  # (while pc, end pc, id)
    ifs: list[int] = field(default_factory=list)  # ENDIF pcs of the open IF-THEN blocks
    call_code: str | None = None  # "G100" / "M100" / "T" while executing a code-called macro
    restarts: int = 0
    args: dict[int, float] | None = None  # the call's arguments: every L repetition starts from them
    entry: int = 0  # where each repetition starts (M98 H/Q enter mid-program)


@dataclass
class PreviewRecord:
    """A macro statement and the motion block the machine was executing when it ran (preview)."""

    line: int
    block: str
    program: str
    ahead_of_line: int | None = None
    ahead_of_block: str | None = None
    blocks_ahead: int = 0


def _log_length(profile: Profile) -> int | None:
    """Profile parameter "preview log": how many statements the preview log keeps (< 0: all)."""
    v = profile.param("preview log", 1000)
    try:
        n = int(v)
    except (TypeError, ValueError, OverflowError):
        return 1000
    return None if n < 0 else n


def _transforms(host):
    """`nc.transforms` (issue 4) when scaling, mirror or rotation is active, else None. The module is
    loaded by the first G50.1/G51/G68 (ModalMixin); until then none can be active, and a program
    without them never loads it (start-up, issue 16)."""
    tr = sys.modules.get("nc.transforms")
    if tr is None:
        return None
    try:
        return tr if tr.stack(host).active else None
    except AttributeError:
        return None


def _compensation():
    try:
        from nc.compensation.stream import compensate
    except ImportError:
        return None
    return compensate
