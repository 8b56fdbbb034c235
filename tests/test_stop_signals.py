"""Signals end `hil run` through the stop path (issue 15): a second signal, and an internal error in the
cycle loop (SIGINT, SIGTERM and SIGHUP on every bus: tests/test_stop_matrix.py). Each cell asserts what a controller engineer checks at a bench: the axes
decelerate within their limits, the drives leave Operation Enabled only at standstill and nothing
moves after, the trace is complete and names the signal, the summary is printed, and the exit code
is 128 + the signal's number."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hil.bench_file import load_bench_file
from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
# Z at 100 mm/s from t≈0.7 s, back and forth for ≈ 510 s of simulated time: a signal sent once the run is
# under way (its first trace part, ≈ 2 s of wall time) must land mid-program however fast the cycle runs (the
# lathe runs at ~85x real time since issue 17's session 11 work: 170 s of program ended before the signal once).
LONG = "G98\nG00 X58. Z98.\nG01 Z-300. F6000\n" + "G01 Z98.\nG01 Z-300.\n" * 63 + "M30\n"
OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)


def start(tmp_path: Path, bus: str, ignore: tuple[int, ...] | None = None) -> tuple[subprocess.Popen, Path]:
    """`hil run` on the long program, once it is under way. `ignore`: the stop signals start at their default but
    these ignored, as nohup or a shell's `&` leave them (pytest's own parent may be a background job, whose SIGQUIT
    is ignored); None: as this process has them."""
    prog = tmp_path / "long.nc"
    prog.write_text(LONG)
    trace = tmp_path / "run.parquet"

    def dispositions() -> None:
        for s in (signal.SIGINT, signal.SIGQUIT, signal.SIGHUP, signal.SIGTERM):
            signal.signal(s, signal.SIG_IGN if s in (ignore or ()) else signal.SIG_DFL)

    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(LATHE), "--bus", bus,
                          "--trace", str(trace), "--no-check", "--no-progress"],
                         preexec_fn=dispositions if ignore is not None else None,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    parts = trace.with_name(trace.name + ".part")
    deadline = time.monotonic() + 60
    while not list(parts.glob("*.parquet")) and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.02)  # the run is under way (its first row group is on disk)
    return p, trace


def test_a_second_signal_during_the_stop_disables_at_once(tmp_path):
    """In process, so the two signals land on known cycles: the first at cycle 1500 (Z at full
    speed) starts the controlled stop, the second 5 cycles later disables the drives at once."""
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.stop_signals import stop_on_signals
    from hil.trace import open_trace
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"

    def kill(runner):
        if runner.cycle in (1500, 1505):
            os.kill(os.getpid(), signal.SIGINT)

    runner = BenchRunner(bench, make_link(bench), None, on_cycle=kill)
    runner.trace = open_trace(tmp_path / "t.parquet", runner.trace_columns())
    with pytest.raises(KeyboardInterrupt), stop_on_signals(runner):
        runner.run_program(parse_program(LONG, name="long.nc"))
    tf = TraceFile(tmp_path / "t.parquet")  # the trace is still whole, and says the run was cut
    assert tf.meta["end"]["reason"] == "interrupted" and not tf.meta["end"]["complete"]
    c = tf.arrays(["Z_sw", "Z_vel"])
    enabled = (c["Z_sw"] & 0x6F) == OP_ENABLED
    off = int(np.flatnonzero(enabled)[-1]) + 1
    assert 1505 <= off <= 1530 and abs(c["Z_vel"][off - 1]) > 10  # disabled while still moving


def _second_signal_run(tmp_path, settle_time: float, when):
    """SIGINT at cycle 1500 (Z at 100 mm/s), and once more on the first cycle `when(runner)` holds after it."""
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.trace import open_trace
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"
    bench.settle_time = settle_time
    sent = []

    def kill(runner):
        if runner.cycle == 1500 or (len(sent) == 1 and when(runner)):
            sent.append(runner.cycle)
            os.kill(os.getpid(), signal.SIGINT)

    runner = BenchRunner(bench, make_link(bench), None, on_cycle=kill)
    runner.trace = open_trace(tmp_path / "t.parquet", runner.trace_columns())
    return runner, parse_program(LONG, name="long.nc"), sent


def test_a_second_signal_while_waiting_for_standstill_still_disables_and_finishes_the_trace(tmp_path):
    """The second signal landing in the shutdown's wait for standstill (the path stop done, an axis still settling:
    a bench with no settle time; on EtherCAT in lock-step that wait is long in wall time) skipped the rest of the
    shutdown: the drives were never disabled, the bus never closed and the trace left as its .part (bench decision
    B95). Now it disables at once there too, and the trace says `interrupted`."""
    from hil.stop_signals import stop_on_signals

    def settling(runner):
        return getattr(runner, "_winding_down", False) and not all(runner._at_rest(i) for i in range(len(runner.tx)))

    runner, prog, sent = _second_signal_run(tmp_path, 0.0, settling)
    with pytest.raises(KeyboardInterrupt), stop_on_signals(runner):
        runner.run_program(prog)
    assert len(sent) == 2 and sent[1] > 1500
    assert not (tmp_path / "t.parquet.part").exists()
    tf = TraceFile(tmp_path / "t.parquet")
    assert tf.meta["end"]["reason"] == "interrupted" and not tf.meta["end"]["complete"]
    assert tf.meta["end"]["bus"] == "closed"
    sw = tf.arrays(["Z_sw"])["Z_sw"]
    assert (sw[-1] & 0x6F) != OP_ENABLED and tf.num_rows <= sent[1] + 20  # disabled at once, not after a wait


def test_a_second_signal_while_the_standing_drives_are_disabled_lets_the_disable_finish(tmp_path):
    """The axes stand and the drives are being disabled (a few cycles): a second signal there would only cut the
    disable short and leave them enabled until the bus closes, so it is not taken (B95). The run ends as the first
    signal's stop, complete."""
    from hil.stop_signals import stop_on_signals

    runner, prog, sent = _second_signal_run(tmp_path, 0.3, lambda r: getattr(r, "disabling", False))
    with stop_on_signals(runner):
        result = runner.run_program(prog)
    assert len(sent) == 2 and result.stopped_by == "SIGINT"
    tf = TraceFile(tmp_path / "t.parquet")
    assert tf.meta["end"]["reason"] == "SIGINT" and tf.meta["end"]["complete"] and tf.meta["end"]["bus"] == "closed"
    sw = tf.arrays(["Z_sw"])["Z_sw"]
    assert (sw[-1] & 0x6F) != OP_ENABLED


