"""A second process that works the program's fitted windows out ahead of a real-time run (decision bench B86).

Real time paces every cycle to the bench's period; a fitted run's window (nc/motion/spline_feed.py, 7–35 ms of
CPU) in one cycle overran it by as much, so a dense CAM program on a real bus starved its drives for tens of
milliseconds every 20 segments. A controller prepares blocks ahead of its interpolator; here a forked child runs
the same program offline (interpreter, channel, planner: nc.motion.offline) on the other CPU, and sends each window
it fits to the run (nc.motion.fit_memo), which takes it instead of fitting in the cycle. The setpoints are the
same bits either way: a window the child did not see the same way (an override, MLC data, a feed hold) is
fitted in the cycle as before.

The child is forked before power-up (a fork copies the page tables: milliseconds the paced cycles do not have),
waits for the axes' start position, has no bus, no MLC and no signal handlers of the run, runs at normal
scheduling on the CPUs the run does not pin, and ends with its program, when the run closes the pipe, or when
the run ends it (`close`).
"""

from __future__ import annotations

import copy
import os
import signal
from dataclasses import dataclass
from typing import TYPE_CHECKING

from nc.motion.fit_memo import FitReceiver, FitSender
from nc.motion.limits import MotionConfig

if TYPE_CHECKING:  # multiprocessing's connection module (≈ 5 ms) loads in `start`: every run imports this module
    from multiprocessing.connection import Connection


MARK_CYCLES = 200  # the child's cycles after which the run may start (`prefetch`)


