"""`hil spindle RPM [--seconds S] [--ccw] [--override PCT]`: start the spindle through M03/M04 S and the handshake
(the drive in CSV), hold it, stop it with M05, and report the ramps."""

from __future__ import annotations

import argparse

from hil.commands.script import add_bench_options, finish, on_machine


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("spindle", help="spin the spindle up to RPM, hold, stop, and report the ramps")
    p.add_argument("rpm", type=float, help="speed (S word)")
    p.add_argument("--seconds", type=float, default=1.0, help="time at speed before M05 (default 1 s)")
    p.add_argument("--ccw", action="store_true", help="M04 instead of M03")
    p.add_argument("--override", type=int, default=100, metavar="PCT",
                   help="spindle override D2x026 in %% (default 100): the drive runs at RPM x PCT/100")
    add_bench_options(p)
    p.set_defaults(func=cmd_spindle)


def cmd_spindle(args: argparse.Namespace) -> int:
    if not (0.0 <= args.rpm < float("inf") and 0.0 <= args.seconds < float("inf")):
        print(f"hil spindle: RPM {args.rpm:g} and --seconds {args.seconds:g} must be >= 0 (--ccw turns backwards)",
              file=__import__("sys").stderr)
        return 2
    return on_machine(args, _spindle)


def _spindle(args: argparse.Namespace, machine) -> int:
    if not machine.bench.spindles:
        print("hil spindle: the bench has no spindle", file=__import__("sys").stderr)
        machine.close()
        return 2
    if not 0 <= args.override <= 65535:
        print(f"hil spindle: --override {args.override} is outside 0-65535 %", file=__import__("sys").stderr)
        machine.close()
        return 2
    machine.spindle_override(args.override)
    up = machine.spindle(args.rpm, -1 if args.ccw else 1)
    machine.wait(args.seconds)
    rpm = machine.get_rpm()
    down = machine.spindle(0)
    ovr = f" at {args.override} % override" if args.override != 100 else ""
    print(f"spindle: M0{4 if args.ccw else 3} S{args.rpm:g}{ovr} finished after {up:.3f} s (speed reached), "
          f"{rpm:.1f} rpm at speed; M05 finished after {down:.3f} s (zero speed)")
    return finish(machine)
