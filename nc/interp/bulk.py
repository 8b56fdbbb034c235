"""The bulk lane (issue 16): runs of plain motion blocks read in one pass, for `hil path`.

Most CAM output is a long run of blocks such as ``G1 X12.5 Y-3.25 Z-1. F1200``. Read block by block,
each makes a Block, Words, three dicts and a Move and passes four generator stages. Here a run of
such lines is read straight from the program text (`BlockList.raw`): one pass picks the words into
per-letter columns, the modal G0/G1 and F are carried forward, work -> machine conversion is done
per axis column with numpy, and the result is one `MoveBatch` event that `hil path` formats in bulk.

Taken in bulk are lines of an optional N, at most one G00/G01, F, and one-letter axis words of the
profile (each letter once), while the state is the plain one: G90, mm, no radius compensation,
no canned cycle, no transforms (scaling, mirror, rotation, G16 polar), no G61, no G66, no code
call on G00/G01, no ,A/,C/,R or G2.4 waiting for its partner block, no statement budget (a channel)
and no M96 interrupt. Anything else, and any line the block-by-block path would refuse (F < 0, a
cutting move without F, a target out of range, the `max blocks` limit), ends the run: the general
interpreter takes the next block from exactly the state the batch leaves (`take` updates position,
last target, F, modal G, the block counter and `block` as the blocks one by one would).
tests/test_interp_bulk.py compares the two lanes on random programs (hypothesis).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from nc.interp.records import _transforms
from nc.interp.state import PLANES
from nc.moves import MoveBatch

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.interpreter import Interpreter
    from nc.interp.records import Frame

MIN_RUN = 32  # shorter runs go block by block (numpy's fixed cost; `hil path` on a short program never imports it)
MAX_RUN = 4096  # lines per batch: output streams, memory stays flat
_NUM = r"([+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+))[ \t]*"
_LETTER = re.compile(r"[A-Za-z]")
_G_VALUE = {"0": 0.0, "00": 0.0, "000": 0.0, "1": 1.0, "01": 1.0, "001": 1.0}  # G00 / G01 as programs write them
_G_OK = frozenset(_G_VALUE)


@dataclass(frozen=True)
class _Shape:
    """The letters of a line in order (``GXYZF``) and where each sits: one compiled pattern reads
    every line of that shape in one call (most CAM runs are one shape)."""

    pattern: re.Pattern
    lines: re.Pattern  # the same for every line of a text (MULTILINE): a run of one shape in one call
    g: int | None  # group index of G, F; (axis index, group index) of each axis word
    f: int | None
    axes: tuple[tuple[int, int], ...]


def _shape(letters: tuple[str, ...], axes: dict[str, int]) -> _Shape | None:
    """The shape of a line with these letters, None if the bulk lane does not take it: each letter
    once (a repeated one is for the general path: last wins, or 0x0202 for two G), and only N
    (first), G, F and the profile's one-letter axes."""
    if len(set(letters)) != len(letters):
        return None
    g = f = None
    words = []
    for k, letter in enumerate(letters):
        if letter == "N":
            if k:
                return None
        elif letter == "G":
            g = k
        elif letter == "F":
            f = k
        elif letter in axes:
            words.append((axes[letter], k))
        else:
            return None
    body = r"[ \t]*" + "".join(f"[{c}{c.lower()}]" + _NUM for c in letters)
    return _Shape(re.compile(body), re.compile("^" + body + "$", re.MULTILINE), g, f, tuple(words))


def eligible(ip: Interpreter) -> bool:
    """The modal state in which a plain G0/G1 block does nothing but move (see the module text)."""
    st = ip.state
    return (st.absolute and not st.inch and st.comp == 40 and st.cycle is None and st.motion in (0, 1)
            and not st.polar and not st.exact_stop_modal and ip.macro_modal is None and ip._three_point is None
            and ip._angle_pending is None and ip.budget is None and ip.interrupt_program is None
            and not ip._interrupt_pending and _transforms(ip) is None
            and ip._call_table("G", 0) is None and ip._call_table("G", 1) is None)


_UNSEEN = object()


def _shape_of(raw: str, shapes: dict, axes: dict[str, int]) -> _Shape | None:
    """The shape of a line's letters. `shapes` holds them by letters (tuples) and, for the first
    few thousand lines looked at, by the line's text too (a repeated line, issue 16)."""
    shape = shapes.get(raw, _UNSEEN)
    if shape is not _UNSEEN:
        return shape  # type: ignore[return-value]
    letters = tuple(c.upper() for c in _LETTER.findall(raw))
    if letters not in shapes:
        shapes[letters] = _shape(letters, axes)
    shape = shapes[letters]
    if len(shapes) < 8192:
        shapes[raw] = shape
    return shape