@dataclass
class FitAhead:
    pid: int
    start_conn: Connection  # the start position goes to the child through it
    memo: FitReceiver

    def begin(self, start: dict[str, float]) -> None:
        """The axes stand at `start`: the child runs the program from there."""
        try:
            self.start_conn.send(start)
        except OSError:  # the child is gone: every window is fitted in the cycle
            pass
        self.start_conn.close()

    def prefetch(self, timeout: float) -> None:
        """Before the paced cycles: wait up to `timeout` s until the child is MARK_CYCLES into its run (or ended).
        The run's look-ahead completes its first windows within a few cycles of the start, before the child,
        started at the same time, could have them; past those first cycles the child runs faster than real time.
        The windows in hand then are decoded here too (B98): the first of them is needed a few cycles into the run,
        before its slacks could have decoded it."""
        import time

        memo, deadline = self.memo, time.monotonic() + timeout
        try:
            while not memo.closed and not memo.marked:
                left = deadline - time.monotonic()
                if left <= 0.0 or not memo.conn.poll(left):
                    break
                memo._read()
        except (EOFError, OSError):
            memo.closed = True
        while time.monotonic() < deadline and memo.work_part(read=False):
            pass

    def close(self) -> tuple[int, int]:
        """End the child (whatever it still has to do) and reap it; (windows taken from it, fitted in the cycle)."""
        for conn in (self.start_conn, self.memo.conn):
            conn.close()
        try:
            os.kill(self.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            os.waitpid(self.pid, 0)
        except ChildProcessError:
            pass
        return len(self.memo.found), len(self.memo.fitted)


def mode() -> str:
    """"auto" (real time only), "off" (DELTAHIL_FIT_AHEAD=0: A/B runs, or no fork here) or "wait" (DELTAHIL_FIT_AHEAD=wait:
    lock-step too, each window waited for: tests that compare it with fitting in the cycle)."""
    env = os.environ.get("DELTAHIL_FIT_AHEAD", "auto")
    if env == "0" or not hasattr(os, "fork"):
        return "off"
    return "wait" if env == "wait" else "auto"


def start(interp, program, cfg: MotionConfig, guess: dict[str, float], wait: bool = False) -> FitAhead | None:
    """Fork the child for `program` (a parsed Program) on a copy of `interp` as it stands now, starting at once from
    `guess` (where the axes are believed to stand before power-up; `begin` says where they do). None where fork
    fails. `wait`: the run waits for each window the child has not sent yet (lock-step tests)."""
    from multiprocessing.connection import Pipe  # only a run that fits ahead loads it (B84)

    pipes: list[Connection] = []
    try:  # a machine out of file descriptors or processes: every window is fitted in the cycle, as without it
        pipes += Pipe(duplex=False)
        pipes += Pipe(duplex=False)
        capacity = _widen(pipes[1])
        pid = os.fork()
    except OSError:
        for c in pipes:
            c.close()
        return None
    results_r, results_w, start_r, start_w = pipes
    if pid == 0:  # the child: never returns into the run's code
        code = 0
        try:
            results_r.close()
            start_w.close()
            _child(interp, program, cfg, dict(guess), start_r, FitSender(results_w, capacity))
        except BaseException:  # noqa: BLE001 - the run fits what it does not get; nothing to report from here
            code = 1
        finally:
            os._exit(code)  # not the run's atexit handlers, buffers or trace writer
    results_w.close()
    start_r.close()
    return FitAhead(pid, start_w, FitReceiver(results_r, wait=wait))


def _widen(conn: Connection) -> int:
    """The pipe as wide as an unprivileged process may make it (Linux: 1 MiB, ≈ 10 windows of ≈ 93 kB): the child
    waits once the run is that far behind (a 64 kB pipe held less than one window: the child then ran in step
    with the run, one window behind). Its size in bytes, 0 where unknown (the child then writes without waiting
    for room)."""
    try:
        import fcntl

        with open("/proc/sys/fs/pipe-max-size") as f:
            size = int(f.read())
        return fcntl.fcntl(conn.fileno(), getattr(fcntl, "F_SETPIPE_SZ", 1031), size)
    except (OSError, ValueError, ImportError):
        return 0


class _Moved(Exception):
    """The axes stood elsewhere than guessed: the program again from there."""

    def __init__(self, start: dict[str, float]) -> None:
        self.start = start


def _child(interp, program, cfg: MotionConfig, start: dict[str, float], start_r: Connection,
           sender: FitSender) -> None:
    """Run the program offline from `start`, sending every window; when the run's `begin` says the axes stood
    elsewhere, again from there (the windows already sent are keyed by their vertices: they stay unused)."""
    # a Ctrl-C or Ctrl-\ (the terminal's, to the whole group) is the run's to stop it (B94); the run ends this child
    for s in (signal.SIGINT, signal.SIGQUIT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_IGN if s in (signal.SIGINT, signal.SIGQUIT) else signal.SIG_DFL)
    try:
        os.nice(5)
    except OSError:
        pass
    try:  # Linux: the child ends with the run even when the run is killed (a pipe it never writes to again)
        import ctypes

        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    interp.servo.handler = None  # G10 L40-L46 would talk to the bus: not from here
    from nc.motion.offline import run

    known: list[bool] = [False]  # the run's start position arrived

    def check(n: int, _ch) -> None:
        sender.flush()  # a window fitted in the cycle before: its spans went through the look-ahead since (B99)
        if n == MARK_CYCLES:
            sender.mark()
        if not known[0] and n % 16 == 0 and start_r.poll():
            known[0] = True
            actual = start_r.recv()
            if actual != start:
                raise _Moved(actual)

    while True:
        try:
            it = copy.deepcopy(interp)  # each attempt from the interpreter as the run left it
        except Exception:  # noqa: BLE001 - something in it does not copy: one attempt, on the interpreter itself
            it = interp
        it.take_position(start)
        try:
            run(it.run(program), cfg, start, keep=False, fit_memo=sender, on_cycle=check)
        except _Moved as moved:
            if it is interp:
                return
            start = moved.start
            continue
        if not known[0]:  # the program ran out before the run began: was it from there?
            known[0] = True
            actual = start_r.recv()  # EOFError when the run ends before its program starts
            if actual != start and it is not interp:
                start = actual
                continue
        break
    sender.flush()
    sender.conn.close()
