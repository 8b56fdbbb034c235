"""`hil path --json`'s JSON Lines, written as text: the same bytes as `strict_json.dumps(move_dict(m))`,
without building the dicts (issue 16: the dicts and the generic encoder were half of `hil path` on a
lathe-cycle program). Pinned by tests/test_path_json_fast.py and tests/test_interp_bulk.py."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from json import dumps as _json_str
from typing import TYPE_CHECKING

from hil import strict_json

if TYPE_CHECKING:
    from nc.moves import Move, MoveBatch


def fmt(v: float) -> float:
    """Round away float noise so golden files compare cleanly: 7 decimals, 1e-7 mm (0.1 nm), far below
    the NC5's 0.001 mm input unit yet keeping computed points (arc chords, offsets) true to 1e-7."""
    r = round(v, 7)
    return 0.0 if r == 0 else r


def move_dict(m: Move) -> dict:
    d = m.as_dict()
    for key in ("start", "end", "work", "center"):
        if d[key] is not None:
            d[key] = {a: fmt(v) for a, v in d[key].items()}
    if m.per_rev and m.feed is not None:  # additive key: `feed` is mm/rev (G99 / G95)
        d["per_rev"] = True
    if m.exact_stop:  # additive key (issue 3): G09 / G61 / G53 / G28 exact stop at the end of this move
        d["exact_stop"] = True
    if m.tags:  # additive keys (issue 4): which cycle / pass / compensation produced the move
        d["tags"] = list(m.tags)
    if m.kind == "thread":
        d.update(lead=m.lead, lead_change=m.lead_change, start_angle=m.start_angle)
    if m.comp:
        d.update(comp=m.comp, comp_radius=m.comp_radius, tip=m.tip)
    return d


_NUMS: dict[float, str] = {}  # nonzero float -> its repr ("null" for ±inf)


def _num(v) -> str:
    """One number as strict_json.dumps writes it: floats by repr, non-finite as null; anything else
    (a float subclass such as numpy's, None) the general way."""
    t = type(v)
    if t is float:
        if v != 0:  # equal nonzero floats write alike (0.0 and -0.0 do not): a feed, a lead written once
            text = _NUMS.get(v)
            if text is None:
                text = repr(v) if math.isfinite(v) else "null"
                if len(_NUMS) >= _QUOTED_LIMIT:
                    _NUMS.clear()
                _NUMS[v] = text
            return text
        return repr(v)
    if t is int:
        return repr(v)
    if v is None:
        return "null"
    return _json_str(strict_json.finite(v), allow_nan=False)


def _val(v) -> str:
    """`_num(fmt(v))`: a float rounded to 7 decimals by repr, -0.0 as 0.0, non-finite as null."""
    if type(v) is float:
        r = round(v, 7)
        return "0.0" if r == 0 else repr(r) if r - r == 0 else "null"  # r - r is nan for nan and ±inf
    return _num(fmt(v))


def _seven(v: float) -> str:
    """`_val(v)` of a finite float, repr(round(v, 7) + 0.0), at a quarter of its cost: '%.7f' rounds
    to the same 7-decimal number D as round() does (both correctly rounded from the exact double),
    and between 1e-4 and 1e8 D has at most 15 significant digits, so the shortest repr of the double
    nearest D is D itself without its trailing zeros (repr writes no exponent there). Outside that
    range (zero, tiny, huge) the general way. Pinned by tests/test_path_json_fast.py."""
    if 1e-4 <= abs(v) < 1e8:
        t = ("%.7f" % v).rstrip("0")
        return t + "0" if t[-1] == "." else t
    return repr(round(v, 7) + 0.0)


_TEMPLATES: dict[tuple, str] = {}  # axis names -> '{"X": %s, "Z": %s}'
_FLOATS = {float}
_POINTS: dict[tuple, tuple[str, bool]] = {}  # ((axis, value), …) of floats -> (text, a value is integral)
_POINTS_LIMIT = 4096  # points remembered: a program comes back to its points (a repeated part, a cycle's passes)


def _axes(d: dict[str, float], key: tuple | None = None) -> str:
    """The JSON object of a point; `key` is tuple(d.items()) when the caller has it already."""
    if key is None:
        key = tuple(d.items())
    hit = _POINTS.get(key)
    # stored for plain floats only; an int or bool equal to a float (5 == 5.0) writes otherwise, so a
    # point with an integral value is taken only after a look at the types
    if hit is not None and (not hit[1] or set(map(type, d.values())) == _FLOATS):
        return hit[0]
    names = tuple(d)
    t = _TEMPLATES.get(names)
    if t is None:
        t = _TEMPLATES[names] = "{" + ", ".join([_json_str(a).replace("%", "%%") + ": %s" for a in names]) + "}"
    vals = tuple(d.values())
    if set(map(type, vals)) == _FLOATS:  # plain floats: equal values (0.0 and -0.0 too) write the same
        if (s := sum(vals)) - s == 0:  # all finite (a NaN or ±inf makes s - s nan)
            text = t % tuple([_seven(v) for v in vals])
            if len(_POINTS) >= _POINTS_LIMIT:
                _POINTS.clear()
            _POINTS[key] = (text, any([v.is_integer() for v in vals]))
            return text
    return t % tuple([_val(v) for v in vals])