def take(ip: Interpreter, fr: Frame, limit: int) -> MoveBatch | None:
    """The run of bulk lines at `fr.pc` as one batch (and the interpreter's state after it), or None
    when fewer than MIN_RUN lines qualify: the caller then runs the block the usual way. The lines
    are read in growing chunks, so a short run costs what it holds; a run found too short is
    remembered (`_bulk_skip`), its later lines are not looked at again."""
    blocks = fr.program.blocks
    pc = fr.pc
    skip = ip._bulk_skip
    if skip is not None and skip[0] is blocks and skip[1] <= pc < skip[2]:
        return None  # a suffix of a run already found too short: shorter still
    raw_at = getattr(blocks, "raw", None)
    first = raw_at(pc) if raw_at is not None else None
    if first is None:
        return None
    # a line the lane never takes (T0101, M05 …) is refused at once, found by its text when seen before
    known = ip.__dict__.setdefault("_bulk_refused", set())
    if first in known:
        return None
    shapes = ip.__dict__.setdefault("_bulk_shapes", {})  # per interpreter: the axes decide the shapes
    axes = ip.__dict__.get("_bulk_axes")
    if axes is None:
        axes = ip._bulk_axes = {a: j for j, a in enumerate(ip.axes) if len(a) == 1 and a in ip._plain_axes}
    if _shape_of(first, shapes, axes) is None:
        _refuse(known, first)
        return None
    if not eligible(ip):
        return None
    room = min(MAX_RUN, len(blocks) - pc, limit - ip._executed)
    # a refused line or a parsed block within MIN_RUN lines ends the run short: found without reading
    # the lines before it (a lathe program's G00 between cycle blocks, issue 16)
    for j in range(1, MIN_RUN):
        nxt = raw_at(pc + j) if j < room else None
        if nxt is None or nxt in known:
            ip._bulk_skip = (blocks, pc, pc + j + 1)
            return None
    segments: list[tuple[_Shape, int, list[tuple[str, ...]]]] = []  # (shape, first row, groups per row)
    texts: list[str] = []
    shape: _Shape | None = None
    rows: list[tuple[str, ...]] = []
    want = 4  # then 16, 64 …: a run that ends after a line or two is found so, not after slicing MIN_RUN lines
    while len(texts) < room:
        part = blocks.texts(pc + len(texts), min(want, room - len(texts)))
        if not part:
            break
        k = _same_shape(shape, part, rows) if shape is not None else 0
        match = shape.pattern.fullmatch if shape is not None else None
        for raw in part[k:]:
            m = match(raw) if match is not None else None
            if m is None:
                shape = _shape_of(raw, shapes, axes)
                if shape is None:
                    _refuse(known, raw)
                    break
                match = shape.pattern.fullmatch
                m = match(raw)
                if m is None:
                    break
                rows = []
                segments.append((shape, len(texts) + k, rows))
            rows.append(m.groups())
            k += 1
        texts += part[:k]
        if k < len(part):
            break
        want = min(want * 4, MAX_RUN)
    if len(texts) < MIN_RUN:
        ip._bulk_skip = (blocks, pc, pc + len(texts) + 1)
        return None
    return _run(ip, fr, segments, texts)


def _refuse(known: set[str], raw: str) -> None:
    """Remember a line the lane never takes (memory flat: a few thousand texts)."""
    if len(known) >= 4096:
        known.clear()
    known.add(raw)


def _same_shape(shape: _Shape, part: list[str], rows: list[tuple[str, ...]]) -> int:
    """How many lines of `part` were taken in one call because all are of `shape` (0: not all)."""
    found = shape.lines.findall("\n".join(part))
    if len(found) != len(part):  # one match a line, or some line is of another shape
        return 0
    rows.extend([(r,) for r in found] if shape.lines.groups == 1 else found)
    return len(part)


