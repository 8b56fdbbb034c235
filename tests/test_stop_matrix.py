"""The stop-path matrix (issue 15): every way a run ends × every bus, through `hil run` as a user
runs it, in its own process. Each cell checks what a controller engineer checks at a bench:

- the exit code is the documented one (README: 0, 1, 128 + signal) and the summary is printed;
- while a drive followed the NC (Operation Enabled) its setpoints kept the axis's v/a/j limits, and
  where it braked on its own quick stop (E-stop, a failed planner) it kept the axis's acceleration;
- each drive left Operation Enabled / Quick Stop Active only at standstill, and nothing moved after;
- the bus was closed, and the trace is whole, with an end record naming the reason.

Reasons: program end, an alarm (MLC user alarm A1), E-stop (M2x013), an internal error injected
into the NC channel, SIGINT, SIGTERM, SIGHUP, the run's --max-time (the second Ctrl-C:
tests/test_stop_signals.py).
Buses: the in-process sim, canopen:virtual, and EtherCAT over a veth pair (root only)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hil.bench_file import load_bench_file
from hil.trace_read import TraceFile
from virtual_bus.ethercat.veth import SimProcess, can_create

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
# Z at 100 mm/s from t≈0.7 s, back and forth for ≈ 510 s of simulated time: a signal sent once the run is
# under way (its first trace part, ≈ 2 s of wall time) must land mid-program however fast the cycle runs (the
# lathe's stretches ran ≈ 170 s of it in under 2 s of wall time, issue 17, session 11).
LONG = "G98\nG00 X58. Z98.\nG01 Z-300. F6000\n" + "G01 Z98.\nG01 Z-300.\n" * 63 + "M30\n"
SHORT = "G98\nG00 X58. Z98.\nG01 Z50. F6000\nM30\n"
OP_ENABLED, QUICK_STOP = 0x27, 0x07
EC_REASON = can_create()

# reason -> (program, extra hil args, exit code, the trace's end reason, first alarm)
REASONS = {
    "end": (SHORT, [], 0, "completed", None),
    "alarm": (LONG, ["--at", "t=1.5:set A1=1"], 1, "alarm", "A1"),
    "estop": (LONG, ["--at", "t=1.5:estop"], 1, "alarm", "0x0401"),
    "internal": (LONG, [], 1, "internal error", "0x0000"),
    "SIGINT": (LONG, [], 130, "SIGINT", None),
    "SIGTERM": (LONG, [], 143, "SIGTERM", None),
    "SIGHUP": (LONG, [], 129, "SIGHUP", None),  # the terminal hung up (B93)
    "max_time": (LONG, ["--max-time", "2"], 1, "max_time", "0xDE03"),  # the run's time budget (B13)
}


@pytest.fixture(scope="module")
def ethercat_line():
    if EC_REASON is not None:
        pytest.skip(EC_REASON)
    with SimProcess(tag="m") as sim:
        yield sim


def hil_run(tmp_path: Path, bus: str, reason: str) -> tuple[int, str, TraceFile]:
    text, extra, _, _, _ = REASONS[reason]
    prog = tmp_path / "prog.nc"
    prog.write_text(text)
    trace = tmp_path / "run.parquet"
    args = ["run", str(prog), "--bench", str(LATHE), "--bus", bus, "--trace", str(trace), "--no-progress",
            "--no-check", *extra]
    cmd = [sys.executable, str(ROOT / "tests" / "stop_matrix_inject.py"), "1500", *args] if reason == "internal" \
        else [sys.executable, "-m", "hil.cli", *args]
    p = subprocess.Popen(cmd, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    if reason.startswith("SIG"):
        parts = trace.with_name(trace.name + ".part")
        deadline = time.monotonic() + 60
        while not list(parts.glob("*.parquet")) and time.monotonic() < deadline and p.poll() is None:
            time.sleep(0.02)  # the first row group is on disk: Z is at full speed
        p.send_signal(getattr(signal, reason))
    out, err = p.communicate(timeout=180)
    assert "Traceback" not in err, err
    assert not trace.with_name(trace.name + ".part").exists()
    return p.returncode, out + err, TraceFile(trace)


def assert_stopped_under_control(tf: TraceFile, moving_at_stop: bool) -> None:
    bench = load_bench_file(LATHE)
    for ax in bench.axes:
        c = tf.arrays([f"{ax.name}_{k}" for k in ("cmd", "act", "vel", "sw")])
        sw = c[f"{ax.name}_sw"].astype(np.int64) & 0x6F
        cmd, vel = c[f"{ax.name}_cmd"], c[f"{ax.name}_vel"]
        lim = ax.limits
        for order, top in ((1, lim.max_velocity), (2, lim.max_acceleration), (3, lim.max_jerk)):
            d = np.abs(np.diff(cmd, n=order)) / 0.001 ** order
            followed = np.lib.stride_tricks.sliding_window_view(sw == OP_ENABLED, order + 1).all(axis=1)
            assert d[followed].max() <= top * 1.001, (ax.name, order)
        braking = (sw[1:] == QUICK_STOP) | (sw[:-1] == QUICK_STOP)
        if braking.any():  # the drive's own ramp (0x6085), within the axis's acceleration
            assert (np.abs(np.diff(vel)) / 0.001)[braking].max() <= lim.max_acceleration * 1.01, ax.name
        energised = np.isin(sw, (OP_ENABLED, QUICK_STOP))
        off = int(np.flatnonzero(energised)[-1]) + 1
        assert off < len(sw), f"{ax.name} never disabled"
        assert not energised[off:].any()
        assert abs(vel[off]) < 0.01 and abs(vel[off - 1]) < 2.0, (ax.name, vel[off - 1])  # disabled at standstill
        assert np.ptp(c[f"{ax.name}_act"][off:]) < 1e-3  # and nothing moved after
    if moving_at_stop:  # stopped mid-program: before the end of its ≈ 510 s (Z passes Z-300 at every reversal,
        assert tf.arrays(["t"])["t"][-1] < 500.0  # so where Z stood says nothing about the program's end)


@pytest.mark.parametrize("reason", list(REASONS))
@pytest.mark.parametrize("bus", ["sim", "canopen:virtual", "ethercat"])
def test_every_end_stops_the_axes_under_control(tmp_path, request, bus, reason):
    if bus == "ethercat":
        bus = f"ethercat:{request.getfixturevalue('ethercat_line').iface}"
    _, _, code, end_reason, alarm = REASONS[reason]
    rc, out, tf = hil_run(tmp_path, bus, reason)
    assert rc == code, out
    assert "program time" in out and "result" in out, out  # the summary, whatever the ending
    if reason.startswith("SIG"):
        assert f"STOPPED by {reason}" in out, out
    end = tf.meta["end"]
    assert end["reason"] == end_reason and end["complete"] and end["bus"] == "closed", end
    assert end["cycle"] == tf.num_rows
    if alarm is not None:
        assert end["alarm"] == alarm, end
    assert_stopped_under_control(tf, moving_at_stop=reason != "end")
    if reason == "internal":
        assert "injected planner bug" in out and "0x0000" in out


def test_max_time_is_alarm_0xfe01_and_the_axes_stop_along_the_path():
    """The bench's max_time runs out with Z at full speed: alarm 0xFE01, a stop along the path
    within the braking distance, drives disabled at standstill (decision B13)."""
    from hil.runner import MAX_TIME_ALARM, BenchRunner
    from hil.session import load_bench, make_link
    from nc.program import parse_program
    from tests.fault_helpers import Recorder, assert_stopped_after_alarm

    bench = load_bench(str(LATHE))
    bench.mlc, bench.max_time = "basic", 2.0
    rec = Recorder()
    result = BenchRunner(bench, make_link(bench), on_cycle=rec).run_program(parse_program(LONG, name="long.nc"))
    assert [a.code for a in result.alarms] == [MAX_TIME_ALARM] and result.alarms[0].line == 3
    assert abs(rec.vel[1999][1]) > 99  # Z at 100 mm/s when the time ran out
    assert_stopped_after_alarm(rec, result)
