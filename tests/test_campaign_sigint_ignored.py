"""A campaign started with SIGINT ignored — a non-interactive shell's background job, `hil campaign … &` — and then
sent `kill -INT` (decision bench B114). B94: SIGINT and SIGTERM are always the run's, ignored at start or not; B107:
a signal that stops a serial campaign's run interrupts the campaign (exit 130, the cut run no row, resumable). The
campaign ran on to its end instead, or lost the signal when it came between two cases' runs."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

import hil

sys.path.insert(0, str(Path(__file__).resolve().parent))  # test_campaign_interrupt's helpers

ROOT = Path(hil.__file__).resolve().parents[1]  # the deltahil under test, for the campaign's process
MILL = ROOT / "benches" / "mill-3axis.toml"


def _ignoring_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # as a shell starts a background job


def _campaign(tmp_path: Path, workers: str) -> tuple[list[str], dict[str, str]]:
    prog = tmp_path / "long.nc"
    # six 400 mm passes at F600: a case lasts seconds of wall time, so the signal lands inside the campaign
    prog.write_text("G00 X-200. Y0.\n" + "G01 X200. F600.\nX-200.\n" * 3 + "G00 X0.\nM30\n")
    camp = tmp_path / "c.toml"
    camp.write_text(f'[campaign]\nprograms = ["{prog}"]\nbenches = ["{MILL}"]\noverrides = [100, 150]\n')
    argv = [sys.executable, "-m", "hil.cli", "campaign", str(camp), "--out", str(tmp_path / "out"), "--workers",
            workers, "--quiet", "--no-reports"]
    return argv, dict(os.environ, PYTHONPATH=str(ROOT))


def _rows(out: Path) -> list[dict]:
    return pq.read_table(out / "results.parquet").to_pylist() if (out / "results.parquet").exists() else []


BETWEEN = """import os, signal, sys
from hil.campaign import Engine, orchestrate
update = orchestrate.Progress.update

def update_then_sigint(self, row):  # the first row written and counted: the campaign is between two cases' runs
    update(self, row)
    if not getattr(self, "signalled", False):
        self.signalled = True
        os.kill(os.getpid(), signal.SIGINT)  # what `kill -INT` of the background job does, at this moment

if sys.argv[3] == "between":
    orchestrate.Progress.update = update_then_sigint
else:  # in the last cycles of the first case's run, while its standing drives are disabled (B95)
    from hil.runner import BenchRunner
    exchange = BenchRunner._exchange

    def exchange_then_sigint(self, *a, **k):
        if self.disabling and not getattr(BenchRunner, "signalled", False):
            BenchRunner.signalled = True
            os.kill(os.getpid(), signal.SIGINT)
        return exchange(self, *a, **k)

    BenchRunner._exchange = exchange_then_sigint
print("ignored at start:", signal.getsignal(signal.SIGINT) is signal.SIG_IGN, flush=True)
outcome = orchestrate.run_campaign(sys.argv[1], sys.argv[2], Engine(workers=0))
print("interrupted:", outcome.interrupted, "rows:", len(outcome.rows), flush=True)
"""


def short_campaign(tmp_path: Path, script_text: str) -> tuple[Path, Path]:
    """A script (`script_text`) and the campaign it runs: three short cases on the mill (overrides 50/100/150 %)."""
    prog = tmp_path / "short.nc"
    prog.write_text("G00 X10. Y0.\nG01 X30. F600.\nM30\n")
    camp = tmp_path / "c.toml"
    camp.write_text(f'[campaign]\nprograms = ["{prog}"]\nbenches = ["{MILL}"]\noverrides = [50, 100, 150]\n')
    script = tmp_path / "between.py"
    script.write_text(script_text)
    return script, camp


@pytest.mark.parametrize("when, rows", [("between", 1), ("disabling", 0)])
def test_kill_int_between_two_runs_of_a_serial_campaign_started_with_sigint_ignored_is_not_lost(tmp_path, when, rows):
    """Between two cases (its row written, the next case not yet running) SIGINT, ignored at start, was lost: the
    campaign ran its remaining cases and ended as not interrupted. So was one (ignored at start or not) in a run's
    last cycles, while its standing drives are disabled: the run's handler let the disable finish (B95) and dropped
    it. The signal is sent by the campaign's process to itself at that moment, so the moment is exact. In the
    disable the first case's run ends as stopped by the signal: no row (B107), the same command runs it again."""
    script, camp = short_campaign(tmp_path, BETWEEN)
    p = subprocess.run([sys.executable, str(script), str(camp), str(tmp_path / "out"), when], capture_output=True,
                       text=True, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=300,
                       preexec_fn=_ignoring_sigint)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr[-800:]
    assert p.stdout.splitlines() == ["ignored at start: True", f"interrupted: True rows: {rows}"], p.stdout
    assert [r["status"] for r in _rows(tmp_path / "out")] == ["completed"] * rows
    assert (tmp_path / "out" / "journal.jsonl").exists() == bool(rows)  # kept: the same command resumes


