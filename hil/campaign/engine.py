"""Running a campaign's cases: serially in this process, or on Dask — a local cluster of one
worker process per core by default, or an existing cluster given by its scheduler address.

Dask does the distribution: a worker that dies has its case rescheduled on another one, and a
case that has lost `retries` workers comes back as `KilledWorker`, which becomes a `worker_lost`
row. A case never aborts the campaign: every outcome is a row.
"""

from __future__ import annotations

import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import closing, contextmanager
from dataclasses import dataclass
from typing import Any

from hil.campaign.inputs import CaseInputs
from hil.campaign.worker import lost_row, run_case


class SchedulerLost(Exception):
    """The cluster's scheduler went away mid-campaign (stopped, crashed, its host gone): the cases not
    finished were never judged, so they are no rows; the campaign ends like an interrupted one (B76)."""


@dataclass
class Engine:
    scheduler: str | None = None  # tcp://HOST:PORT of an existing cluster; None = a local cluster
    workers: int | None = None  # local cluster size (default: one per core); 0 = serially, in process
    retries: int = 3


def run_cases(cases: Sequence[CaseInputs], engine: Engine) -> Iterator[dict[str, Any]]:
    """Rows as cases finish, in completion order."""
    if not cases:
        return iter(())
    if engine.workers == 0 and engine.scheduler is None:
        return (run_case(c) for c in cases)
    return _dask(cases, engine)


def _dask(cases: Sequence[CaseInputs], engine: Engine) -> Iterator[dict[str, Any]]:
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": engine.retries - 1,
                          "distributed.worker.daemon": False,  # a worker may start its own processes
                          "distributed.admin.system-monitor.gil.enabled": False}):
        cluster = None
        try:
            if engine.scheduler is None:
                import os

                n = engine.workers or os.cpu_count() or 1
                # Ctrl-C reaches the whole foreground process group: the worker processes must leave it to
                # this one (which stops the cluster and writes what finished), not die with a traceback
                # each (bench B55). They are spawned ignoring SIGINT (SIG_IGN survives exec; Python and
                # asyncio then keep it), and _QuietWorker keeps a restarted worker the same. A Ctrl-C while
                # they start is held, not lost (B77, B126): it ends the campaign once the cluster is there to close.
                with _sigint_held():
                    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=None, host="127.0.0.1", silence_logs=50)
            yield from _on_cluster(cases, engine, cluster)
        finally:
            if cluster is not None:
                cluster.close()


def _on_cluster(cases: Sequence[CaseInputs], engine: Engine, cluster: Any) -> Iterator[dict[str, Any]]:
    """The cases on a cluster (ours, or the one at engine.scheduler), rows as they finish."""
    from distributed import Client

    client = Client(cluster if cluster is not None else engine.scheduler, timeout="30s")
    # a lost scheduler is the campaign's to report, not tracebacks from distributed's client
    with _quiet_client(), closing(client):
        if cluster is not None:
            client.register_plugin(_quiet_worker(), name="hil-sigint-ignored")
        # The scheduler decides when a case has lost too many workers; on a cluster that is not
        # ours it has its own setting, so the campaign's `retries` is set there for the campaign (and put
        # back after it: the cluster may be the team's, B101).
        saved = client.run_on_scheduler(_allow_failures, engine.retries - 1)
        try:
            yield from _cases_on(client, cases, engine)
        finally:
            if cluster is None and client.status == "running":
                _try(lambda: client.run_on_scheduler(_allow_failures, saved))


def _cases_on(client: Any, cases: Sequence[CaseInputs], engine: Engine) -> Iterator[dict[str, Any]]:
    from distributed import as_completed
    from distributed.client import FutureCancelledError

    by_key = {}
    futures = []
    for c in cases:
        # pure=False: a rerun is a new computation, never a cached result
        f = client.submit(run_case, c, key=f"case-{c.input_hash}-{time.monotonic_ns()}", pure=False)
        by_key[f.key] = c
        futures.append(f)
    for batch in as_completed(futures).batches():
        # the workers each case lost, from the scheduler's count, one call for what finished together (B101)
        lost = _try(lambda: client.run_on_scheduler(_workers_lost, [f.key for f in batch])) or {}
        for f in batch:
            case = by_key[f.key]
            try:
                row = f.result()
                row["attempts"] = 1 + lost.get(f.key, 0)
            except (FutureCancelledError, Exception) as exc:  # KilledWorker after `retries` lost workers
                if _scheduler_gone(client, exc):
                    where = engine.scheduler or "of the local cluster"
                    raise SchedulerLost(f"lost the connection to the scheduler {where}") from None
                row = lost_row(case, f"{type(exc).__name__}: {exc}", engine.retries)
            finally:
                f.release()
            yield row


def _try(call: Callable[[], Any]) -> Any:
    """A bookkeeping call to the scheduler that must not end the campaign (None when it fails: a lost
    scheduler is found, and reported, by the futures)."""
    try:
        return call()
    except Exception:
        return None


