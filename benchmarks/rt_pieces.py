"""The thread CPU of a real-time run's work split by piece (benchmarks/rt_census.py, benchmarks/rt_slack_profile.py):
each wrapped callable is charged the thread CPU between the events around it, exclusive of the wrapped pieces it
calls, so a piece inside another counts once. Figures only: a wrapper costs ≈ 1 µs a call."""

from __future__ import annotations

import functools
import time
from collections.abc import Callable

_tt = time.thread_time_ns


class Pieces:
    """`account(label, ns)` gets every charge; `stack` the pieces running (innermost last); `gen_depth` > 0 inside a
    wrapped generator's step, where `wrap` labels with `gen_prefix`."""

    def __init__(self, account: Callable[[str, int], None], base: str | None = None, gen_prefix: str = "") -> None:
        self.account = account
        self.stack: list[str] = [] if base is None else [base]
        self.mark = 0
        self.gen_depth = 0
        self.gen_prefix = gen_prefix

    def charge(self) -> None:
        """What ran since the last charge goes to the innermost piece (nothing where none runs)."""
        now = _tt()
        if self.stack:
            self.account(self.stack[-1], now - self.mark)
        self.mark = now

    def restart(self) -> None:
        """Charge nothing for the time until now."""
        self.mark = _tt()

    def wrap(self, label: str, f: Callable) -> Callable:
        @functools.wraps(f)
        def w(*a, **k):
            self.charge()
            self.stack.append(self.gen_prefix + label if self.gen_depth else label)
            try:
                return f(*a, **k)
            finally:
                self.charge()
                self.stack.pop()
        return w

    def wrap_gen(self, label: str, f: Callable) -> Callable:
        """A generator function whose every step is charged to `label` (the next start's parts, B22)."""
        @functools.wraps(f)
        def w(*a, **k):
            g = f(*a, **k)

            def steps():
                while True:
                    self.charge()
                    self.stack.append(label)
                    self.gen_depth += 1
                    try:
                        next(g)
                    except StopIteration:
                        return
                    finally:
                        self.charge()
                        self.stack.pop()
                        self.gen_depth -= 1
                    yield
            return steps()
        return w
