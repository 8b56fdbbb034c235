"""`hil path PROGRAM`: interpret without motion and print the canonical moves.

The `--json` form (JSON Lines) is the stable verification seam; docs/path-format.md documents it.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import sys
from collections import deque
from typing import TYPE_CHECKING

from hil import strict_json
from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from hil.path_json import batch_json, fmt, move_json, moves_json
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
            if type(ev) is MoveBatch:  # up to MAX_RUN lines already: written at once, so memory stays
                add(batch_json(ev) if as_json else batch_text(ev))  # flat (256 batches held 1M lines)
                _flush(out, lines)
            elif type(ev) is MoveList:  # a cycle's moves (bulk only: no interrupt, no plot)
                if as_json:
                    lines.extend(moves_json(ev.items))
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
