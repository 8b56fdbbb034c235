"""SIGTERM ignored when `hil` started (a supervisor's or a script's choice, `trap '' TERM`) is still the command's
(decision bench B117; B94: SIGINT and SIGTERM are always the run's, ignored or not). It was taken only inside a
run (stop_on_signals) and stayed ignored everywhere else: before or after the run of `hil run`, between a serial
campaign's cases, and in the whole of a local-cluster campaign (whose runs are the workers'), so `kill -TERM`
let the command run on to its end. Each test fails without B117."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq

import hil

sys.path.insert(0, str(Path(__file__).resolve().parent))  # test_campaign_interrupt's helpers

ROOT = Path(hil.__file__).resolve().parents[1]  # the deltahil under test, for the command's process
ENV = dict(os.environ, PYTHONPATH=str(ROOT))


def _ignoring_sigterm() -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)


def _script(script: Path, *args: Path) -> subprocess.CompletedProcess:
    """The script in a process started with SIGTERM ignored."""
    p = subprocess.run([sys.executable, str(script), *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                       env=ENV, timeout=300, preexec_fn=_ignoring_sigterm)
    assert "Traceback" not in p.stderr, p.stderr[-800:]
    return p


def _rows(out: Path) -> list[dict]:
    return pq.read_table(out / "results.parquet").to_pylist() if (out / "results.parquet").exists() else []


RUN = """import os, signal, sys
import hil.api as api
from hil.cli import main
run = api.run

def sigterm_then_run(*a, **k):  # `hil run` has started, its run has not: SIGTERM from outside at this moment
    os.kill(os.getpid(), signal.SIGTERM)
    return run(*a, **k)

api.run = sigterm_then_run
print("ignored at start:", signal.getsignal(signal.SIGTERM) is signal.SIG_IGN, flush=True)
code = main(["run", sys.argv[1], "--trace", sys.argv[2], "--no-check", "--no-progress"])
print("code:", code, flush=True)
"""


def test_kill_term_of_hil_run_outside_its_run_with_sigterm_ignored_at_start_stops_it_with_143(tmp_path):
    prog = tmp_path / "p.nc"
    prog.write_text("G00 X10. Z10.\nM30\n")
    script = tmp_path / "run.py"
    script.write_text(RUN)
    trace = tmp_path / "t.parquet"
    p = _script(script, prog, trace)
    assert p.stdout.splitlines()[0] == "ignored at start: True"
    assert p.stdout.splitlines()[-1] == "code: 143", p.stdout + p.stderr[-500:]
    assert "hil run: stopped by SIGTERM" in p.stderr
    assert not trace.exists() and not list(tmp_path.glob("*.part"))  # no run, no half-written trace


BETWEEN = """import os, signal, sys
from hil.campaign import orchestrate
from hil.cli import main
update = orchestrate.Progress.update

def update_then_sigterm(self, row):  # the first row written and counted: between two cases' runs
    update(self, row)
    if not getattr(self, "signalled", False):
        self.signalled = True
        os.kill(os.getpid(), signal.SIGTERM)

orchestrate.Progress.update = update_then_sigterm
print("ignored at start:", signal.getsignal(signal.SIGTERM) is signal.SIG_IGN, flush=True)
code = main(["campaign", sys.argv[1], "--out", sys.argv[2], "--workers", "0", "--quiet", "--no-reports"])
print("code:", code, "ignored after:", signal.getsignal(signal.SIGTERM) is signal.SIG_IGN, flush=True)
"""


def test_kill_term_between_two_runs_of_a_serial_campaign_with_sigterm_ignored_at_start_stops_it_resumably(tmp_path):
    from test_campaign_sigint_ignored import short_campaign

    script, camp = short_campaign(tmp_path, BETWEEN)
    out = tmp_path / "out"
    p = _script(script, camp, out)
    lines = p.stdout.splitlines()
    assert lines[0] == "ignored at start: True" and lines[-1] == "code: 143 ignored after: True", p.stdout
    assert "hil campaign: stopped by SIGTERM; run the same command again to resume" in p.stderr
    assert [r["status"] for r in _rows(out)] == ["completed"]
    assert (out / "journal.jsonl").exists()  # kept: the same command resumes
    assert not [f for f in out.rglob("*") if f.name.endswith((".part", ".tmp"))]  # no half-written file
    p2 = subprocess.run([sys.executable, "-m", "hil.cli", "campaign", str(camp), "--out", str(out), "--workers", "0",
                         "--quiet", "--no-reports"], capture_output=True, text=True, cwd=ROOT, env=ENV, timeout=300)
    assert p2.returncode == 0, p2.stderr[-500:]
    assert sorted(r["override"] for r in _rows(out)) == [50.0, 100.0, 150.0]


def test_kill_term_of_a_dask_campaign_with_sigterm_ignored_at_start_stops_it_with_143(tmp_path):
    """The local cluster: its runs are the workers', so the campaign's process never took SIGTERM and ran to its
    end (its workers, inheriting SIG_IGN, ignored the nanny's terminate too). Now `kill -TERM` of its pid ends it:
    143, no worker left, resumable."""
    from test_campaign_interrupt import _group_left
    from test_campaign_sigint_ignored import busy_dask_campaign

    p = busy_dask_campaign(tmp_path, _ignoring_sigterm)
    p.send_signal(signal.SIGTERM)
    try:
        stdout, stderr = p.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        raise AssertionError("the campaign ran on after kill -TERM") from None
    assert p.returncode == 143, stdout + stderr
    assert "Traceback" not in stderr and "hil campaign: stopped by SIGTERM; run the same command again to resume" \
        in stderr
    assert int(stdout.split("cases", 1)[1].split()[0]) < 4
    assert _group_left(p.pid, 20) == []  # no worker outlives the campaign
