"""`hil run PROGRAM`: execute a program on the bench (virtual bus by default) and summarise."""

from __future__ import annotations

import argparse
import sys

from hil.bench import Bench
from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE
from hil.runner import BenchRunner, RunResult
from hil.session import InputError, load_bench, load_program, make_link, print_alarm
from hil.trace import CsvTrace, trace_columns
from nc.alarms import NcAlarm


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a G-code program on the bench and print a summary")
    p.add_argument("program", help="G-code program file")
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--bus", help="sim | ethercat:IFACE | canopen:INTERFACE[:CHANNEL] (overrides the bench)")
    p.add_argument("--profile", help="controller profile (overrides the bench)")
    p.add_argument("--trace", metavar="FILE.csv", help="write every cycle to this CSV file")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    try:
        bench = load_bench(args.bench, args.profile, args.bus)
    except InputError as exc:
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        program = load_program(args.program)
    except NcAlarm as exc:
        print_alarm(exc.alarm)
        return EXIT_ALARM
    try:
        link = make_link(bench)
    except InputError as exc:
        print(f"hil run: {exc}", file=sys.stderr)
        return EXIT_USAGE
    trace = None
    if args.trace:
        spindles = [s.name for s in bench.spindles]
        try:
            trace = CsvTrace(args.trace, trace_columns(bench.axis_names, spindles))
        except OSError as exc:
            print(f"hil run: cannot write trace {args.trace}: {exc.strerror}", file=sys.stderr)
            return EXIT_USAGE
    runner = BenchRunner(bench, link, trace)
    result = runner.run_program(program)
    print_summary(args.program, bench, result)
    return EXIT_OK if result.ok else EXIT_ALARM


def print_summary(program: str, bench: Bench, r: RunResult) -> None:
    out = sys.stdout
    print(f"program        {program}  (profile {bench.profile}, bench {bench.name}, bus {bench.bus})", file=out)
    print(f"cycles         {r.cycles}  ({bench.cycle * 1000:g} ms cycle, {r.sim_time:.3f} s simulated)", file=out)
    print(f"drives enabled after {r.enable_cycles} cycles", file=out)
    print(f"program time   {r.program_time:.3f} s simulated", file=out)
    ferr = "  ".join(f"{a} {v:.4f} mm" for a, v in r.max_ferr.items())
    print(f"max following error  {ferr}", file=out)
    final = "  ".join(f"{a} {v:.4f}" for a, v in r.final.items())
    print(f"final machine position  {final}", file=out)
    if r.alarms:
        print(f"alarms         {len(r.alarms)}", file=out)
        for a in r.alarms:
            print(f"  {a}", file=out)
    else:
        print("alarms         none", file=out)
    print(f"result         {'completed' if r.ok else 'STOPPED'}", file=out)
