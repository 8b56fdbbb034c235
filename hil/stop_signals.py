"""Signals end a run through the stop path, as an operator's reset would on the NC.

While a run is in progress, SIGINT (Ctrl-C), SIGTERM, SIGHUP and SIGQUIT (Ctrl-\\) only *request* a stop: the runner
sees the request at the next cycle, stops the axes along the path under control (jerk-limited, the
planner's reset), lets them settle, disables the drives at standstill, closes the bus and finishes
the trace with the signal as its end reason; `hil run` prints its summary and exits 128 + signal
number (130, 143, 129, 131). A second signal during that stop does not wait: it raises KeyboardInterrupt
at once, and the drives are disabled where they are (their own quick-stop ramp brakes them).
A SIGHUP or SIGQUIT that was ignored when the run started (nohup; a shell's background job) stays ignored (B94).
Ctrl-Z (SIGTSTP) is not taken while a run holds the drives on a field bus: a suspended master trips their
watchdogs (decision ethercat.md E36).
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

STOP_SIGNALS = tuple(s for s in (getattr(signal, "SIGINT", None), getattr(signal, "SIGTERM", None),
                                 getattr(signal, "SIGHUP", None), getattr(signal, "SIGQUIT", None)) if s is not None)
# Whoever started `hil` may have chosen to ignore these: nohup (SIGHUP), a shell's background job (SIGQUIT). SIGINT
# and SIGTERM are always a run's stop (a script's `kill -INT` of its background run stops it, as before).
KEEP_IGNORED = tuple(getattr(signal, n) for n in ("SIGHUP", "SIGQUIT") if hasattr(signal, n))


def _taken(s: int) -> bool:
    return not (s in KEEP_IGNORED and signal.getsignal(s) is signal.SIG_IGN)


@contextmanager
def stop_on_signals(runner: Any) -> Iterator[None]:
    """Route the stop signals to `runner.request_stop(name)` for the duration (main thread only:
    elsewhere Python cannot take signals, and the caller's own handling stays)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        name = signal.Signals(signum).name
        if getattr(runner, "disabling", False):  # the drives stand and are being disabled, a few cycles: what a
            if runner.stop_request is None:  # signal asks for is under way, and cutting it would leave them enabled
                runner.request_stop(name)  # (B95); a first one still ends the run as its stop (a campaign's, B114)
            return
        if runner.stop_request is not None:
            raise KeyboardInterrupt(f"second {name} during the stop")
        runner.request_stop(name)

    previous = {s: signal.signal(s, handler) for s in STOP_SIGNALS if _taken(s)}
    tstp = getattr(signal, "SIGTSTP", None)
    if tstp is not None and _on_a_field_bus(runner) and signal.getsignal(tstp) is not signal.SIG_IGN:
        previous[tstp] = signal.signal(tstp, _not_suspended)
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def _on_a_field_bus(runner: Any) -> bool:
    from fieldbus.link import SimLink

    link = getattr(runner, "link", None)
    return link is not None and not isinstance(link, SimLink)


def _not_suspended(signum: int, frame: Any) -> None:
    """E36: suspended, the master would stop sending process data; every drive's watchdog (EtherCAT SM watchdog,
    CANopen heartbeat) would trip and it would fault at speed. So the run goes on, and says how to stop it."""
    try:
        print("hil: Ctrl-Z (SIGTSTP) not taken while the drives are enabled on the field bus: a suspended master "
              "trips their watchdogs; Ctrl-C stops the run under control", file=sys.stderr, flush=True)
    except OSError:  # no terminal to say it on
        pass


def exit_code(name: str) -> int:
    return 128 + int(signal.Signals[name])


class SignalStop(KeyboardInterrupt):
    """SIGTERM, SIGHUP or SIGQUIT outside a run (start-up, bring-up's imports, writing the report): the command ends as
    Ctrl-C ends it there, its `finally` blocks and atomic writes done, and `hil` exits 128 + n saying so."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.name = name
        self.signal_name = name  # as a stopped campaign case's (CaseStopped): the campaign ends with its code (B117)


@contextmanager
def signals_end_command() -> Iterator[None]:
    """For the whole `hil` command (main thread): SIGTERM, SIGHUP and SIGQUIT whose handling is the default raise
    SignalStop (a run's own stop_on_signals takes them over while it runs), and SIGTERM ignored at start too (B117).
    An ignored SIGHUP (nohup) or SIGQUIT stays ignored; the previous handlers come back at the end."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise SignalStop(signal.Signals(signum).name)

    previous = {}
    for s in STOP_SIGNALS:  # SIGTERM ignored at start too: B94 makes it the command's always (B117)
        if s != signal.SIGINT and _taken(s) and signal.getsignal(s) in (signal.SIG_DFL, signal.SIG_IGN):
            previous[s] = signal.signal(s, handler)
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