def test_kill_int_during_a_run_of_a_serial_campaign_started_with_sigint_ignored_interrupts_it_resumably(tmp_path):
    argv, env = _campaign(tmp_path, "0")
    out = tmp_path / "out"
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env,
                         preexec_fn=_ignoring_sigint)
    deadline = time.monotonic() + 60
    while not any(out.glob("*")) and time.monotonic() < deadline:  # the campaign has laid out its output
        time.sleep(0.01)
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 130, (p.returncode, err[-500:])
    assert "Traceback" not in err and "hil campaign: interrupted; run the same command again to resume" in err
    for r in _rows(out):  # whatever was written is a whole run (241 s at 100 %, 161 s at 150 %)
        assert r["status"] == "completed" and r["program_time_s"] > 150, r
    assert len(_rows(out)) < 2
    p2 = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert p2.returncode == 0, p2.stderr[-500:]
    rows = _rows(out)
    assert sorted(r["override"] for r in rows) == [100.0, 150.0] and all(r["status"] == "completed" for r in rows)


def test_kill_int_of_a_dask_campaign_started_with_sigint_ignored_stops_it_with_130(tmp_path):
    """The local cluster's campaign: its process ignored SIGINT from the start, so no KeyboardInterrupt ever came and
    it ran to its end. Now `kill -INT` of it (not of its group: a script's `kill -INT $!`) ends it as Ctrl-C does."""
    from test_campaign_interrupt import _group_left

    p = busy_dask_campaign(tmp_path, _ignoring_sigint)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stdout + stderr
    assert "Traceback" not in stderr and "hil campaign: interrupted; run the same command again to resume" in stderr
    assert int(stdout.split("cases", 1)[1].split()[0]) < 4
    assert _group_left(p.pid, 20) == []  # no worker outlives the campaign


def busy_dask_campaign(tmp_path: Path, preexec) -> subprocess.Popen:
    """`hil campaign --workers 1` in its own process group, started with `preexec` (the signal dispositions it
    inherits), once its worker has taken its first case: the stalled cases (feed override 0) run to max_time, so
    the campaign is still busy at a signal sent now."""
    from test_campaign_interrupt import DATA, _workers

    for name in ("bench.toml", "short_turn.nc"):
        shutil.copy(DATA / name, tmp_path / name)
    (tmp_path / "c.toml").write_text(
        '[campaign]\nprograms = ["short_turn.nc"]\nbenches = ["bench.toml"]\nfaults = ["stall"]\nmax_time = 60\n'
        'overrides = [50, 60, 70, 80]\n[faults]\nstall = ["t=0.2:set FEED_OVERRIDE=0"]\n')
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "campaign", "c.toml", "--out", str(tmp_path / "out"),
                          "--workers", "1"], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                         preexec_fn=preexec)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None and not _workers(p.pid):
        time.sleep(0.1)
    time.sleep(1.0)  # the worker takes its first case
    assert p.poll() is None, p.communicate()
    return p
