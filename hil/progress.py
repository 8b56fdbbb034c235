"""A one-line progress bar on stderr for long runs: current program line and simulated time.

Shown only when stderr is a terminal (or when forced with `--progress`), redrawn at most every
0.2 s of wall time so it costs nothing per cycle.
"""

from __future__ import annotations

import sys
import time
from typing import IO, Any


class Progress:
    def __init__(self, last_line: int, stream: IO[str] | None = None, every: float = 0.2, width: int = 30) -> None:
        self.last_line = max(1, last_line)
        self.stream = stream or sys.stderr
        self.every = every
        self.width = width
        self._next = 0.0
        self._shown = False
        self._gone = False  # the terminal was closed (B93)

    def update(self, runner: Any) -> None:
        now = time.monotonic()
        if now < self._next or self._gone:
            return
        self._next = now + self.every
        self.draw(runner.line, runner.time)

    def draw(self, line: int, sim_time: float) -> None:
        frac = min(1.0, max(0.0, line / self.last_line))
        fill = int(frac * self.width)
        bar = "#" * fill + "-" * (self.width - fill)
        self._write(f"\r[{bar}] line {line}/{self.last_line}  t={sim_time:9.3f} s ")
        self._shown = not self._gone

    def close(self) -> None:
        if self._shown:
            self._write("\n")
            self._shown = False

    def _write(self, text: str) -> None:
        """A closed terminal (EIO after its hang-up) or a reader gone (EPIPE) ends the bar, not the run: the bar
        is drawn from the cycle loop, and the stop the hang-up asked for runs in that loop too (B93)."""
        if self._gone:
            return
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # ValueError: the stream was closed under it
            self._gone = True


def wants_progress(flag: bool | None, stream: IO[str] | None = None) -> bool:
    """--progress forces it on, --no-progress off; otherwise only on a terminal."""
    if flag is not None:
        return flag
    s = stream or sys.stderr
    return bool(getattr(s, "isatty", lambda: False)())