def test_an_internal_error_in_the_cycle_loop_still_stops_under_control(tmp_path):
    """The planner raising mid-move (an injected bug at cycle 1500, Z at full speed) must not take
    the stop with it: the NC internal alarm 0x0000 is raised, every drive does its quick stop (CiA
    402, ramp 0x6085), and is disabled at standstill; the trace is finished and names the cause."""
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.trace import open_trace
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"

    def inject(runner):
        if runner.cycle == 1500:
            def broken():
                raise ZeroDivisionError("injected planner bug")
            runner.channel.step = broken

    runner = BenchRunner(bench, make_link(bench), None, on_cycle=inject)
    runner.trace = open_trace(tmp_path / "t.parquet", runner.trace_columns())
    result = runner.run_program(parse_program(LONG, name="long.nc"))
    assert not result.ok and result.alarms[0].code == 0x0000
    assert "injected planner bug" in result.alarms[0].message
    tf = TraceFile(tmp_path / "t.parquet")
    assert tf.meta["end"]["reason"] == "internal error" and tf.meta["end"]["alarm"] == "0x0000"
    c = tf.arrays(["Z_sw", "Z_vel", "Z_act"])
    assert abs(c["Z_vel"][1498]) > 99  # it was moving at full speed when the bug hit
    sw = c["Z_sw"] & 0x6F
    assert (sw[1500:1510] == 0x07).any()  # Quick Stop Active
    energised = np.isin(sw, (OP_ENABLED, 0x07))
    off = int(np.flatnonzero(energised)[-1]) + 1
    moving = np.flatnonzero(np.abs(c["Z_vel"]) > 0.01)
    assert moving[-1] < off  # the drive stood still before it was disabled
    assert np.ptp(c["Z_act"][off:]) < 1e-3  # and nothing moved after
    v = c["Z_vel"][1498:off]
    assert np.all(np.abs(np.diff(v)) <= 2.0)  # the drive's ramp (0x6085 = 1.56 m/s² on Z): no jump
    assert np.all(v * np.sign(v[0]) >= -0.01)  # braking only, no reversal


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_a_signal_leaves_no_temporary_check_trace(tmp_path, sig):
    """Without --trace, `hil run` judges the bench's checks on a temporary trace: a signal mid-run
    still judges them on what ran and removes it (nothing left in the temporary folder)."""
    prog = tmp_path / "long.nc"
    prog.write_text(LONG)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(LATHE), "--no-progress"],
                         env={**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmp)}, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not any(tmp.glob("hil-run-*")) and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.02)  # the run is under way: its temporary trace exists
    time.sleep(1.0)
    p.send_signal(sig)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 128 + sig and "checks" in out and "Traceback" not in err, out + err
    assert not list(tmp.iterdir())


