"""The `hil` command line. Each subcommand lives in `hil.commands.<name>` and registers itself,
so capabilities can be added without touching this file.

Exit codes (README): 0 success, 1 the run or program raised an alarm, 2 bad usage or a bad input
file, 3 a run that completed but failed a check (hil run), 128 + n for a run (or a command) stopped by signal n
(hil/stop_signals.py), 130 interrupted. No Python traceback reaches the user: an unexpected error is reported as
NC internal alarm 0x0000.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import pkgutil
import signal
import sys
import threading
from collections.abc import Sequence

import hil.commands
from hil.stop_signals import SignalStop, exit_code, signals_end_command
from nc.alarms import internal_error

EXIT_OK, EXIT_ALARM, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Bad arguments or a bad input file: exit 2 with a message naming what is wrong."""


class _Version(argparse.Action):
    """`--version`: the version of the source that runs (hil/version.py, decision B90)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from hil.version import version

        print(f"hil (deltahil) {version()}")  # on stdout, as argparse's own version action does
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Every subcommand registers itself; command modules import only argparse at the top and load
    what they run (the bench, pyarrow, python-can, the runner) inside their command function, so
    `hil path` does not pay for `hil run`'s imports (issue 16). `command`: only that subcommand's
    module (each module registers the command of its name), for a command line that names it."""
    parser = argparse.ArgumentParser(prog="hil", description="Delta NC5 hardware-in-the-loop bench driver")
    parser.add_argument("--version", action=_Version, help="show program's version number and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for mod in sorted(pkgutil.iter_modules(hil.commands.__path__), key=lambda m: m.name):
        if command is not None and mod.name != command:
            continue
        module = importlib.import_module(f"hil.commands.{mod.name}")
        register = getattr(module, "register", None)
        if register is not None:
            register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    if argv is not None:  # a caller's own process (a test, a script): it ends as its caller ends it
        return _main(list(argv))
    try:
        return _main(sys.argv[1:])
    finally:  # the `hil` command itself: the process ends when this returns
        _late_interrupts_ignored()
        _end_without_collections()


def _late_interrupts_ignored() -> None:
    """Once the command has decided its exit code (and printed its summary), a Ctrl-C in the last milliseconds of the
    process (the teardown, the interpreter's finalization, which puts SIGINT back to the default) would kill it by
    the signal: an exit of -2 to a caller's subprocess, after a summary that said `completed` (the fault sweep,
    tests/fuzz22_gen.py, hit it). The outcome stands: SIGINT is ignored from here on. SIGTERM keeps its default, so a
    supervisor can still end a teardown that hangs."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _end_without_collections() -> None:
    """The finalization's full garbage collections walk the ≈ 47,000 objects of a run's ≈ 450 modules, ≈ 35 ms of
    a `hil run`'s exit, to free memory the process gives back anyway (bench decision B83). Frozen, they are skipped.
    What a collection would have finalized is done here instead: a file a user's module keeps open in a reference
    cycle is flushed (its text written, as the collection's close would); ruckig's objects are released by their
    owners in the atexit handlers (nc/exit_release.py). The atexit handlers and the modules' teardown run as before."""
    import gc
    from _io import _IOBase  # the C base of every io class (io.IOBase is an ABC: a slow isinstance)
    from itertools import compress, repeat

    objects = gc.get_objects()
    # by type(obj), not isinstance: a proxy whose every attribute raises (canopen's network before it is
    # assigned) raises on isinstance's __class__ look-up; C iteration: ≈ 2 ms where a Python loop took ≈ 8
    for obj in compress(objects, map(issubclass, map(type, objects), repeat(_IOBase))):
        try:
            if not obj.closed:
                obj.flush()
        except Exception:  # a reader gone (BrokenPipeError), a detached wrapper: its close would fail as well
            pass
    del objects
    gc.freeze()


def _main(argv: list[str]) -> int:
    if "numpy" not in sys.modules:  # before numpy loads OpenBLAS, which reads it once
        # One OpenBLAS thread (bench decision B47): at numpy's import OpenBLAS starts a thread per core, whose
        # start-up spins ≈ 0.1 s of CPU on 2 cores in every `hil` process; deltahil's matrices are a few rows. A
        # user's own setting stays.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # `hil path …` registers `path` alone (some 150 arguments of every other command not built at
    # start-up); anything else (`hil --help`, a misspelt command) gets the whole parser
    first = argv[0] if argv else ""
    known = first.isidentifier() and any(m.name == first for m in pkgutil.iter_modules(hil.commands.__path__))
    parser = build_parser(first if known else None)
    args = parser.parse_args(argv)
    try:
        with signals_end_command():  # SIGTERM/SIGHUP outside a run: a message and 128 + n, not a silent death
            return int(args.func(args) or 0)
    except UsageError as exc:
        return _say(f"hil {args.command}: {exc}", EXIT_USAGE)
    except SignalStop as exc:
        return _say(f"hil {args.command}: stopped by {exc.name}", exit_code(exc.name))
    except KeyboardInterrupt:
        return _say("hil: interrupted", 130)
    except BrokenPipeError:
        return _reader_left()
    except OSError as exc:
        if exc.errno != errno.EIO:
            return _internal(exc)
        # EIO writing to the terminal: it was closed (hung up). The kernel sent SIGHUP, which stopped the run
        # under control; the summary has no one to read it. End as SIGHUP ends a command (B93).
        _terminal_gone()
        return exit_code("SIGHUP")
    except Exception as exc:  # never a traceback: report as the NC's internal alarm
        return _internal(exc)


def _internal(exc: Exception) -> int:
    return _say(str(internal_error(exc)), EXIT_ALARM)


def _say(text: str, code: int) -> int:
    """The last word on stderr, and the exit code; a closed terminal (SIGHUP's) does not turn it into a traceback."""
    try:
        print(text, file=sys.stderr)
    except OSError:
        _terminal_gone()
    return code


def _terminal_gone() -> None:
    """stdout and stderr point at the hung-up terminal: Python's exit would flush them again and print
    'Exception ignored …' to it, so both go to devnull."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        for stream in (sys.stdout, sys.stderr):
            os.dup2(null, stream.fileno())
    except (OSError, ValueError):  # not real files (pytest capture): nothing to flush
        pass


def _reader_left() -> int:
    """stdout's reader closed (`hil path … | head`): end quietly, exit 0 as README says. Python would
    flush stdout again at exit and print 'Exception ignored … BrokenPipeError', so point it at devnull."""
    import os

    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):  # stdout is not a real file (pytest capture): nothing to flush
        pass
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
