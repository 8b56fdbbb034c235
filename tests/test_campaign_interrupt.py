"""Ctrl-C of `hil campaign` on its local Dask cluster (decisions B55): the terminal's SIGINT reaches the
whole process group; the campaign stops, writes what finished and exits 130, and no worker process
prints a KeyboardInterrupt traceback (before: one per worker) or outlives it."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import hil

DATA = Path(__file__).resolve().parent / "data" / "campaign"
ROOT = Path(hil.__file__).resolve().parents[1]  # the deltahil under test, for the campaign's process


def test_ctrl_c_of_a_campaign_stops_it_quietly_with_130(tmp_path):
    for name in ("bench.toml", "short_turn.nc", "bad_code.nc"):
        shutil.copy(DATA / name, tmp_path / name)
    # the stalled cases (feed override 0) run to max_time: the campaign is still busy at the interrupt
    (tmp_path / "c.toml").write_text(
        '[campaign]\nprograms = ["short_turn.nc", "bad_code.nc"]\nbenches = ["bench.toml"]\n'
        'faults = ["stall"]\nmax_time = 60\noverrides = [50, 60, 70, 80, 90, 100]\n'
        '[faults]\nstall = ["t=0.2:set FEED_OVERRIDE=0"]\n')
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "campaign", "c.toml", "--out", str(out), "--workers", "2"],
                         cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)  # its own group: the SIGINT below is a terminal's Ctrl-C
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None and len(_workers(p.pid)) < 2:
        time.sleep(0.1)
    time.sleep(1.0)  # the workers take their first cases
    assert p.poll() is None, p.communicate()
    workers = _workers(p.pid)
    ignoring = [_ignores_sigint(w) for w in workers]  # Ctrl-C is the campaign's to handle, not theirs
    os.killpg(p.pid, signal.SIGINT)
    stdout, stderr = p.communicate(timeout=120)
    assert len(workers) == 2 and all(ignoring), (workers, ignoring)
    assert p.returncode == 130, stdout + stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr, stderr
    assert "hil campaign: interrupted; run the same command again to resume" in stderr
    done = int(stdout.split("cases", 1)[1].split()[0])
    assert 0 <= done < 12 and (out / "results.parquet").is_file()
    assert _group_left(p.pid, 20) == []  # no worker outlives the campaign


def _group(pgid: int) -> list[tuple[str, str]]:
    """(stat, args, pid) of the processes of the group."""
    ps = subprocess.run(["ps", "-ww", "-e", "-o", "pgid=,pid=,stat=,args="], capture_output=True, text=True).stdout
    rows = [ln.split(None, 3) for ln in ps.splitlines()]
    return [(r[2], r[3] if len(r) > 3 else "", r[1]) for r in rows if r and r[0] == str(pgid)]


def _workers(pgid: int) -> list[str]:
    return [pid for _, args, pid in _group(pgid) if "spawn_main" in args]


def _ignores_sigint(pid: str) -> bool:
    for ln in Path(f"/proc/{pid}/status").read_text().splitlines():
        if ln.startswith("SigIgn:"):
            return bool(int(ln.split()[1], 16) & (1 << (signal.SIGINT - 1)))
    return False


def _group_left(pgid: int, within: float) -> list[str]:
    """The live (not zombie) processes of the group, after waiting up to `within` s for them to end."""
    end = time.monotonic() + within
    while True:
        left = [args for stat, args, _ in _group(pgid) if not stat.startswith("Z")]
        if not left or time.monotonic() > end:
            return left
        time.sleep(0.2)


WINDOW = (
    "import multiprocessing, signal, sys, time\n"
    "from hil.campaign.engine import _sigint_held\n"
    "def report(q):\n"
    "    q.put(signal.getsignal(signal.SIGINT) == signal.SIG_IGN)\n"
    "if __name__ == '__main__':\n"
    "    ctx = multiprocessing.get_context('spawn')  # as Dask's Nanny spawns a worker\n"
    "    q = ctx.Queue()\n"
    "    try:\n"
    "        with _sigint_held():\n"
    "            child = ctx.Process(target=report, args=(q,))\n"
    "            child.start()\n"
    "            print('window', flush=True)\n"
    "            time.sleep(3)\n"
    "            print('child', q.get(timeout=30), flush=True)\n"
    "            child.join()\n"
    "        print('lost', flush=True)\n"
    "    except KeyboardInterrupt:\n"
    "        print('interrupted', signal.getsignal(signal.SIGINT) is signal.default_int_handler, flush=True)\n")


def _window(tmp_path, send) -> list[str]:
    script = tmp_path / "window.py"
    script.write_text(WINDOW)
    p = subprocess.Popen([sys.executable, str(script)], env=dict(os.environ, PYTHONPATH=str(ROOT)),
                         stdout=subprocess.PIPE, text=True, start_new_session=True)
    assert p.stdout.readline().strip() == "window"
    time.sleep(0.5)
    send(p.pid)
    return p.communicate(timeout=60)[0].split()


def test_a_ctrl_c_while_the_local_cluster_starts_is_held_not_lost(tmp_path):
    """Decision B77: a Ctrl-C while the local cluster's workers are spawned (seconds on a loaded machine) was lost,
    and the campaign ran to its end. Now it ends the campaign once the window closes, and a worker spawned in the
    window (multiprocessing's spawn, as Dask's) ignores it (B55, B126)."""
    out = _window(tmp_path, lambda pid: os.killpg(pid, signal.SIGINT))  # the terminal's Ctrl-C, mid-start
    assert out == ["child", "True", "interrupted", "True"], out  # the child ignores it; this process was told


def test_a_kill_int_of_the_campaign_alone_while_the_local_cluster_starts_is_held_not_lost(tmp_path):
    """Decision B126 (B77's and B117's "Left"): `kill -INT` of the campaign's pid alone in that window was discarded
    (it ignored SIGINT there so that its workers would inherit SIG_IGN). It now ends the campaign as a Ctrl-C does;
    the worker still comes up ignoring SIGINT, and the handler the campaign had is back."""
    out = _window(tmp_path, lambda pid: os.kill(pid, signal.SIGINT))
    assert out == ["child", "True", "interrupted", "True"], out