def _signal_inside_the_command(monkeypatch, sig):
    """`hil run`'s work replaced by one that receives `sig` before any run starts (start-up, imports)."""
    import hil.commands.run as run_cmd

    def receives(args, scope):
        os.kill(os.getpid(), sig)
        time.sleep(2.0)  # the handler raises at once; never reached otherwise
        return 0

    monkeypatch.setattr(run_cmd, "_run_and_print", receives)


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_a_signal_before_the_run_ends_the_command_with_its_code(monkeypatch, capsys, sig, code):
    """SIGTERM/SIGHUP before a run has started (its own handlers not yet set) used to kill `hil` silently;
    now the command ends through its `finally` blocks, says so and exits 128 + n."""
    from hil.cli import main

    before = signal.getsignal(sig)
    _signal_inside_the_command(monkeypatch, sig)
    assert main(["run", str(ROOT / "examples" / "lathe_demo.nc")]) == code
    assert f"hil run: stopped by {signal.Signals(sig).name}" in capsys.readouterr().err
    assert signal.getsignal(sig) is before  # given back


def test_an_ignored_hangup_stays_ignored(monkeypatch, capsys):
    """Under nohup SIGHUP is ignored: `hil` leaves it so, and the command goes on."""
    from hil.cli import main

    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        _signal_inside_the_command(monkeypatch, signal.SIGHUP)
        monkeypatch.setattr(time, "sleep", lambda s: None)
        assert main(["run", str(ROOT / "examples" / "lathe_demo.nc")]) == 0
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, previous)


def test_a_ctrl_c_after_the_command_decided_its_exit_code_does_not_change_it(tmp_path):
    """A Ctrl-C in the `hil` process's last milliseconds (its summary printed, the teardown under way, the
    interpreter's finalization putting SIGINT back to the default) killed it by the signal: exit -2 to a caller's
    subprocess after `result completed` (found by tests/fuzz22_gen.py's signals once runs got faster). The outcome
    stands: SIGINT is ignored once main has its exit code."""
    prog = tmp_path / "short.nc"
    prog.write_text("G98\nG00 X58. Z98.\nG01 Z90. F6000\nM30\n")
    script = (
        "import os, signal, sys\n"
        "import hil.cli as cli\n"
        "real = cli._end_without_collections\n"
        "def late():\n"
        "    os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C once the command has its exit code\n"
        "    real()\n"
        "cli._end_without_collections = late\n"
        f"sys.argv = ['hil', 'run', {str(prog)!r}, '--bench', {str(LATHE)!r}, '--no-progress']\n"
        "sys.exit(cli.main())\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert out.returncode == 0, (out.returncode, out.stderr[-1500:])
    assert re.search(r"^result +completed", out.stdout, re.M)
    assert "Traceback" not in out.stderr
