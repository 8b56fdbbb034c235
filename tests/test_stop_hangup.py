"""Closing the terminal a `hil run` shows its progress bar on (issue 17, bench decision B93): the kernel sends
SIGHUP, and from then on every write to the terminal fails with EIO. The stop along the path must go on as for any
SIGHUP — axes to rest within their limits, drives disabled at standstill, the trace finished — and `hil` exits
129 without a traceback (there is nobody to read the summary)."""

from __future__ import annotations

import errno
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
LONG = "G98\nG00 X58. Z98.\nG01 Z-300. F6000\n" + "G01 Z98.\nG01 Z-300.\n" * 63 + "M30\n"
OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)


class HungUpTerminal:
    """A terminal that was closed: every write fails with EIO once `hung` is set."""

    def __init__(self) -> None:
        self.hung = False
        self.writes = 0

    def write(self, s: str) -> int:
        if self.hung:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        self.writes += 1
        return len(s)

    def flush(self) -> None:
        if self.hung:
            raise OSError(errno.EIO, os.strerror(errno.EIO))


def assert_stopped_under_control(trace: Path) -> None:
    tf = TraceFile(trace)
    assert tf.meta["end"]["reason"] == "SIGHUP" and tf.meta["end"]["complete"]
    assert tf.meta["end"]["bus"] == "closed"
    c = tf.arrays(["Z_sw", "Z_vel", "Z_act"])
    assert np.abs(c["Z_vel"]).max() > 99  # it was moving at full speed before the hang-up
    enabled = (c["Z_sw"] & 0x6F) == OP_ENABLED
    off = int(np.flatnonzero(enabled)[-1]) + 1  # first row with the drive out of Operation Enabled
    assert off < len(enabled) and not enabled[off:].any()
    assert abs(c["Z_vel"][off - 1]) < 0.01 and np.ptp(c["Z_act"][off - 1:]) < 1e-3  # at standstill, and stays
    a = np.diff(c["Z_vel"]) / 0.001
    assert np.abs(a).max() <= 4000.0 * 1.001  # Z's acceleration limit: a ramp, no step
    assert not trace.with_name(trace.name + ".part").exists()


def test_a_terminal_gone_mid_stop_does_not_cut_the_stop(tmp_path):
    """Lock-step, in process: at cycle 1500 (Z at 100 mm/s) the hang-up requests the stop and the progress bar's
    terminal fails from then on. The bar used to raise OSError inside the stop's cycles: no disable at standstill
    and the trace left as its .part."""
    from hil.progress import Progress
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.trace import open_trace
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"
    tty = HungUpTerminal()

    def hang_up(runner):
        if runner.cycle == 1500:
            tty.hung = True
            runner.request_stop("SIGHUP")

    runner = BenchRunner(bench, make_link(bench), None, on_cycle=hang_up,
                         progress=Progress(len(LONG.splitlines()), stream=tty, every=0.0))
    runner.trace = open_trace(tmp_path / "t.parquet", runner.trace_columns())
    result = runner.run_program(parse_program(LONG, name="long.nc"))
    assert result.stopped_by == "SIGHUP" and tty.writes > 0
    assert_stopped_under_control(tmp_path / "t.parquet")


@pytest.mark.skipif(sys.platform != "linux", reason="a pseudo-terminal")
def test_closing_the_terminal_stops_the_run_like_a_hangup(tmp_path):
    """`hil run` on a pseudo-terminal (progress bar on, as an engineer's shell shows it), the terminal closed once
    the run is under way."""
    import pty

    prog = tmp_path / "long.nc"
    prog.write_text(LONG)
    trace = tmp_path / "run.parquet"
    pid, fd = pty.fork()
    if pid == 0:  # the child: its controlling terminal is the pty; stderr goes to the pty as well
        try:
            os.environ["PYTHONPATH"] = str(ROOT)
            os.execv(sys.executable, [sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(LATHE),
                                      "--trace", str(trace), "--no-check"])
        finally:
            os._exit(127)
    parts = trace.with_name(trace.name + ".part")
    deadline = time.monotonic() + 60
    seen = b""
    while not list(parts.glob("*.parquet")) and time.monotonic() < deadline:
        try:  # keep the terminal drained, as a terminal window does
            import select

            if select.select([fd], [], [], 0.02)[0]:
                seen += os.read(fd, 65536)
        except OSError:
            break
    time.sleep(0.3)
    os.close(fd)  # the window closed: SIGHUP to the run, EIO on every write after
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 129, seen.decode(errors="replace")[-2000:]
    assert_stopped_under_control(trace)
