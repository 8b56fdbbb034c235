"""`hil path PROGRAM`: interpret without motion and print the canonical moves.

The `--json` form (JSON Lines) is the stable verification seam; docs/path-format.md documents it.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import math
import re
import sys
from json import dumps as _json_str
from collections import deque
from collections.abc import Sequence

from typing import TYPE_CHECKING

from hil import strict_json
from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from nc.alarms import NcAlarm, internal_error

if TYPE_CHECKING:  # the interpreter and the bench load when the command runs, not at `hil` start-up
    from nc.interp import Interpreter
    from nc.moves import Move, MoveBatch


def parse_ranges(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            if "-" in part:
                a, b = (int(x) for x in part.split("-", 1))
                if b < a:
                    raise ValueError
                out.extend(range(a, b + 1))
            else:
                out.append(int(part))
        except ValueError:
            from hil.session import InputError

            raise InputError(f"bad --vars range {part!r}: use e.g. 100-199,500") from None
    return out


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("path", help="interpret a program without motion and print its moves")
    p.add_argument("program")
    p.add_argument("--profile", help="nc5-lathe-a (default), nc5-lathe-b, nc5-lathe-c, nc5-mill, lathe-2018")
    p.add_argument("--bench", help="bench file: its profile, axes and parameters")
    p.add_argument("--json", action="store_true", help="JSON Lines, one object per move (stable format)")
    p.add_argument("--vars", metavar="RANGES", help="append the values of these # variables, e.g. 100-199,500")
    p.add_argument("--lib", action="append", default=[], metavar="DIR|FILE",
                   help="where subprograms and macros (O numbers) are found: a folder searched in the NC5 order "
                        "(PATH_1, PATH_1/O_MACRO, GLOBAL, GLOBAL/O_MACRO, the folder itself) or a file of O programs")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set a controller parameter, e.g. --param 'N8.018 Bit10=1' (overrides the bench)")
    p.add_argument("--block-skip", action="store_true", help="block skip switch on: '/' blocks are skipped")
    p.add_argument("--preview-log", action="store_true",
                   help="also print which macro statement ran ahead of which motion block (preview)")
    p.add_argument("--plot", metavar="FILE.png",
                   help="also draw the tool path in the active plane (rapids dashed, feeds solid, "
                        "programmed contour vs compensated path)")
    p.add_argument("--interrupt", metavar="LINE[@FRACTION]",
                   help="M96: the MLC's M2x019 fires while the move of main-program line LINE runs, FRACTION "
                        "(default 0.5) of the way along it; that move is cut there (tag 'M96 stop'), the "
                        "interrupt program runs, and its M99 goes on to the block's end (program read without "
                        "preview)")
    p.set_defaults(func=cmd_path)


def parse_interrupt(text: str) -> tuple[int, float]:
    from hil.session import InputError

    line, _, frac = text.partition("@")
    try:
        at = (int(line), float(frac) if frac else 0.5)
    except ValueError:
        raise InputError(f"bad --interrupt {text!r}: use LINE or LINE@FRACTION") from None
    if at[0] < 1 or not 0.0 <= at[1] <= 1.0:
        raise InputError(f"bad --interrupt {text!r}: LINE >= 1, 0 <= FRACTION <= 1")
    return at


def suspend(interp: Interpreter, move: Move, fraction: float) -> Move:
    """What the machine ran of `move` before M2x019 stopped it; tells the interpreter where it stopped."""
    from nc.motion.path import Segment

    axes = tuple(move.start)
    seg = Segment.of(move, axes)
    stop = {a: float(v) for a, v in zip(axes, seg.points([fraction * seg.length])[0])}
    interp.request_interrupt(stop)
    return dataclasses.replace(move, end=stop, work=interp.to_work(stop), tags=move.tags + ("M96 stop",))


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
_LAST_END: list = [None, (), ""]  # the last move's end dict, its items then, its text


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


def move_json(m: Move) -> str:
    """The JSON line of `move_dict(m)`, byte for byte as strict_json.dumps writes it, built as text
    without the intermediate dicts (issue 16: the dicts and the generic encoder were half of `hil
    path` on a lathe-cycle program); a move with a field of an unusual type goes the general way.
    Pinned by tests/test_path_json_fast.py (hypothesis)."""
    if m.start is None or m.end is None or m.work is None or type(m.line) is not int \
            or type(m.kind) is not str:
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
    start, end = m.start, m.end
    last = _LAST_END
    start_text = last[2] if start is last[0] and tuple(start.items()) == last[1] else _axes(start)
    # `_axes` of end and work, its remembered-point hit inline (the usual case: a call less per point)
    end_items = tuple(end.items())
    hit = _POINTS.get(end_items)
    end_text = hit[0] if hit is not None and (not hit[1] or set(map(type, end.values())) == _FLOATS) \
        else _axes(end, end_items)
    last[0], last[1], last[2] = end, end_items, end_text
    work = m.work
    hit = _POINTS.get(work_items := tuple(work.items()))
    work_text = hit[0] if hit is not None and (not hit[1] or set(map(type, work.values())) == _FLOATS) \
        else _axes(work, work_items)
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
    # one string for the whole line: the additive keys of move_dict in its order, none appended to a
    # finished line (each append copied the line, issue 16)
    return (f'{head}{start_text}, "end": {end_text}, "work": {work_text}, '
            f'"center": {"null" if m.center is None else _axes(m.center)}, '
            f'"dir": {"null" if m.dir is None else _str(m.dir)}, '
            f'"feed": {"null" if feed is None else _num(feed)}, '
            f'"duration": {"null" if (duration := m.duration) is None else _num(duration)}'
            f'{_PER_REV if m.per_rev and feed is not None else ""}{_EXACT_STOP if m.exact_stop else ""}{tags}'
            f'{_thread_keys(m) if m.kind == "thread" else ""}{_comp_keys(m) if m.comp else ""}}}')


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


def batch_text(b: MoveBatch) -> str:
    """The text listing lines of a MoveBatch, as `_human` writes each of `b.moves()`."""
    unit = "/rev" if b.per_rev else ""
    out = []
    for line, rapid, work, feed in zip(b.lines, b.rapid, zip(*b.work), b.feed):
        end = " ".join([f"{a}{fmt(v):g}" for a, v in zip(b.axes, work)])
        extra = "" if feed is None else f" F{feed:g}{unit}"
        out.append(f"{line:5d} {'rapid' if rapid else 'line':6s} {end}{extra}")
    return "\n".join(out)


DEFAULT_PROFILE = "nc5-lathe-a"  # hil.bench.default_lathe's (tests/test_foundation_path.py holds them equal)


def cmd_path(args: argparse.Namespace) -> int:
    from hil.session import InputError, checked_profile, load_bench, print_alarm
    from nc.interp import Interpreter
    from nc.moves import Move, MoveBatch, MoveList, Sync
    from nc.profiles import make_profile
    from nc.store import ProgramStore

    try:
        if args.bench:
            bench = load_bench(args.bench, args.profile)
            profile_name, params = bench.profile, dict(bench.params)
        else:  # the default bench's profile, no parameters: without loading the bench module (start-up)
            profile_name, params = checked_profile(args.profile) if args.profile else DEFAULT_PROFILE, {}
        var_ids = parse_ranges(args.vars) if args.vars else []
        for item in args.param:
            name, sep, value = item.partition("=")
            if not sep:
                raise InputError(f"bad --param {item!r}: use NAME=VALUE")
            params[name.strip()] = float(value)
        if args.block_skip:
            params["M2x010"] = 1
        interrupt = parse_interrupt(args.interrupt) if getattr(args, "interrupt", None) else None
        rotary = tuple(a.name for a in bench.axes if a.units == "deg") if args.bench else ()
        profile = make_profile(profile_name, bench.axis_names if args.bench else None, params, rotary)
    except (InputError, ValueError) as exc:
        print(f"hil path: {exc}", file=sys.stderr)
        return EXIT_USAGE
    store = ProgramStore(usb_first=bool(profile.param("N8.22 Bit5")))
    interp = Interpreter(profile, store=store)
    # asked for: the whole log, not only the last statements (decisions B3); else none is kept
    interp.preview_log = deque() if args.preview_log else deque(maxlen=0)
    # runs of plain G0/G1 blocks come as MoveBatch events, formatted in bulk (issue 16); the plot,
    # the preview log and an M96 interrupt want every Move on its own
    interp.bulk = not (args.preview_log or interrupt or getattr(args, "plot", None))
    out = sys.stdout
    try:
        store.add_libs(args.lib)
    except ValueError as exc:
        print(f"hil path: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except NcAlarm as exc:
        print_alarm(exc.alarm, as_json=args.json)
        return EXIT_ALARM
    listed = 0  # G10 L40-L46 servo accesses are listed where they happen (issue 8)
    # lines gather and go out a chunk at a time (issue 16: a write call per move), always before
    # anything else is printed, so the order on the stream stays
    lines: list[str] = []
    if not args.json:
        print(text_header(profile.diameter_axes), file=out)
    try:
        # Parsing builds many small objects that live for the whole run: keep the cyclic collector
        # from walking them again and again (half of the parse time, issue 16).
        gc.disable()
        try:
            program = store.load_main(args.program)
        finally:
            gc.enable()
        gc.freeze()
        plotted: list[Move] = []
        add = lines.append
        servo_log = interp.servo.log
        plot, as_json = getattr(args, "plot", None), args.json  # asked once, not per event
        for ev in interp.run(program, preview=interrupt is None):
            if len(servo_log) > listed:  # asked per event: a look at the log's length (hot path)
                _flush(out, lines)
                listed = _print_servo(interp, args, listed)
            if type(ev) is MoveBatch:
                add(batch_json(ev) if as_json else batch_text(ev))
            elif type(ev) is MoveList:  # a cycle's moves (bulk only: no interrupt, no plot)
                if as_json:
                    lines.extend(map(move_json, ev.items))
                else:
                    lines.extend([_human(m, profile.diameter_axes) for m in ev.items])
            elif isinstance(ev, Move):
                if interrupt and ev.line == interrupt[0] and ev.program == program.name \
                        and interp.interrupt_program is not None:
                    ev, interrupt = suspend(interp, ev, interrupt[1]), None
                if plot:
                    plotted.append(ev)
                add(move_json(ev) if as_json else _human(ev, profile.diameter_axes))
            elif args.preview_log and isinstance(ev, Sync):
                _flush(out, lines)
                print(strict_json.dumps(ev.as_dict()) if args.json else f"{ev.line:5d} sync   {ev.reason}", file=out)
            if len(lines) >= 256:
                _flush(out, lines)
        _flush(out, lines)
    except NcAlarm as exc:
        _flush(out, lines)
        _print_servo(interp, args, listed)
        _print_preview(interp, args)
        print_alarm(exc.alarm, as_json=args.json)
        return EXIT_ALARM
    except BrokenPipeError:  # `hil path … | head`: the reader left; hil.cli ends quietly
        raise
    except Exception as exc:  # a bug, reported as the NC internal alarm, never a traceback
        _flush(out, lines)
        print_alarm(internal_error(exc), as_json=args.json)
        return EXIT_ALARM
    _print_servo(interp, args, listed)
    _print_preview(interp, args)
    if getattr(args, "plot", None):
        from hil.plot import plot_program
        try:
            plot_program(plotted, args.plot, profile, lambda: Interpreter(profile, store=store), program)
        except NcAlarm as exc:
            print_alarm(exc.alarm, as_json=args.json)
            return EXIT_ALARM
        except OSError as exc:
            print(f"hil path: cannot write {args.plot}: {exc.strerror}", file=sys.stderr)
            return EXIT_USAGE
    if var_ids:
        values = {str(i): interp.variable(i) for i in var_ids}
        print(strict_json.dumps({"kind": "vars", "values": values}) if args.json else
              "vars " + " ".join(f"#{k}={'vacant' if v is None else v}" for k, v in values.items()), file=out)
    return EXIT_OK


def _flush(out, lines: list[str]) -> None:
    """Write the gathered lines in one call and empty the list."""
    if lines:
        out.write("\n".join(lines) + "\n")
        lines.clear()


def _print_servo(interp: Interpreter, args: argparse.Namespace, listed: int) -> int:
    """Print the servo parameter accesses (G10 L40/L41/L45/L46) logged since `listed`; offline
    nothing is sent to a drive, so a read leaves #20023 vacant and #20024 = -2."""
    log = interp.servo.log
    for req, reply in log[listed:]:
        if args.json:
            print(strict_json.dumps({"kind": "servo", "line": req.line, "block": req.block, "station": req.station,
                              "object": req.label, "write": req.value, "value": reply.value,
                              "result": reply.result}))
        else:
            print(f"{req.line:5d} servo  {req.describe()} -- not sent (offline, #20024 = {reply.result})"
                  if reply.value is None else f"{req.line:5d} servo  {req.describe()} = {reply.value}")
    return len(log)


