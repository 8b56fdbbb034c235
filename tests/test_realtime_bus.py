"""Real time on the field buses (issue 17, session 16; decisions E24, E25).

- A field bus's summary splits the cycle work: `bus wait` (the link's send and receive: the virtual slaves'
  answer) and `master work` (the rest, what a real line's cycle costs the master); the sim bus keeps its summary.
- `hil run --realtime` over the virtual EtherCAT slaves completes without an alarm (it stopped at cycle 5 with the
  SM watchdog's AL status 0x001B while mlockall ran after the slaves were in OP; decisions E23).
- Over CANopen the real-time clock paces the SYNC: the link no longer holds it back on a grid of its own (E24).

The root tests create their own network namespace and remove it (EtherCAT: a veth pair named with "rtb";
CANopen: tests/test_canopen_process.py's loopback-only namespace and `hil sim canopen`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from hil.api import run
from tests.conftest import ROOT
from tests.test_canopen_process import _Sim, netns  # noqa: F401  (a loopback-only namespace, removed after)
from virtual_bus.ethercat.veth import SimProcess, can_create

PROGRAM = "G21 G18 G98\nG01 X50. Z90. F1200\nM30\n"  # 0.6 s of motion on the lathe bench
BENCH = ROOT / "benches" / "lathe-2axis.toml"


def _summary_lines(text: str) -> dict[str, str]:
    return {line[:15].strip(): line[15:].strip() for line in text.splitlines() if len(line) > 15}


def test_canopen_lock_step_summary_splits_the_cycle_work(tmp_path, hil):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    r = hil("run", prog, "--bus", "canopen:virtual", "--no-check")
    assert r.code == 0, r.out + r.err
    lines = _summary_lines(r.out)
    for key in ("bus wait", "master work"):
        assert key in lines and lines[key].startswith("p50 ") and lines[key].endswith(" µs"), r.out
    res = run(prog, bus="canopen:virtual", check=False)
    t = res.run.timing
    # one wait and one master figure for every cycle whose work the summary counts
    assert t["bus_wait"]["count"] == t["master"]["count"] == t["exec"]["count"] == res.cycles
    assert 0 < t["bus_wait"]["p50"] and 0 < t["master"]["p50"] < t["exec"]["max"]


def test_sim_bus_summary_has_no_bus_lines(tmp_path, hil):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    r = hil("run", prog, "--no-check")
    assert r.code == 0, r.out + r.err
    assert "bus wait" not in r.out and "master work" not in r.out
    assert "bus_wait" not in run(prog, check=False).run.timing


def _run_realtime(cmd_prefix: list[str], prog, bench, bus: str) -> subprocess.CompletedProcess:
    """`hil run --realtime --no-check --trace` as its own process (mlockall and SCHED_FIFO stay out of pytest's).
    The trace, as the guide's run writes one: its Parquet writer makes the process the size whose mlockall
    outlasted the SM watchdog."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([*cmd_prefix, sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(bench),
                           "--bus", bus, "--realtime", "--no-check", "--trace", str(prog.with_suffix(".parquet"))],
                          capture_output=True, text=True, timeout=120, cwd=ROOT, env=env)


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_realtime_over_virtual_ethercat_slaves_completes(tmp_path):
    pytest.importorskip("pysoem", reason="the EtherCAT master needs pysoem")
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    with SimProcess("--bench", str(BENCH), tag="rtb") as sim:
        r = _run_realtime([], prog, BENCH, f"ethercat:{sim.iface}")
    _assert_completed(r)


def _assert_completed(r: subprocess.CompletedProcess) -> None:
    lines = _summary_lines(r.stdout)
    assert r.returncode == 0, r.stdout + r.stderr
    assert lines.get("result") == "completed" and lines.get("alarms") == "none", r.stdout
    assert "final machine position  X 25.0000  Z 90.0000" in r.stdout  # X50. is a diameter
    assert "bus wait" in lines and "master work" in lines, r.stdout


def _bench_4ms(tmp_path):
    bench = tmp_path / "lathe-4ms.toml"  # the canopen guide's 4 ms bench (44 % of 1 Mbit/s)
    bench.write_text(BENCH.read_text().replace("cycle_ms = 1.0", "cycle_ms = 4.0").split("[checks]")[0])
    return bench


def _against_sim(netns: str, group: str, bench, client) -> subprocess.CompletedProcess:
    """`client()` while `hil sim canopen` serves the bench's nodes on `group` in the namespace."""
    sim = _Sim(netns, group, "--bench", str(bench))
    try:
        assert sim.banner.startswith("hil sim canopen: nodes 1=X, 2=Z, 3=S1"), sim.banner
        return client()
    finally:
        sim.stop()


# Two exchanges back to back on an open link, 100 ms cycle, TPDOs waited for at most 20 ms: a link whose own
# SYNC producer holds the cycle sends the second SYNC a cycle after the first; a paced one sends it at once.
_BACK_TO_BACK = textwrap.dedent("""
    import json, sys
    from fieldbus.canopen.link import CanopenLink
    from fieldbus.pdo import RxPdo
    from hil.bench_file import load_bench_file
    bench = load_bench_file(sys.argv[1])
    out = {}
    for paced in (True, False):
        link = CanopenLink.for_bench(bench, "udp_multicast", sys.argv[2])
        link.cycle_time, link.tpdo_timeout, link.paced = 0.1, 0.02, paced
        link.open()
        try:
            rx = [RxPdo() for _ in link.nodes_cfg]
            link.exchange(rx)
            link.exchange(rx)
            out[str(paced)] = link.wait_ns
        finally:
            link.close()
    print(json.dumps(out))
""")


def test_canopen_paced_link_sends_the_sync_when_asked(netns, tmp_path):
    group = "239.74.163.17"
    bench = _bench_4ms(tmp_path)
    script = tmp_path / "b2b.py"
    script.write_text(_BACK_TO_BACK)
    r = _against_sim(netns, group, bench, lambda: subprocess.run(
        ["ip", "netns", "exec", netns, sys.executable, str(script), str(bench), group],
        capture_output=True, text=True, timeout=60, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT))))
    assert r.returncode == 0, r.stderr[-2000:]
    wait = json.loads(r.stdout.strip().splitlines()[-1])
    assert wait["False"] >= 50_000_000  # held: the 100 ms cycle from the first SYNC, less the first exchange
    assert wait["True"] < 50_000_000  # paced by the caller: sent at once, at most the 20 ms TPDO wait after it


def test_realtime_over_canopen_between_processes_completes(netns, tmp_path):
    group = "239.74.163.18"
    bench = _bench_4ms(tmp_path)
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    _assert_completed(_against_sim(netns, group, bench, lambda: _run_realtime(
        ["ip", "netns", "exec", netns], prog, bench, f"canopen:udp_multicast:{group}")))