_QUOTED: dict[str, str] = {}  # block text -> its JSON string: the moves of a cycle share their block
_QUOTED_LIMIT = 4096
_HEADS: dict[tuple, str] = {}  # (kind, line, block text) -> the line's text up to the start point
_TAGS: dict[tuple, str] = {}  # tags (strings) -> their ', "tags": [...]' text
# the last move's end dict, its items then, its text, and whether nothing can have changed it since
# (True only inside `moves_json`)
_LAST_END: list = [None, (), "", False]


def _str(s) -> str:
    """json.dumps of a string: as it is, quoted, when it holds nothing JSON escapes."""
    q = _QUOTED.get(s) if type(s) is str else None
    if q is None:
        q = f'"{s}"' if type(s) is str and s.isascii() and s.isprintable() and '"' not in s and "\\" not in s \
            else _json_str(s)
        if type(s) is str:
            if len(_QUOTED) >= _QUOTED_LIMIT:
                _QUOTED.clear()
            _QUOTED[s] = q
    return q


def _all_floats(d: dict) -> bool:
    """Every value a float (`set(map(type, …)) == _FLOATS` at a third of its cost, for a point that may
    hash like one with an int)."""
    for v in d.values():
        if type(v) is not float:
            return False
    return True


def move_json(m: Move) -> str:
    """The JSON line of `move_dict(m)`, byte for byte as strict_json.dumps writes it, built as text
    without the intermediate dicts (issue 16: the dicts and the generic encoder were half of `hil
    path` on a lathe-cycle program); a move with a field of an unusual type goes the general way.
    Pinned by tests/test_path_json_fast.py (hypothesis)."""
    start, end, work = m.start, m.end, m.work
    if start is None or end is None or work is None or type(m.line) is not int or type(m.kind) is not str:
        return strict_json.dumps(move_dict(m))
    key = (m.kind, m.line, m.block)
    head = _HEADS.get(key)
    if head is None:  # the moves of a cycle share their block: its head is written once
        head = f'{{"kind": {_str(m.kind)}, "line": {m.line}, "block": {_str(m.block)}, "start": '
        if type(m.block) is str:
            if len(_HEADS) >= _QUOTED_LIMIT:
                _HEADS.clear()
            _HEADS[key] = head
    # a cycle's move starts at the dict its last move ended at: that point's text again (checked by
    # value, so a dict changed in place since is written anew)
    last = _LAST_END
    start_text = last[2] if start is last[0] and (last[3] or tuple(start.items()) == last[1]) else _axes(start)
    # `_axes` of end and work, its remembered-point hit inline (the usual case: a call less per point);
    # a point with an integral value is taken only when all its values are floats (see `_axes`)
    end_items = tuple(end.items())
    hit = _POINTS.get(end_items)
    if hit is not None and hit[1] and not (type(end_items[0][1]) is float and type(end_items[-1][1]) is float
                                           and (len(end_items) <= 2 or _all_floats(end))):
        hit = None
    end_text = hit[0] if hit is not None else _axes(end, end_items)
    last[0], last[1], last[2] = end, end_items, end_text
    hit = _POINTS.get(work_items := tuple(work.items()))
    if hit is not None and hit[1] and not (type(work_items[0][1]) is float and type(work_items[-1][1]) is float
                                           and (len(work_items) <= 2 or _all_floats(work))):
        hit = None
    work_text = hit[0] if hit is not None else _axes(work, work_items)
    # the rest of the line of a move without centre, direction, duration or compensation is one of
    # few (feed, flags, tags, thread keys): remembered by them where equal keys write alike (floats
    # but 0.0 and -0.0 do, an int as 5 and 5.0 do not)
    feed, tags = m.feed, m.tags
    key = None
    if m.center is None and m.dir is None and m.duration is None and not m.comp and type(tags) is tuple \
            and (feed is None or type(feed) is float and feed != 0):
        if m.kind != "thread":
            key = (feed, not m.per_rev, not m.exact_stop, tags)  # (`not`: their truth, without a call)
        elif _plain(lead := m.lead) and _plain(lead_change := m.lead_change) and _plain(angle := m.start_angle):
            key = (feed, not m.per_rev, not m.exact_stop, tags, lead, lead_change, angle)
    tail = _TAILS.get(key) if key is not None else None
    if tail is None:
        tail = _tail(m)
        if key is not None and all(type(t) is str for t in tags):
            if len(_TAILS) >= _QUOTED_LIMIT:
                _TAILS.clear()
            _TAILS[key] = tail
    # one string for the whole line, none appended to a finished line (each append copied the line)
    return f'{head}{start_text}, "end": {end_text}, "work": {work_text}{tail}'


_TAILS: dict[tuple, str] = {}  # (feed, per_rev, exact_stop, tags[, lead, lead_change, start_angle]) -> tail


def _plain(v) -> bool:
    """None or a float that writes as every float equal to it does (not -0.0)."""
    return v is None or type(v) is float and (v != 0 or math.copysign(1.0, v) > 0)


