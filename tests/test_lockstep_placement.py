"""`[realtime] lockstep = "fifo"` (decisions E21): a lock-step `hil run` takes SCHED_FIFO on one CPU for the run
and gives the thread back its scheduling afterwards, however the run ends; `hil sim ethercat --bench` places
its slaves on the same CPU; without the privilege the run summary says what was refused and the run goes on."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from hil import api

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = "G98\nG00 X40. Z50.\nG01 Z20. F600\nM30\n"
ROOT_ONLY = pytest.mark.skipif(os.geteuid() != 0, reason="SCHED_FIFO needs root (CAP_SYS_NICE)")


def _cpu() -> int:
    return min(os.sched_getaffinity(0))  # not the default pick (the highest): the bench's `cpu` is what is used


def _bench(tmp_path: Path, priority: int = 30) -> Path:
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    assert "[realtime]\npriority = 80\n" in text
    p = tmp_path / "placed.toml"
    p.write_text(text.replace("[realtime]\npriority = 80\n",
                              f'[realtime]\nlockstep = "fifo"\npriority = {priority}\ncpu = {_cpu()}\n'))
    return p


def _now() -> tuple[int, int, frozenset[int]]:
    return os.sched_getscheduler(0), os.sched_getparam(0).sched_priority, frozenset(os.sched_getaffinity(0))


class Probe:
    """The runner's per-cycle progress hook: records this thread's scheduling during the run; from cycle
    `stop_at` on it ends the run the way `how` says (a signal's stop request, a second Ctrl-C, a bug)."""

    def __init__(self, how: str = "", stop_at: int = 0) -> None:
        self.seen: set[tuple[int, int, frozenset[int]]] = set()
        self.how, self.stop_at = how, stop_at
        self.fired = False

    def update(self, runner) -> None:
        self.seen.add(_now())
        if self.how and runner.cycle >= self.stop_at and (not self.fired or self.how == "hook raising every cycle"):
            self.fired = True
            if self.how == "SIGTERM":
                runner.request_stop("SIGTERM")  # what the signal handler does
            elif self.how == "second Ctrl-C":
                raise KeyboardInterrupt
            else:
                raise RuntimeError("a bug in a hook")

    def close(self) -> None:
        pass


@ROOT_ONLY
@pytest.mark.parametrize("how", ["", "SIGTERM", "second Ctrl-C", "internal error", "hook raising every cycle"])
def test_a_placed_lockstep_run_is_fifo_on_its_cpu_and_restored_however_it_ends(tmp_path, how):
    before = _now()
    assert before[0] != os.SCHED_FIFO
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    probe = Probe(how, stop_at=300)
    if how in ("second Ctrl-C", "hook raising every cycle"):  # the shutdown itself is cut: the run raises
        with pytest.raises((KeyboardInterrupt, RuntimeError)):
            api.run(prog, _bench(tmp_path), progress=probe, aux_timeout=0)
    else:
        r = api.run(prog, _bench(tmp_path), progress=probe, aux_timeout=0).run
        assert r.granted == f"lock-step placement: SCHED_FIFO prio 30 on CPU {_cpu()}"
        assert r.ok == (how == "")
        assert (r.stopped_by == "SIGTERM") == (how == "SIGTERM")
    assert probe.seen == {(os.SCHED_FIFO, 30, frozenset({_cpu()}))}
    assert _now() == before


def test_without_the_privilege_the_summary_says_so_and_the_run_completes(tmp_path):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    prefix: list[str] = []
    if os.geteuid() == 0:  # root: drop CAP_SYS_NICE for the child, as a user without it runs
        if shutil.which("setpriv") is None:
            pytest.skip("needs setpriv to drop CAP_SYS_NICE as root")
        prefix = ["setpriv", "--bounding-set", "-sys_nice"]

    def no_rtprio() -> None:  # an RLIMIT_RTPRIO above 0 would grant SCHED_FIFO without the capability
        import resource

        resource.setrlimit(resource.RLIMIT_RTPRIO, (0, 0))

    out = subprocess.run(prefix + [sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(_bench(tmp_path))],
                         capture_output=True, text=True, timeout=120, preexec_fn=no_rtprio,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    assert "Traceback" not in out.stdout + out.stderr
    line = next(x for x in out.stdout.splitlines() if x.startswith("placement"))
    assert f"default scheduling on CPU {_cpu()}" in line
    assert "SCHED_FIFO refused (Operation not permitted: needs root or CAP_SYS_NICE)" in line
    assert "result         completed" in out.stdout


@ROOT_ONLY
def test_hil_sim_ethercat_shares_the_cpu_of_a_placed_ethercat_run(tmp_path):
    from virtual_bus.ethercat.veth import SimProcess, can_create

    why = can_create()
    if why is not None:
        pytest.skip(why)
    bench = _bench(tmp_path, priority=20)
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    before = _now()
    probe = Probe()
    with SimProcess("--bench", str(bench), tag="place9") as sim:
        assert sim.banner.endswith(f"; SCHED_FIFO prio 20 on CPU {_cpu()}")
        assert os.sched_getscheduler(sim.proc.pid) == os.SCHED_FIFO
        assert os.sched_getaffinity(sim.proc.pid) == {_cpu()}
        r = api.run(prog, bench, bus=f"ethercat:{sim.iface}", progress=probe, aux_timeout=0).run
    assert r.ok, [a.code_text for a in r.alarms]
    assert r.final["Z"] == pytest.approx(20.0, abs=1e-3)  # the program ran to its end over the bus
    assert r.granted == f"lock-step placement: SCHED_FIFO prio 20 on CPU {_cpu()}"
    assert probe.seen == {(os.SCHED_FIFO, 20, frozenset({_cpu()}))}
    assert _now() == before


@pytest.mark.parametrize("args, message", [
    (["--priority", "0"], "--priority 0: a SCHED_FIFO priority from 1 to 99"),
    (["--priority", "100"], "--priority 100: a SCHED_FIFO priority from 1 to 99"),
    (["--cpu", "-1"], "--cpu -1: a CPU number (0, 1, ...)"),
])
def test_hil_sim_ethercat_refuses_a_bad_placement_before_it_serves(args, message):
    out = subprocess.run([sys.executable, "-m", "hil.cli", "sim", "ethercat", "--bus", "ethercat:lo", *args],
                         capture_output=True, text=True, timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 2
    assert out.stderr.strip() == f"hil sim ethercat: {message}"
