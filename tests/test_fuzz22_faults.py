"""Faults from every side of `hil run` / `hil check` / `hil campaign`, as a user meets them (session 21, fuzz22).

The seeded sweep (`tests/fuzz22_gen.py`) throws broken bench files, programs that are not text, malformed `--at`
events, unwritable traces and signals at random moments at the CLI in a subprocess, and checks each ends as
README "Exit codes" says: a documented code, no traceback, no internal error, a message naming what was wrong, a
result line for every run that started, and a trace complete or absent. The findings are pinned below it.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz22_gen as gen  # noqa: E402

ROOT = gen.ROOT


@pytest.fixture(scope="module")
def good_trace(tmp_path_factory) -> Path:
    return gen.prepare(tmp_path_factory.mktemp("fuzz22good"))


# a few seeds per side: each case is one `hil` process (0.5-3 s); `explore` more with FUZZ22_SEEDS=N
_N = int(os.environ.get("FUZZ22_SEEDS", "3"))


@pytest.mark.parametrize("kind", gen.KINDS)
@pytest.mark.parametrize("seed", range(_N))
def test_every_fault_ends_as_documented(tmp_path, good_trace, kind, seed):
    c = gen.case(seed, kind, tmp_path)
    bad = gen.judge(c)
    assert not bad, (c.note, c.argv[3:], bad, c.output[-800:])


def _run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    prog = tmp_path / "p.nc"
    prog.write_text(gen.PROGRAM)
    return subprocess.run([sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(gen.MILL), "--no-check",
                           *args], capture_output=True, text=True, cwd=ROOT,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=120)


@pytest.mark.parametrize("at", ["t=1:set D21002=1e400", "t=1:set D21002=nan", "t=1:set D21002=-inf",
                                "t=1:set D21002=\u0665", "t=1:set D21002=1_0", "t=\u0661:reset",
                                "line=\u0663:reset", "Z<-\u0660.5:reset"])
def test_an_event_value_that_is_not_an_ascii_finite_number_is_refused_before_the_run(tmp_path, at):
    """`--at "t=1:set D21002=1e400"` (or nan) started the run and ended it at 1 s in `ALARM ... NC internal
    error: OverflowError` (exit 1); `D21002=٥` and `t=١` were taken as 5 and 1 (Python's float() reads any
    script's digits, and `1_0` as 10). Decision B106: refused with exit 2 naming the event, no cycle run."""
    p = _run(tmp_path, "--at", at)
    assert p.returncode == 2, (p.returncode, p.stdout[-400:], p.stderr[-400:])
    assert "--at" in p.stderr and "Traceback" not in p.stderr + p.stdout and "NC internal error" not in p.stdout
    assert "cycles" not in p.stdout  # nothing ran


def test_a_good_event_value_still_sets_its_register(tmp_path):
    p = _run(tmp_path, "--at", "t=0.2:set D21002=+5.0e1")
    assert p.returncode == 0, p.stderr
    assert "result         completed" in p.stdout


@pytest.mark.parametrize("signum, code", [(2, 130), (15, 143)])
def test_a_signal_during_a_serial_campaign_interrupts_it_and_no_cut_run_is_a_completed_row(tmp_path, signum, code):
    """Ctrl-C during `hil campaign --workers 0` reached the case's run, which stopped under control as `hil run`
    does; the campaign then wrote that case as `completed` (with a third of its cycles and a trace cut short),
    went on with the next cases and exited 0. Decision B107: the stopped run ends the campaign as interrupted
    (130 for SIGINT, 143 for SIGTERM, README), its row is not written, and the same command resumes it."""
    import signal
    import time

    import pyarrow.parquet as pq

    prog = tmp_path / "long.nc"
    # six 400 mm passes at F600 (240 s at 100 %, 160 s at 150 %): a case lasts seconds of wall time even with the
    # compiled drive kernel (B113), so the signal below lands inside the campaign (two passes, 81 s, were over
    # before it on an idle box)
    prog.write_text("G00 X-200. Y0.\n" + "G01 X200. F600.\nX-200.\n" * 3 + "G00 X0.\nM30\n")
    camp = tmp_path / "c.toml"
    camp.write_text(f'[campaign]\nprograms = ["{prog}"]\nbenches = ["{gen.MILL}"]\noverrides = [100, 150]\n')
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "hil.cli", "campaign", str(camp), "--out", str(out), "--workers", "0", "--quiet",
            "--no-reports"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # as from a terminal: Ctrl-C's default action (a shell's background job would start it ignored)
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while not any(out.glob("*")) and time.monotonic() < deadline:  # the campaign has begun its first case
        time.sleep(0.05)
    time.sleep(0.5)
    p.send_signal(signum)
    _, err = p.communicate(timeout=120)
    assert p.returncode == code, (p.returncode, err[-500:])
    assert "Traceback" not in err and "resume" in err
    rows = pq.read_table(out / "results.parquet").to_pylist() if (out / "results.parquet").exists() else []
    full = {100.0: None, 150.0: None}
    for r in rows:  # whatever was written is a whole run
        assert r["status"] == "completed" and r["program_time_s"] > 150, r  # 241 s at 100 %, 161 s at 150 %
    # the same command resumes and finishes every case
    p2 = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert p2.returncode == 0, p2.stderr[-500:]
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert sorted(r["override"] for r in rows) == sorted(full) and all(r["status"] == "completed" for r in rows)
    times = {r["override"]: r["program_time_s"] for r in rows}
    assert times[100.0] > 235 and times[150.0] > 155
