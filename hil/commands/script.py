"""`hil script SCRIPT.py [ARGS…]`: run an exercising script against the bench, then report what
every drive did (see hil.scripting and docs/guide/mlc.md)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("script", help="run an exercising script (MPG, jog, homing, spindle …) on the bench")
    p.add_argument("script", help="Python file with main(machine) or top-level code using `machine`")
    p.add_argument("args", nargs="*", help="passed to main(machine, *args)")
    add_bench_options(p)
    p.set_defaults(func=cmd_script)


def add_bench_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--bus", help="sim | ethercat:IFACE | canopen:INTERFACE[:CHANNEL]")
    p.add_argument("--mlc", metavar="MODULE",
                   help="MLC program: the bench's (default; lathe where that is basic) | lathe | module name | path.py")


def open_machine(args: argparse.Namespace):
    """Build and power up the bench for a script; returns (machine, exit code or None)."""
    from fieldbus.link import BusError
    from hil.scripting import Machine, ScriptError, mlc_setup
    from hil.session import InputError, load_bench, make_link, print_alarm

    try:
        bench = load_bench(args.bench, None, args.bus)
        spec = args.mlc or bench.mlc_program  # scripts drive the Delta relays: BasicMlc has none
        mlc, _, _ = mlc_setup(bench, spec if spec != "basic" else "lathe", None, 0.5)
        machine = Machine(bench, mlc, make_link(bench))
    except InputError as exc:
        print(f"hil {args.command}: {exc}", file=sys.stderr)
        return None, EXIT_USAGE
    try:
        machine.power_up()
    except ScriptError as exc:
        print(f"hil {args.command}: {exc}", file=sys.stderr)
        return None, EXIT_ALARM
    except BusError as exc:  # a bus that does not answer (no such interface …): its alarm, exit 1
        print_alarm(exc.alarm)
        machine.close()
        return None, EXIT_ALARM
    return machine, None


@contextmanager
def stoppable(machine) -> Iterator[None]:
    """SIGINT, SIGTERM, SIGHUP and SIGQUIT while a script, `hil mpg` or `hil spindle` drives the bench stop it as they
    stop `hil run` (B9, B96): the script ends at the next cycle (Machine.cycle raises SignalStop), the operator's
    RESET with the jog keys let go brings the motion to rest, the drives are disabled at standstill, the report is
    printed and `hil` exits 128 + n ("hil CMD: stopped by SIG…"). A second signal meanwhile disables at once."""
    from hil.stop_signals import SignalStop, stop_on_signals

    with stop_on_signals(machine.runner):
        try:
            yield
        except SignalStop:
            try:
                machine.stop_under_control()
            except KeyboardInterrupt:  # the second signal: no more waiting (B9)
                machine.runner._end_reason = "interrupted"
                raise
            finally:
                machine.close()  # standstill, then the drives disabled
            machine.report()  # where everything came to rest
            raise
        except KeyboardInterrupt:  # two signals before a cycle saw the first: disabled at once (B9)
            machine.runner._end_reason = "interrupted"
            machine.close()
            raise


def on_machine(args: argparse.Namespace, work: Callable[[argparse.Namespace, Any], int]) -> int:
    """`work(args, machine)` on the bench powered up for it, stoppable by a signal (B96)."""
    machine, code = open_machine(args)
    if machine is None:
        return code
    with stoppable(machine):
        return work(args, machine)


def finish(machine, ok: bool = True) -> int:
    machine.report()
    machine.close()
    return EXIT_OK if ok and not machine.active_alarms() else EXIT_ALARM  # a reset cleared the others (B59)


def cmd_script(args: argparse.Namespace) -> int:
    return on_machine(args, _script)


def _script(args: argparse.Namespace, machine) -> int:
    from fieldbus.link import BusError
    from hil.scripting import ScriptError, run_script
    from nc.alarms import NcAlarm

    try:
        run_script(args.script, machine, args.args)
    except ScriptError as exc:  # the API refused a call: where in the script, what it said (B80)
        line = _script_line(args, exc)
        print(f"hil script: {args.script}{f' at line {line}' if line else ''}: {exc}", file=sys.stderr)
        machine.report()
        machine.close()
        return EXIT_ALARM if "does not exist" not in str(exc) else EXIT_USAGE
    except (NcAlarm, BusError) as exc:  # a bus fault (station lost …) is an alarm, not a traceback
        print(str(exc.alarm), file=sys.stderr)
        machine.report()
        machine.close()
        return EXIT_ALARM
    except (SyntaxError, ValueError) as exc:  # not a Python file (syntax, NUL bytes): a bad input file
        if not isinstance(exc, SyntaxError) and "null bytes" not in str(exc):
            return _script_failed(args, machine, exc)
        print(f"hil script: {args.script} is not a Python script: {exc}", file=sys.stderr)
        machine.close()
        return EXIT_USAGE
    except Exception as exc:  # the script's own error: where it raised, then the drives' report
        return _script_failed(args, machine, exc)
    return finish(machine)


def _script_line(args: argparse.Namespace, exc: BaseException) -> int | None:
    """The script's line the exception came through last (its own frames, not hil's)."""
    import os
    import traceback

    mine = os.path.realpath(args.script)
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if os.path.realpath(f.filename) == mine]
    return frames[-1].lineno if frames else None


def _script_failed(args: argparse.Namespace, machine, exc: Exception) -> int:
    line = _script_line(args, exc)
    where = f" at line {line}" if line else ""
    print(f"hil script: {args.script} raised{where}: {type(exc).__name__}: {exc}", file=sys.stderr)
    machine.report()
    machine.close()
    return EXIT_ALARM