def _tail(m: Move) -> str:
    """The line of `move_json(m)` after its work point: the additive keys of move_dict in its order."""
    tags = ""
    if m.tags:
        tags = _TAGS.get(m.tags)
        if tags is None:
            tags = ', "tags": [' + ", ".join([_str(t) for t in m.tags]) + "]"
            if type(m.tags) is tuple and all(type(t) is str for t in m.tags):
                if len(_TAGS) >= _QUOTED_LIMIT:
                    _TAGS.clear()
                _TAGS[m.tags] = tags
    feed = m.feed
    return (f', "center": {"null" if m.center is None else _axes(m.center)}, '
            f'"dir": {"null" if m.dir is None else _str(m.dir)}, '
            f'"feed": {"null" if feed is None else _num(feed)}, '
            f'"duration": {"null" if (duration := m.duration) is None else _num(duration)}'
            f'{_PER_REV if m.per_rev and feed is not None else ""}{_EXACT_STOP if m.exact_stop else ""}{tags}'
            f'{_thread_keys(m) if m.kind == "thread" else ""}{_comp_keys(m) if m.comp else ""}}}')


def moves_json(moves: Iterable[Move]) -> list[str]:
    """`move_json` of each move in order (a cycle's MoveList). Between two of these calls no code runs
    that could change a point in place, so a move that starts at the dict the move before ended at
    takes that point's text without the by-value check `move_json` makes on its own (issue 16: a
    fifth of the writer's time on the lathe-cycle bench)."""
    out: list[str] = []
    add = out.append
    last = _LAST_END
    try:
        for m in moves:
            add(move_json(m))
            last[3] = True
    finally:
        last[3] = False
    return out


_PER_REV = ', "per_rev": true'
_EXACT_STOP = ', "exact_stop": true'


def _thread_keys(m: Move) -> str:
    return f', "lead": {_num(m.lead)}, "lead_change": {_num(m.lead_change)}, "start_angle": {_num(m.start_angle)}'


def _comp_keys(m: Move) -> str:
    return f', "comp": {_str(m.comp)}, "comp_radius": {_num(m.comp_radius)}, "tip": {_num(m.tip)}'


def _coord(v: float) -> str:
    """`_num(fmt(v))` for a finite float: round(v, 7) is v itself when |v| < 1e7 and v's shortest repr
    has at most 7 decimals and no exponent, which is every coordinate read from a program written
    to 0.001 mm (pinned against the general form by tests/test_interp_bulk.py)."""
    r = repr(v)
    dot = r.find(".")
    if dot > 0 and len(r) - dot <= 8 and "e" not in r and -1e7 < v < 1e7:
        return "0.0" if v == 0 else r
    return _num(fmt(v))


# reprs `_coord` takes as they are have no exponent, at most 7 decimals and at most 7 integer digits
_DECIMALS_8 = re.compile(r"\.[0-9]{8}")
_DIGITS_8 = re.compile(r"[0-9]{8}")  # without an exponent and beyond 7 decimals: an integer part >= 1e7


def _coords(col: Sequence[float]) -> list[str]:
    """`_coord` of every value of a column: reprs in one go, checked in one pass over their text."""
    r = list(map(repr, col))
    text = "\n".join(r)
    if "e" in text or _DECIMALS_8.search(text) or _DIGITS_8.search(text):
        return [_coord(v) for v in col]
    if "-0.0" in r:
        r = ["0.0" if x == "-0.0" else x for x in r]
    return r


def _points(axes: tuple[str, ...], cols: Sequence[Sequence[float]]) -> list[str]:
    """`_axes` of each row of per-axis columns."""
    template = "{" + ", ".join(f"{_json_str(a)}: %s" for a in axes) + "}"
    return [template % t for t in zip(*map(_coords, cols))]


def batch_json(b: MoveBatch) -> str:
    """The JSON lines of a MoveBatch, byte for byte `move_json` of each of `b.moves()` (a batch holds
    rapids and lines without additive keys but `per_rev`): numbers formatted column by column, each
    end point once (it is the next move's start), a work point equal to it not again."""
    if not b.lines:
        return ""
    ends = _points(b.axes, b.end)
    works = ends if b.work == b.end else _points(b.axes, b.work)
    starts = [_axes(b.start)] + ends[:-1]
    per_rev = ', "per_rev": true' if b.per_rev else ""
    tails: dict[float | None, str] = {None: 'null, "duration": null}'}
    out = []
    for line, text, rapid, start, end, work, feed in zip(b.lines, b.texts, b.rapid, starts, ends, works, b.feed):
        tail = tails.get(feed)
        if tail is None:
            tail = tails[feed] = f'{_num(feed)}, "duration": null{per_rev}}}'
        block = f'"{text}"' if "\t" not in text else _json_str(text)
        out.append(f'{{"kind": "{"rapid" if rapid else "line"}", "line": {line}, "block": {block}, '
                   f'"start": {start}, "end": {end}, "work": {work}, "center": null, "dir": null, "feed": {tail}')
    return "\n".join(out)