def _run(ip: Interpreter, fr: Frame, segments, texts: list[str]) -> MoveBatch | None:
    import numpy as np

    st, prof = ip.state, ip.profile
    names = ip.axes
    n, na = len(texts), len(names)
    point_scale = 1.0 if prof.param("N8.018 Bit10") else 0.001  # a number without '.' is in µm (A4)
    # ---- per-row columns: G (nan: none), F (nan: none), axis values (nan: no word)
    g_col = np.full(n, np.nan)
    f_col = np.full(n, np.nan)
    vals = np.full((n, na), np.nan)
    cut = n
    for shape, first, rows in segments:
        cols = list(zip(*rows))
        idx = slice(first, first + len(rows))
        if shape.g is not None:
            gs = cols[shape.g]
            if not _G_OK.issuperset(gs):
                bad = next(i for i, v in enumerate(gs) if v not in _G_OK)
                cut = min(cut, first + bad)
            g_col[idx] = [_G_VALUE.get(v, 0.0) for v in gs]
        if shape.f is not None:
            f_col[idx] = list(map(float, cols[shape.f]))
        for j, k in shape.axes:
            col = cols[k]
            v = np.array(list(map(float, col)))
            if "".join(col).count(".") != len(col):  # some numbers without '.': those are scaled
                v = np.where(np.array(["." in x for x in col]), v, v * point_scale)
            vals[idx, j] = v
    negative_f = np.flatnonzero(f_col < 0)  # 0x0223 from the general path
    if len(negative_f):
        cut = min(cut, int(negative_f[0]))
    # ---- modal G and F carried forward from the state
    motion = _carry_forward(g_col, float(st.motion))
    feed = _carry_forward(f_col, np.nan if st.feed is None else float(st.feed))
    moving = ~np.isnan(vals).all(axis=1)
    line_mv = moving & (motion == 1.0)
    no_feed = line_mv & (np.isnan(feed) | (feed == 0.0))
    default_f = prof.param("N1.042")
    if no_feed.any():
        if default_f > 0 and not st.per_rev and type(default_f) is float:  # (an int would print as one)
            eff = np.where(no_feed, default_f, feed * 1.0)
        else:
            cut = min(cut, int(np.argmax(no_feed)))  # 0x1001 at this block
            eff = feed * 1.0
    else:
        eff = feed * 1.0  # MotionMixin.feed (mm: no 25.4)
    # ---- work -> machine per axis column over the moving rows
    movers = np.flatnonzero(moving[:cut])
    m_rows = vals[movers]
    origin = ip.frames.origins(st.wcs, names)
    start = [ip.position[a] for a in names]
    end = np.empty_like(m_rows)
    work = np.empty_like(m_rows)
    diameter = prof.diameter_axes
    for j, a in enumerate(names):
        col = m_rows[:, j]
        o = origin[a]
        k = 2.0 if a in diameter else 1.0
        given = ~np.isnan(col)
        m_given = (col / k if k != 1.0 else col) + o
        end[:, j] = _carry(m_given, given, start[j], o)
        prev = np.concatenate(([start[j]], end[:-1, j]))
        w_kept = prev - o
        if k != 1.0:
            w_kept = w_kept * k
        work[:, j] = np.where(given, col, w_kept)
    bad = ~np.isfinite(end).all(axis=1) | (np.abs(end) > 1e9).any(axis=1)  # 0x120E
    if bad.any():
        k_ok = int(np.argmax(bad))
        cut = int(movers[k_ok])
        movers, end, work = movers[:k_ok], end[:k_ok], work[:k_ok]
    if cut < MIN_RUN:
        return None
    # ---- the batch, and the state the blocks one by one would leave
    rapid = (motion[movers] == 0.0).tolist()
    feeds = [None if r else f for r, f in zip(rapid, eff[movers].tolist())]
    pc = fr.pc
    mv = movers.tolist()
    file_lines = fr.program.blocks.lines(pc, cut)
    if len(mv) == cut:  # every block moves (the usual CAM run)
        mv_lines, mv_texts = file_lines, texts[:cut]
    else:
        mv_lines, mv_texts = [file_lines[i] for i in mv], [texts[i] for i in mv]
    batch = MoveBatch(names, mv_lines, mv_texts, rapid,
                      dict(ip.position), end.T.tolist(), work.T.tolist(), feeds, st.per_rev, fr.program.name,
                      PLANES[st.plane], st.surface_speed if st.css else None)
    g_set = np.flatnonzero(~np.isnan(g_col[:cut]))
    if len(g_set):
        st.groups[1] = float(g_col[g_set[-1]])
        st.motion = int(g_col[g_set[-1]])
    f_set = np.flatnonzero(~np.isnan(f_col[:cut]))
    if len(f_set):
        st.feed = float(f_col[f_set[-1]])
    if mv:
        ip.position = dict(zip(names, [c[-1] for c in batch.end]))
        ip.last_target = dict(zip(names, [c[-1] for c in batch.work]))
        ip.unit_locked = True
    ip.block = fr.program.blocks[pc + cut - 1]
    ip.program_name = fr.program.name
    ip._executed += cut
    fr.pc += cut
    return batch


def _carry_forward(col, before: float):
    """Each row's value, else the last one above it, else `before` (a modal word carried on)."""
    import numpy as np

    idx = np.where(np.isnan(col), -1, np.arange(len(col)))
    np.maximum.accumulate(idx, out=idx)
    return np.where(idx >= 0, col[np.maximum(idx, 0)], before)


def _carry(m_given, given, start: float, o: float):
    """Machine values of one axis: the given ones, and where the block has no word for the axis the
    previous value taken through work and back, `(prev - o) + o`, as `to_machine(to_work(...))`
    does block by block (not always the previous value bit for bit). Solved as a fixed point of
    the whole column; a few passes at most, else row by row."""
    import numpy as np

    if given.all():
        return m_given
    cur = np.where(given, m_given, start)
    for _ in range(8):
        prev = np.concatenate(([start], cur[:-1]))
        nxt = np.where(given, m_given, (prev - o) + o)
        if np.array_equal(nxt.view(np.int64), cur.view(np.int64)):
            return nxt
        cur = nxt
    out = cur.copy()
    p = start
    for i in range(len(out)):
        p = float(m_given[i]) if given[i] else (p - o) + o
        out[i] = p
    return out
