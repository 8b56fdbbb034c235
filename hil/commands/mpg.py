"""`hil mpg AXIS PULSES [--ratio R]`: turn the simulated handwheel in MPG mode and report the move."""

from __future__ import annotations

import argparse

from hil.commands.script import add_bench_options, finish, on_machine


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("mpg", help="drive an axis with the handwheel: pulses × ratio × 0.001 mm")
    p.add_argument("axis", help="axis name, e.g. X")
    p.add_argument("pulses", type=int, help="detents (negative: backwards)")
    p.add_argument("--ratio", type=int, default=1, help="D2x009 ratio: 1, 10 or 100 (default 1)")
    p.add_argument("--rate", type=float, default=100.0, help="detents per second (default 100)")
    add_bench_options(p)
    p.set_defaults(func=cmd_mpg)


def cmd_mpg(args: argparse.Namespace) -> int:
    return on_machine(args, _mpg)


def _mpg(args: argparse.Namespace, machine) -> int:
    from hil.scripting import ScriptError

    try:
        x0 = machine.command(args.axis)
        machine.mpg(args.axis, args.pulses, args.ratio, args.rate)
    except ScriptError as exc:
        print(f"hil mpg: {exc}", file=__import__("sys").stderr)
        machine.close()
        return 2
    print(f"MPG {args.axis}: {args.pulses} pulses × {args.ratio} × 0.001 mm → "
          f"commanded {machine.command(args.axis) - x0:+.4f} mm, actual {machine.position(args.axis) - x0:+.4f} mm")
    return finish(machine)