def _scheduler_gone(client: Any, exc: BaseException) -> bool:
    """A future cancelled because the client lost its scheduler (not a case's own failure)."""
    return "scheduler-connection-lost" in str(exc) or client.status not in ("running", "connecting", "newly-created")


@contextmanager
def _quiet_client() -> Iterator[None]:
    """distributed logs a lost scheduler as ERROR tracebacks on stderr, from its client, its batched comms and
    more; the campaign says what went wrong itself (B76), so every `distributed` logger is held at CRITICAL."""
    import logging

    import distributed  # noqa: F401  (its loggers exist once it is imported)

    names = ["distributed"] + [n for n in logging.root.manager.loggerDict if n.startswith("distributed.")]
    saved = [(log, log.level) for log in map(logging.getLogger, names)]
    for log, _ in saved:
        log.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for log, level in saved:
            log.setLevel(level)


# Python started through this ignores SIGINT from its first instruction: SIG_IGN survives exec, and Python then keeps it
SHIM = "#!/bin/sh\ntrap '' INT\nexec {python} \"$@\"\n"


@contextmanager
def _sigint_held() -> Iterator[None]:
    """While the local cluster's workers are spawned: they come up ignoring SIGINT, and a SIGINT this process gets
    meanwhile is held and raised as KeyboardInterrupt once the window closes.

    The terminal's Ctrl-C reaches the whole process group; it is the campaign's to handle, not the workers' (B55).
    The workers are spawned by multiprocessing from Dask's threads, through `multiprocessing.set_executable`'s
    program: for the window it is a shim that ignores SIGINT and execs this Python. This process notes the signal
    (a handler, not SIG_IGN: a `kill -INT` of its pid alone was discarded in the window, B77's "Left", B126)."""
    if threading.current_thread() is not threading.main_thread():
        yield  # only the main thread sets handlers (a campaign run from a library thread)
        return
    import multiprocessing
    import multiprocessing.spawn
    import os
    import shlex
    import tempfile

    came: list[int] = []
    folder = tempfile.mkdtemp(prefix="hil-campaign-")
    shim = os.path.join(folder, "python")
    with open(shim, "w") as f:
        f.write(SHIM.format(python=shlex.quote(sys.executable)))
    os.chmod(shim, 0o700)
    executable = multiprocessing.spawn.get_executable()
    old = signal.signal(signal.SIGINT, lambda signum, frame: came.append(signum))
    multiprocessing.set_executable(shim)
    try:
        yield
    finally:
        multiprocessing.set_executable(executable)
        signal.signal(signal.SIGINT, old)
        os.remove(shim)
        os.rmdir(folder)
    if came:
        raise KeyboardInterrupt


def _quiet_worker() -> Any:
    """A Dask worker plugin: the worker process ignores SIGINT (bench B55). Built here so that
    importing this module does not import distributed."""
    from distributed import WorkerPlugin

    class QuietWorker(WorkerPlugin):
        def setup(self, worker=None) -> None:
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)

    return QuietWorker()


def _allow_failures(n: int, dask_scheduler=None) -> int:
    """Set the scheduler's allowed failures a task; the value it had."""
    old, dask_scheduler.allowed_failures = dask_scheduler.allowed_failures, n
    return old


def _workers_lost(keys: list[str], dask_scheduler=None) -> dict[str, int]:
    """How many workers died while they held each task (the scheduler's `suspicious` count)."""
    tasks = dask_scheduler.tasks
    return {k: tasks[k].suspicious for k in keys if k in tasks and tasks[k].suspicious}


class Progress:
    """`cases 12/40  failed 2  ETA 0:45` on stderr: redrawn in place on a terminal, a line at most
    every `every` seconds otherwise (CI logs), nothing when quiet."""

    def __init__(self, total: int, quiet: bool = False, every: float = 10.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.total, self.quiet, self.every, self.clock = total, quiet, every, clock
        self.done = self.failed = 0
        self.t0 = self.clock()
        self.last = -1e9
        self.tty = sys.stderr.isatty()

    def line(self) -> str:
        elapsed = self.clock() - self.t0
        eta = "--"
        if self.done:
            left = elapsed / self.done * (self.total - self.done)
            eta = f"{int(left // 60)}:{int(left % 60):02d}"
        return f"cases {self.done}/{self.total}  failed {self.failed}  ETA {eta}"

    def update(self, row: dict[str, Any]) -> None:
        self.done += 1
        self.failed += row.get("status") != "completed"
        if self.quiet:
            return
        now = self.clock()
        if self.tty:
            print("\r" + self.line() + "   ", end="", file=sys.stderr, flush=True)
        elif now - self.last >= self.every or self.done == self.total:
            print(self.line(), file=sys.stderr, flush=True)
            self.last = now

    def close(self) -> None:
        if self.tty and not self.quiet:
            print(file=sys.stderr)


def host() -> str:
    return socket.gethostname()
