"""The lean lane (issue 17): one plain motion line run straight from its text, for the channel.

A CAM program is thousands of lines such as ``X12.5 Y-3.25`` or ``G1 X.. Y.. F1200``. Block by
block, each line is parsed into a Block of Words, read and checked (`_execute`, `_read_run`), and
its move built by `_motion` -> `_geometry` -> `_plain_geometry` -> `_axis_words` through two
generator layers. Here a line whose letters are one of a few shapes (an optional N, at most one
G00/G01, at most one F, axis words of the profile each once) is matched by one compiled pattern
and its Move built in one call, while the modal state is the plain one (`_eligible`: G90, mm, no
radius compensation, no canned cycle, no transforms, no G16, no G66, no code call on G00/G01,
no ,A or G2.4 waiting for its partner, no corner waiting for its motion block).

Each shape's line runs as straight-line code built once per shape and profile (`_compiled`, kept for
all interpreters in `_SHAPES`), and the plain state and the work origin are found once, then kept in
`Interpreter._lean_origin` until anything else may change them: every block `_execute` and every
statement `_statement` runs, any system variable written (an offset, tool data, from a program or
from outside), a run begun, M02/M30's reset, an M96 program started (decisions bench B121).

The Move, the state it leaves (position, last target, F, group 01, `unit_locked`, the block
counter, `block`, `program_name`) and the alarms are those of the general path: any line it
would refuse or treat otherwise (F < 0, a cutting move without F, a target out of range, the
`max blocks` limit, a word without a decimal point) is left to it untouched, and it raises the
alarm at the same block. Unlike nc.interp.bulk (runs of lines as one `MoveBatch` for `hil path`),
it yields Move by Move, so the channel's look-ahead, statement budget, M96 and the preview window
see the same events at the same moments. tests/test_interp_lean.py and tests/test_lean25_equivalence.py
compare both paths. The lines after one this lane ran, of the same shape, are read a chunk at a time by the shape's
`stream` (nc.interp.lean_run, decisions bench B173: the same Moves and state, line by line).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from nc.interp.gcodes import lookup
from nc.interp.lean_run import axes_dict, move_lines, streamed
from nc.interp.records import _transforms
from nc.interp.state import PLANES
from nc.moves import Move
from nc.program.syntax import Block, Word

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.interpreter import Interpreter
    from nc.interp.records import Frame

# A word's number. The lane reads only lines the parser kept as plain text (nc.program.blocks `_PLAIN_ITEM`: every
# word a letter and a valid number), so a shape's pattern only splits them: the run of number characters after
# the letter is the number (a third of the time of matching the number's form again, issue 17)
_NUM = r"([-+.0-9]+)[ \t]*"
_LETTER = re.compile(r"[A-Za-z]")
_G_MOTION = {"0": 0, "00": 0, "000": 0, "1": 1, "01": 1, "001": 1}  # G00 / G01 as programs write them
_UNSEEN = object()
_TEXTS = 4096  # line texts whose shape is kept; then the memo starts over (memory flat)
_SHAPES: dict[tuple, "_Shape | None"] = {}  # `LeanLane._shape`, for all interpreters
NOTHING = object()  # `take`: the line ran and moved nothing (`G1 F100`): no event, as block by block
MISS = object()  # a shape's `run`: the line is not of that shape


class _Shape:
    """The letters of a line in order and what each is: one compiled pattern reads a line of that
    shape (a CAM run is mostly one shape)."""

    __slots__ = ("match", "letters", "n", "g", "f", "axes", "run", "stream")

    def __init__(self, letters: tuple[str, ...], n: bool, g: int | None, f: int | None,
                 axes: tuple[tuple[str, int], ...], run: Callable[..., object]) -> None:
        body = r"[ \t]*" + "".join((r"[Nn]([0-9]+)[ \t]*" if c == "N" else f"[{c}{c.lower()}]" + _NUM)
                                    for c in letters)
        self.match = re.compile(body).fullmatch
        self.letters, self.n, self.g, self.f, self.axes = letters, n, g, f, axes
        self.run = run  # `_compiled`: the line of this shape run, straight-line code
        self.stream: Callable[..., object] | None = None  # `lean_run.streamed`: the lines after it (a shape that moves)


class LeanLane:
    """The lane of one interpreter (its axes and code-call tables decide the shapes it takes)."""

    __slots__ = ("ip", "shapes", "texts", "refused", "last", "axes", "diameter", "g_codes", "tables", "g_ok", "retry",
                 "runs")

    def __init__(self, ip: "Interpreter") -> None:
        self.ip = ip
        self.shapes: dict[tuple[str, ...], _Shape | None] = {}
        self.texts: dict[str, _Shape | None] = {}  # line text -> its shape, for lines `last` did not match
        # id of a program's block list -> (the list, its `raw`, indexes of the lines the lane never takes)
        self.refused: dict[int, tuple[object, Callable[[int], str | None] | None, set[int]]] = {}
        self.last: _Shape | None = None  # the shape of the last line taken: tried first
        self.axes = tuple(a for a in ip.axes if len(a) == 1 and a in ip._plain_axes)
        self.diameter = ip.profile.diameter_axes
        # a G word is taken when G00/G01 are group-01 motion codes no macro is called for (`_g_ok`)
        self.g_codes = lookup(ip.profile, 0.0) == (1, "G00") and lookup(ip.profile, 1.0) == (1, "G01")
        self.tables: object = None  # the code-call tables `g_ok` was found with
        self.g_ok = False
        self.retry = range(0)  # `lean_run`: the lines a run is not tried at (after a chunk it refused; an M99 loop
        # or another call of the program starts below them and tries again)
        self.runs = 0  # chunks `lean_run` has read (tests see the runs were taken)

    def lines(self, blocks: object) -> tuple[tuple | None, set[int]]:
        """A block list's plain-line texts and file lines (`BlockList.text_index`, None for a list of
        blocks) and the indexes of its lines the lane never takes (`M99`, `T0101`, `G90 G54`: by their
        letters), which `_run` runs on the general path without asking again (a macro's M99, 5,000 passes)."""
        hit = self.refused.get(id(blocks))
        if hit is None or hit[0] is not blocks:  # the list is held: its id is not reused meanwhile
            if len(self.refused) >= 64:
                self.refused.clear()
            index = getattr(blocks, "text_index", None)
            hit = self.refused[id(blocks)] = (blocks, None if index is None else index(), set())
        return hit[1], hit[2]

    def _g_ok(self) -> bool:
        """Whether a G00/G01 word may be taken: no macro is called for either, by the tables in force
        (built again after `params_changed`)."""
        ip = self.ip
        if ip._call_tables is None or ip._call_tables is not self.tables:
            self.g_ok = self.g_codes and ip._call_table("G", 0) is None and ip._call_table("G", 1) is None
            self.tables = ip._call_tables
        return self.g_ok

    def _shape(self, letters: tuple[str, ...]) -> _Shape | None:
        """The shape of a line with these letters, None if the lane does not take it: each letter once
        (a repeated one is for the general path: last wins, or 0x0202 for two G), N only first. Kept for every
        interpreter of the same axes (a shape holds no interpreter's state; building one compiles its code)."""
        key = (letters, self.axes, self.ip.axes, self.diameter, self.g_codes)
        shape = _SHAPES.get(key, _UNSEEN)
        if shape is _UNSEEN:
            if len(_SHAPES) >= _TEXTS:
                _SHAPES.clear()
            shape = _SHAPES[key] = self._new_shape(letters)
        return shape  # type: ignore[return-value]

    def _new_shape(self, letters: tuple[str, ...]) -> _Shape | None:
        if len(set(letters)) != len(letters):
            return None
        g = f = None
        axes = []
        for k, c in enumerate(letters):
            if c == "N":
                if k:
                    return None
            elif c == "G":
                if not self.g_codes:
                    return None
                g = k
            elif c == "F":
                f = k
            elif c in self.axes:
                axes.append((c, k))
            else:
                return None
        shape = _Shape(letters, bool(letters) and letters[0] == "N", g, f, tuple(axes),
                       _compiled(letters, g, f, tuple(axes), self.ip.axes, self.diameter))
        shape.run.__globals__.update(SHAPE=shape, MATCH=shape.match)  # the LineBlock's words are read from SHAPE
        if axes:
            shape.stream = streamed(letters, g, f, tuple(axes), self.ip.axes, self.diameter,
                                    dict(shape.run.__globals__))
        return shape

    def _eligible(self) -> bool:
        """The modal state in which such a line does nothing but set F / G00-G01 and move."""
        ip = self.ip
        st = ip.state
        return (st.absolute and not st.inch and st.comp == 40 and st.cycle is None and st.motion in (0, 1)
                and not st.polar and ip.macro_modal is None and ip._three_point is None
                and ip._angle_pending is None and not ip.corner_pending and _transforms(ip) is None)

    def take(self, fr: "Frame", pc: int, raw: str, limit: int, line: int) -> object:
        """Run the plain line `raw` (file line `line`) at `fr.pc == pc`, one the shape of the last line
        taken (`last`, which `_run` tries first: a CAM run is mostly lines of one shape) did not match:
        its Move, NOTHING when it moved nothing, or None (nothing done) when the general path must run it."""
        # its shape by its text (a line the lane refuses, `M99` of a macro called 5,000 times, is refused
        # by one look-up), else by its letters
        shape = self.texts.get(raw, _UNSEEN)
        if shape is _UNSEEN:
            letters = tuple(c.upper() for c in _LETTER.findall(raw))
            shape = self.shapes.get(letters, _UNSEEN)
            if shape is _UNSEEN:
                shape = self.shapes[letters] = self._shape(letters)
            if len(self.texts) >= _TEXTS:
                self.texts.clear()
            self.texts[raw] = shape
        if shape is None:
            self.lines(fr.program.blocks)[1].add(pc)  # never taken: `_run` no longer asks
            return None
        ev = shape.run(self, self.ip, fr, pc, raw, limit, line)  # type: ignore[union-attr]
        if ev is MISS:
            return None
        self.last = shape  # type: ignore[assignment]
        return ev

    def origin(self) -> dict[str, float] | None:
        """The work origin while the state is the plain one (`_eligible`), else None. Kept until anything
        else may have changed either: a block the general path ran (`_execute`, `_statement`), a system
        variable written, a run begun (they clear `Interpreter._lean_origin`)."""
        ip = self.ip
        if not self._eligible():
            return None
        origin = ip._lean_origin = ip.frames.origins(ip.state.wcs, ip.axes)
        return origin


def _compiled(letters: tuple[str, ...], g: int | None, f: int | None, programmed: tuple[tuple[str, int], ...],
              axes: tuple[str, ...], diameter: frozenset[str] | tuple[str, ...]) -> Callable[..., object]:
    """The line of one shape run as straight-line code, built once per shape and profile (as dataclasses
    builds `__init__`): what a loop over the axes did for every line (which axis is programmed, which
    in diameter, a dict per step) is decided here. Step for step the general path's arithmetic
    (`_plain_geometry`): work = where the axis stands (doubled in diameter) or the word, machine =
    work (halved in diameter) + origin, refused out of +-1e9; the same refusals, then the same state."""
    words = dict(programmed)
    moved = bool(programmed)
    src = ["def run(lane, ip, fr, pc, raw, limit, line):",
           "    m = MATCH(raw)",
           "    if m is None:",
           "        return MISS  # another shape",
           "    if ip._executed >= limit or ip.corner_pending:",
           "        return None",
           "    origin = ip._lean_origin",
           "    if origin is None:",
           "        origin = lane.origin()",
           "        if origin is None:",
           "            return None",
           "    vals = m.groups()",
           "    st = ip.state"]
    if g is None:
        src.append("    motion = st.motion")
    else:
        src += [f"    motion = _G_MOTION.get(vals[{g}])",
                "    if motion is None or not lane._g_ok():",
                "        return None"]
    if f is None:
        src.append("    feed = st.feed")
    else:
        src += [f"    feed = float(vals[{f}])",
                "    if feed < 0:",
                "        return None  # 0x0223 from the general path"]
    if moved:
        src.append("    position = ip.position")
        for i, a in enumerate(axes):
            src.append(f"    o{i} = origin[{a!r}]")
            if a in words:
                src += [f"    t = vals[{words[a]}]",
                        f"    w{i} = float(t) if '.' in t else "  # the decimal-point rule (N8.018 Bit10, decisions A4)
                        f"ip.distance(Word({a!r}, float(t), {a!r} + t, False), {a!r})"]
            elif a in diameter:
                src.append(f"    w{i} = (position.get({a!r}, 0.0) - o{i}) * 2.0")
            else:
                src.append(f"    w{i} = position.get({a!r}, 0.0) - o{i}")
        src += ["    if motion == 1:",
                "        if feed is None or feed == 0.0:",
                "            return None  # N1.042's default F, or 0x1001: the general path",
                "        mfeed = feed * 1.0"]
        for i, a in enumerate(axes):
            src += [f"    m{i} = " + (f"w{i} / 2.0 + o{i}" if a in diameter else f"w{i} + o{i}"),
                    f"    if not -1e9 <= m{i} <= 1e9:",
                    "        return None  # NaN, an infinity or |v| > 1e9: the general path's 0x120E"]
    src += ["    fr.pc = pc + 1",
            "    ip._executed += 1",
            "    name = ip.program_name = fr.program.name",
            "    ip.block = b = NEW(LineBlock)  # LineBlock(line, raw, SHAPE, vals), without its __init__ frame",
            "    b.line = line",
            "    b.text = raw",
            "    b._shape = SHAPE",
            "    b._vals = vals"]
    if g is not None:
        src += [f"    st.groups[1] = float(vals[{g}])", "    st.motion = motion"]
    if f is not None:
        src.append("    st.feed = feed")
    if not moved:
        src.append("    return NOTHING")
    else:
        # its start is the dict `position` was, rebound below (nc.interp.lean_run.move_lines)
        src += move_lines("    ", axes)
        src += [f"    ip.position = {axes_dict(axes, 'm')}",
                "    ip.last_target = work  # never changed in place (rebound by every block that moves)",
                "    return mv"]
    space = {"_G_MOTION": _G_MOTION, "Word": Word, "Move": Move, "PLANES": PLANES, "NOTHING": NOTHING,
             "LineBlock": LineBlock, "NEW": object.__new__, "SHAPE": None, "MATCH": None, "MISS": MISS}
    exec(compile("\n".join(src) + "\n", f"<lean line {''.join(letters)}>", "exec"), space)
    return space["run"]


_NO_COMMA: Mapping[str, Any] = MappingProxyType({})  # LineBlock's comma and comma_expr
_WORDS = Block.__dict__["words"]  # Block's slots: LineBlock fills them when first read
_N = Block.__dict__["n"]


class LineBlock(Block):
    """The Block of a line the lane ran: its words (and N) are made from the matched text when first
    read, as `_plain_block` makes them. What the lane's callers read of `Interpreter.block` (line,
    text, the empty comma: nc.interp.corners, alarms, M96) needs none, and making them was a fifth
    of the lane's time. Equal to, and printed as, the Block the parser makes of the line."""

    __slots__ = ("_shape", "_vals")  # the shape and groups until the words are made, then None

    # what every plain line has, as values of the class (they shadow Block's slots, read-only): no '/', no
    # comment, no statement, and no ,C/,R/,A: one empty mapping for all (nothing writes a block's skip,
    # comment, statement or comma but the parser and `_resolve`, on blocks of their own)
    skip = False
    comment = ""
    stmt = None
    comma = comma_expr = _NO_COMMA

    def __init__(self, line: int, text: str, shape: _Shape, vals: tuple[str, ...]) -> None:
        # a shape's `run` (`_compiled`) makes its LineBlock as this does, without calling it (no frame per line)
        self.line, self.text, self._shape, self._vals = line, text, shape, vals

    def _read(self) -> None:
        shape, vals = self._shape, self._vals
        self._vals = None
        words = []
        n = None
        for c, v in zip(shape.letters, vals):
            if c == "N":
                n = int(v)
            else:
                words.append(Word(c, float(v), c + v, "." in v))
        _WORDS.__set__(self, words)
        _N.__set__(self, n)

    @property  # type: ignore[override]
    def words(self) -> list[Word]:
        if self._vals is not None:
            self._read()
        return _WORDS.__get__(self)

    @words.setter
    def words(self, value: list[Word]) -> None:
        if self._vals is not None:
            self._read()  # N as read
        _WORDS.__set__(self, value)

    @property  # type: ignore[override]
    def n(self) -> int | None:
        if self._vals is not None:
            self._read()
        return _N.__get__(self)

    @n.setter
    def n(self, value: int | None) -> None:
        if self._vals is not None:
            self._read()
        _N.__set__(self, value)

    def plain(self) -> Block:
        """The same block as a Block."""
        return Block(self.line, self.text, self.words, self.n, self.skip, dict(self.comma), self.comment, self.stmt,
                     dict(self.comma_expr))

    def __eq__(self, other: object) -> bool:
        return self.plain() == (other.plain() if isinstance(other, LineBlock) else other)

    __hash__ = None  # type: ignore[assignment]  # as Block's

    def __repr__(self) -> str:
        return repr(self.plain())