def _print_preview(interp: Interpreter, args: argparse.Namespace) -> None:
    if not args.preview_log:
        return
    for r in interp.preview_log:
        if args.json:
            print(strict_json.dumps({"kind": "preview", "line": r.line, "block": r.block, "program": r.program,
                              "ahead_of_line": r.ahead_of_line, "ahead_of_block": r.ahead_of_block,
                              "blocks_ahead": r.blocks_ahead}))
        else:
            where = f"while line {r.ahead_of_line} ({r.ahead_of_block}) runs, {r.blocks_ahead} motion block(s) " \
                    "buffered" if r.ahead_of_line is not None else "before any motion"
            print(f"preview {r.line:5d} {r.block:30s} ran {where}")


def text_header(diameter_axes: tuple[str, ...]) -> str:
    """The one convention of the text listing, said once (issue 19: end points were work coordinates with
    lathe diameters, arc centres machine coordinates with radii)."""
    dia = f", {'/'.join(diameter_axes)} as a diameter" if diameter_axes else ""
    return f"# work coordinates as the program writes them{dia}; arc centres in the same coordinates"


def work_centre(m: Move, diameter_axes: tuple[str, ...]) -> dict[str, float]:
    """The arc centre in the end point's convention: work = machine - origin, doubled on diameter axes."""
    return {a: m.work[a] + (c - m.end[a]) * (2.0 if a in diameter_axes else 1.0)
            for a, c in m.center.items() if a in m.work and a in m.end}


def _human(m: Move, diameter_axes: tuple[str, ...] = ()) -> str:
    end = " ".join(f"{a}{fmt(v):g}" for a, v in m.work.items())
    extra = ""
    if m.kind == "arc" and m.center:
        extra = f" {m.dir} centre " + " ".join(f"{a}{fmt(v):g}" for a, v in work_centre(m, diameter_axes).items())
    if m.feed is not None:
        extra += f" F{m.feed:g}{'/rev' if m.per_rev else ''}"
    if m.duration is not None:
        extra += f" {m.duration:g}s"
    return f"{m.line:5d} {m.kind:6s} {end}{extra}"
