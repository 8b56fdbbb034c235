"""The canonical output of the interpreter: motion in machine coordinates plus auxiliary events.

This is the narrow seam between `nc.interp` and everything downstream (`nc.motion`, `hil path`).
Coordinates are machine coordinates per axis name, as the axis travels (a lathe X is a radius);
``work`` is the end point as the program writes it in the active work system (X as a diameter
in diameter mode).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Union

MoveKind = Literal["rapid", "line", "arc", "thread", "dwell"]


@dataclass(slots=True)
class Move:
    kind: MoveKind
    line: int
    block: str
    start: dict[str, float]
    end: dict[str, float]
    work: dict[str, float]
    center: dict[str, float] | None = None
    dir: Literal["cw", "ccw"] | None = None
    feed: float | None = None  # mm/min, or mm/rev when per_rev
    duration: float | None = None  # dwell seconds
    per_rev: bool = False
    plane: tuple[str, str] = ("Z", "X")  # (first, second) axis of the arc plane
    exact_stop: bool = False  # G09 / G61: stop at the end of this move
    lead: float | None = None  # thread lead per spindle revolution (mm/rev)
    lead_change: float = 0.0  # G34 lead increment per revolution
    start_angle: float = 0.0  # thread start angle Q (degrees)
    turns: float = 0.0  # helix: full turns in addition to the plane arc (G02/G03 with P)
    program: str | None = None
    tags: tuple[str, ...] = ()  # e.g. ("G71", "rough") so checks can tell passes apart
    comp: str | None = None  # "G41" / "G42" while tool radius compensation is active for this move
    comp_radius: float = 0.0  # nose / cutter radius in effect (mm)
    tip: int = 0  # lathe imaginary tool-tip number 0-9
    css: float | None = None  # G96 surface speed (m/min) in effect, None under G97

    def replaced(self, **changes) -> "Move":
        """`dataclasses.replace(self, **changes)` without its per-call look at the fields (compensation
        rewrites every move it offsets, issue 16)."""
        new = Move(self.kind, self.line, self.block, self.start, self.end, self.work, self.center, self.dir,
                   self.feed, self.duration, self.per_rev, self.plane, self.exact_stop, self.lead, self.lead_change,
                   self.start_angle, self.turns, self.program, self.tags, self.comp, self.comp_radius, self.tip,
                   self.css)
        for name, value in changes.items():
            setattr(new, name, value)
        return new

    def as_dict(self) -> dict:
        return {
            "kind": self.kind,
            "line": self.line,
            "block": self.block,
            "start": self.start,
            "end": self.end,
            "work": self.work,
            "center": self.center,
            "dir": self.dir,
            "feed": self.feed,
            "duration": self.duration,
        }



@dataclass(slots=True)
class Aux:
    """An M, S or T code (or G900 / spindle mode request) the MLC must acknowledge."""

    kind: Literal["M", "S", "T", "G900"]
    value: float
    line: int
    block: str
    args: dict[str, float] = field(default_factory=dict)
    wait: bool = True  # the block waits for the MLC finish signal
    program: str | None = None

    def as_dict(self) -> dict:
        return {"kind": "aux", "code": self.kind, "value": self.value, "line": self.line,
                "block": self.block, "args": self.args}


@dataclass(slots=True)
class Sync:
    """A preview stop: the interpreter may not read further until motion has finished
    (G05, G10, G31, G53, halt M codes, reads of live positions). G05's carries its group: the channel
    switches the planner's settings there, at rest (decision language L25-1)."""

    line: int
    block: str
    reason: str
    group: int | None = None  # G05 P: the parameter group the motion after it uses (0: the original settings)
    program: str | None = None

    def as_dict(self) -> dict:
        d = {"kind": "sync", "line": self.line, "block": self.block, "reason": self.reason}
        if self.group is not None:
            d["group"] = self.group
        return d


@dataclass(slots=True)
class ProgramEnd:
    """M02 / M30 (or end of file; a main program's M99 under M99 Call Stop): the channel finishes once motion drains."""

    line: int
    block: str
    code: int  # 2, 30, 99 (M99 Call Stop), or 0 for the end of the text
    rewind: bool = True

    def as_dict(self) -> dict:
        return {"kind": "end", "line": self.line, "block": self.block, "code": self.code}


@dataclass(slots=True)
class MainLoop:
    """M99 of the main program: it runs again from its start (or from the label M99 P names). An M code: the motion
    before it runs out to rest, and the program ends there when the MLC's M99 Call Stop (M2x026) is ON
    (nc.channel, decision mlc M25-1)."""

    line: int
    block: str

    def as_dict(self) -> dict:
        return {"kind": "m99", "line": self.line, "block": self.block}


@dataclass(slots=True)
class Busy:
    """Not part of the program: the interpreter has spent this cycle's macro statement budget
    (`nc.budget`, decisions B2) and reads on next cycle. Stream stages pass it on at once."""

    def as_dict(self) -> dict:
        return {"kind": "busy"}


BUSY = Busy()

Event = Union[Move, Aux, Sync, ProgramEnd, MainLoop, Busy]


@dataclass(slots=True)
class MoveBatch:
    """A run of plain rapids and lines (G0/G1 with axis words and F, nothing else) read in bulk by
    `nc.interp.bulk` for a consumer that asked for it (`hil path`, issue 16): the moves as columns.
    `moves()` gives exactly the Move objects the block-by-block path makes; a stream stage that
    holds state (a pending ,C/,R corner, radius compensation) expands the batch into them."""

    axes: tuple[str, ...]
    lines: list[int]  # file line of each move
    texts: list[str]  # block text of each move
    rapid: list[bool]  # G00 (True) or G01 per move
    start: dict[str, float]  # machine position before the first move
    end: list[list[float]]  # machine end points: one column (a value per move) per axis, axes order
    work: list[list[float]]  # work end points as the program writes them, columns likewise
    feed: list[float | None]  # None for a rapid
    per_rev: bool
    program: str
    plane: tuple[str, str]
    css: float | None

    def __len__(self) -> int:
        return len(self.lines)

    @property
    def line(self) -> int:  # the last move's, as a Move's (the preview window's "executing" block)
        return self.lines[-1]

    @property
    def block(self) -> str:
        return self.texts[-1]

    def moves(self) -> list[Move]:
        axes, out = self.axes, []
        start = dict(self.start)
        for i, (line, e, w) in enumerate(zip(self.lines, zip(*self.end), zip(*self.work))):
            end = dict(zip(axes, e))
            rapid = self.rapid[i]
            out.append(Move("rapid" if rapid else "line", line, self.texts[i], start, end, dict(zip(axes, w)),
                            feed=self.feed[i], per_rev=False if rapid else self.per_rev, program=self.program,
                            plane=self.plane, css=self.css))
            start = dict(end)
        return out


@dataclass(slots=True)
class MoveList:
    """A lathe cycle's Moves as one event, for a consumer that takes MoveBatch events (`hil path`,
    issue 16): the thousands of moves of a G71 pass the corner, compensation and preview stages once
    instead of one by one. Made only of plain Move objects without radius compensation, computed
    before the first is handed on (a cycle that streams its moves keeps streaming them); a stage that
    holds state expands it with `moves()`, as it does a MoveBatch."""

    items: list[Move]

    def __len__(self) -> int:
        return len(self.items)

    @property
    def line(self) -> int:  # the last move's, as a MoveBatch's
        return self.items[-1].line

    @property
    def block(self) -> str:
        return self.items[-1].block

    def moves(self) -> list[Move]:
        return self.items
