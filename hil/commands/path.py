"""`hil path PROGRAM`: interpret without motion and print the canonical moves.

The `--json` form (JSON Lines) is the stable verification seam; docs/path-format.md documents it.
"""

from __future__ import annotations

import argparse
import json
import sys

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from hil.session import InputError, load_bench, load_program, print_alarm
from nc.alarms import NcAlarm, internal_error
from nc.interp import Interpreter
from nc.moves import Move
from nc.profiles import make_profile


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
            raise InputError(f"bad --vars range {part!r}: use e.g. 100-199,500") from None
    return out


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("path", help="interpret a program without motion and print its moves")
    p.add_argument("program")
    p.add_argument("--profile", help="nc5-lathe-a (default), nc5-lathe-b, nc5-lathe-c, nc5-mill, lathe-2018")
    p.add_argument("--bench", help="bench file: its profile, axes and parameters")
    p.add_argument("--json", action="store_true", help="JSON Lines, one object per move (stable format)")
    p.add_argument("--vars", metavar="RANGES", help="append the values of these # variables, e.g. 100-199,500")
    p.set_defaults(func=cmd_path)


def fmt(v: float) -> float:
    """Round away float noise so golden files compare cleanly (0.1 µm)."""
    r = round(v, 7)
    return 0.0 if r == 0 else r


def move_dict(m: Move) -> dict:
    d = m.as_dict()
    for key in ("start", "end", "work", "center"):
        if d[key] is not None:
            d[key] = {a: fmt(v) for a, v in d[key].items()}
    return d


def cmd_path(args: argparse.Namespace) -> int:
    try:
        bench = load_bench(args.bench, args.profile)
        var_ids = parse_ranges(args.vars) if args.vars else []
        profile = make_profile(bench.profile, bench.axis_names if args.bench else None, bench.params)
    except (InputError, ValueError) as exc:
        print(f"hil path: {exc}", file=sys.stderr)
        return EXIT_USAGE
    interp = Interpreter(profile)
    out = sys.stdout
    try:
        program = load_program(args.program)
        for ev in interp.run(program):
            if isinstance(ev, Move):
                if args.json:
                    print(json.dumps(move_dict(ev)), file=out)
                else:
                    print(_human(ev), file=out)
    except NcAlarm as exc:
        print_alarm(exc.alarm, as_json=args.json)
        return EXIT_ALARM
    except Exception as exc:  # a bug, reported as the NC internal alarm, never a traceback
        print_alarm(internal_error(exc), as_json=args.json)
        return EXIT_ALARM
    if var_ids:
        values = {str(i): interp.variable(i) for i in var_ids}
        print(json.dumps({"kind": "vars", "values": values}) if args.json else
              "vars " + " ".join(f"#{k}={'vacant' if v is None else v}" for k, v in values.items()), file=out)
    return EXIT_OK


def _human(m: Move) -> str:
    end = " ".join(f"{a}{fmt(v):g}" for a, v in m.work.items())
    extra = ""
    if m.kind == "arc" and m.center:
        extra = f" {m.dir} centre " + " ".join(f"{a}{fmt(v):g}" for a, v in m.center.items())
    if m.feed is not None:
        extra += f" F{m.feed:g}{'/rev' if m.per_rev else ''}"
    if m.duration is not None:
        extra += f" {m.duration:g}s"
    return f"{m.line:5d} {m.kind:6s} {end}{extra}"
