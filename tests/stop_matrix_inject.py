"""`python tests/stop_matrix_inject.py CYCLE hil-args...`: `hil` with a bug injected into the NC
channel at bench cycle CYCLE (its step raises), for the stop-path matrix (tests/test_stop_matrix.py).
Everything else is the real command: its own process, bus, trace, summary and exit code."""

from __future__ import annotations

import os
import sys

os.environ["DELTAHIL_STRETCH"] = "0"  # the bug lands at an exact cycle: every cycle is stepped (hil/stretch.py)

from hil import runner  # noqa: E402
from hil.cli import main  # noqa: E402

AT = int(sys.argv[1])
_exchange = runner.BenchRunner._exchange


def _exchange_with_bug(self: runner.BenchRunner) -> None:
    if self.cycle == AT and self.channel is not None:
        def broken():
            raise ZeroDivisionError("injected planner bug")

        self.channel.step = broken
    _exchange(self)


runner.BenchRunner._exchange = _exchange_with_bug  # type: ignore[method-assign]
sys.exit(main(sys.argv[2:]))
