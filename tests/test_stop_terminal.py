"""What an engineer's terminal does to a run (issue 17). Closing it (bench decision B93): the kernel sends SIGHUP, and
from then on every write to the terminal fails with EIO; the stop along the path must go on as for any SIGHUP — axes
to rest within their limits, drives disabled at standstill, the trace finished — and `hil` exits 129 without a
traceback (there is nobody to read the summary). Ctrl-\\ (SIGQUIT) and nohup (B94)."""

from __future__ import annotations

import errno
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hil.trace_read import TraceFile
from tests.test_stop_signals import start

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


def assert_stopped_under_control(trace: Path, reason: str = "SIGHUP") -> None:
    tf = TraceFile(trace)
    assert tf.meta["end"]["reason"] == reason and tf.meta["end"]["complete"]
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


def test_ctrl_backslash_stops_the_run_under_control(tmp_path):
    """SIGQUIT (Ctrl-\\) used to end `hil run` as Python leaves it, a core dump: no stop, no summary, the trace
    left as its .part (on a field bus the drives enabled until their watchdog). Now it is a stop like Ctrl-C's."""
    p, trace = start(tmp_path, "sim", ignore=())
    p.send_signal(signal.SIGQUIT)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 131, out + err
    assert "STOPPED by SIGQUIT" in out and "program time" in out and "Traceback" not in err
    assert_stopped_under_control(trace, "SIGQUIT")


def test_a_hangup_nohup_ignores_does_not_stop_the_run(tmp_path):
    """`nohup hil run …` so that the run outlives the terminal: SIGHUP is ignored, and it used to stop the run
    all the same (the run's own handler replaced the ignore). The run now goes to its end; the README said so."""
    p, trace = start(tmp_path, "sim", ignore=(signal.SIGHUP,))
    p.send_signal(signal.SIGHUP)
    time.sleep(0.5)
    assert p.poll() is None  # still running
    p.send_signal(signal.SIGTERM)  # (the whole 510 s program is not waited for)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 143 and "STOPPED by SIGTERM" in out, out + err
    assert_stopped_under_control(trace, "SIGTERM")


def test_ctrl_z_on_a_field_bus_is_not_taken_while_the_drives_are_enabled(capfd):
    """Ctrl-Z (SIGTSTP) suspends the process: on a field bus the master then stops sending, every drive's watchdog
    trips and they fault at speed (a `--realtime` run on the virtual EtherCAT bench, suspended 1 s: 0x0601 and 0xF002,
    X braking 5 m/s² on its own fault reaction). While a run holds the drives on a field bus it is not taken (decision
    ethercat.md E36): a line on stderr says so and how to stop instead, and the run goes on. In process on
    canopen:virtual; the test's own SIGTSTP handler stands in for the default (which would stop pytest) and must not
    be reached."""
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.stop_signals import stop_on_signals
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"
    bench.bus = "canopen:virtual"
    reached: list[int] = []
    previous = signal.signal(signal.SIGTSTP, lambda s, f: reached.append(s))
    try:
        def ctrl_z(runner):
            if runner.cycle == 300:
                os.kill(os.getpid(), signal.SIGTSTP)

        runner = BenchRunner(bench, make_link(bench), None, on_cycle=ctrl_z)
        with stop_on_signals(runner):
            result = runner.run_program(parse_program("G98\nG00 X50. Z50.\nG01 Z10. F3000\nM30\n", name="short.nc"))
        assert not reached and not result.alarms and result.stopped_by is None, result.alarms
        assert "Ctrl-Z" in capfd.readouterr().err
        assert signal.getsignal(signal.SIGTSTP) is not signal.SIG_DFL  # the test's own again
        os.kill(os.getpid(), signal.SIGTSTP)
        assert reached == [signal.SIGTSTP]
    finally:
        signal.signal(signal.SIGTSTP, previous)
