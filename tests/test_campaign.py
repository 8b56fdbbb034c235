"""`hil campaign`: a matrix of lock-step runs on Dask (issue 21).

The test campaign (tests/data/campaign/campaign.toml) is 2 programs × 3 feed overrides × 2 fault
variants on one lathe bench, plus a listed case whose program calls a subprogram beside it: 13
cases, among them a program alarm (unknown G code on line 4) and an injected E-stop.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

pytest.importorskip("distributed")

DATA = Path(__file__).parent / "data" / "campaign"
ROOT = Path(__file__).resolve().parents[1]
NONDETERMINISTIC = ("wall_s", "worker", "attempts", "trace")
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)}


def hil(*argv: str, cwd: Path | None = None, timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hil.cli", *argv], capture_output=True, text=True, env=ENV,
                          cwd=cwd, timeout=timeout)


def with_data(folder: Path, name: str | None = None, text: str = "") -> Path:
    """The test campaign's files copied into `folder`, plus a campaign file `name` holding `text`."""
    for f in DATA.iterdir():
        shutil.copy(f, folder)
    if name:
        (folder / name).write_text(text)
    return folder / (name or "campaign.toml")


def run_quiet(campaign: Path, out: Path) -> subprocess.CompletedProcess:
    return hil("campaign", str(campaign), "--out", str(out), "--workers", "0", "--quiet")


def rows(out: Path) -> list[dict]:
    return pq.read_table(out / "results.parquet").drop(list(NONDETERMINISTIC)).to_pylist()


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("serial")
    p = hil("campaign", str(DATA / "campaign.toml"), "--out", str(out), "--workers", "0", "--quiet")
    assert p.returncode == 1, p.stdout + p.stderr  # alarms in the matrix: the campaign is not all green
    return out


def by_case(rs: list[dict]) -> dict[tuple, dict]:
    return {(r["program"], r["override"], r["fault"]): r for r in rs}


def test_serial_results_are_one_row_per_case_with_what_each_run_did(serial):
    rs = rows(serial)
    assert len(rs) == 13
    cases = by_case(rs)
    for ov in (50.0, 100.0, 150.0):
        ok = cases[("short_turn.nc", ov, "none")]
        assert ok["status"] == "completed" and ok["alarm"] is None
        assert ok["max_ferr_X"] < 0.2 and 0 < ok["peak_v_share_X"] <= 1.0 and ok["peak_j_share_Z"] <= 1.0
        bad = cases[("bad_code.nc", ov, "none")]
        assert (bad["status"], bad["alarm"], bad["alarm_line"]) == ("alarm", "0x021D", 4)
        stop = cases[("short_turn.nc", ov, "estop")]
        assert (stop["status"], stop["alarm"]) == ("alarm", "0x0401")  # E-stop relay M2x013, App. A
        assert stop["program_time_s"] < cases[("short_turn.nc", ov, "none")]["program_time_s"]
    # feed override stretches the feed moves: 50 % is slower than 100 %, which is slower than 150 %
    t = [cases[("short_turn.nc", ov, "none")]["program_time_s"] for ov in (50.0, 100.0, 150.0)]
    assert t[0] > t[1] > t[2]
    sub = cases[("with_sub.nc", 100.0, "none")]
    assert sub["status"] == "completed" and sub["program_time_s"] > 0.3  # O0104 was found and run
    assert {r["deltahil_version"] for r in rs} and all(len(r["input_hash"]) == 20 for r in rs)


def test_local_cluster_gives_the_serial_results_bit_for_bit(serial, tmp_path):
    p = hil("campaign", str(DATA / "campaign.toml"), "--out", str(tmp_path), "--workers", "2")
    assert p.returncode == 1, p.stderr
    assert rows(tmp_path) == rows(serial)
    assert "cases 13/13" in p.stderr and "completed 4" in p.stdout


def test_resume_skips_finished_cases_and_rerun_runs_them_again(serial, tmp_path):
    out = tmp_path / "c"
    shutil.copytree(serial, out)
    t_before = pq.read_table(out / "results.parquet").column("wall_s").to_pylist()
    p = hil("campaign", str(DATA / "campaign.toml"), "--out", str(out), "--workers", "0", "--quiet")
    assert "13 already done, 0 run" in p.stdout
    assert pq.read_table(out / "results.parquet").column("wall_s").to_pylist() == t_before
    p = hil("campaign", str(DATA / "campaign.toml"), "--out", str(out), "--workers", "0", "--quiet", "--rerun")
    assert "0 already done, 13 run" in p.stdout
    assert rows(out) == rows(serial)


def test_diff_flags_a_changed_bench_limit(serial, tmp_path):
    data = tmp_path / "data"
    shutil.copytree(DATA, data)
    bench = data / "bench.toml"
    # a slower Z axis: the same cases take longer
    bench.write_text(bench.read_text().replace("velocity = 400.0, acceleration = 4000.0",
                                               "velocity = 40.0, acceleration = 400.0"))
    p = hil("campaign", str(data / "campaign.toml"), "--out", str(tmp_path / "new"), "--workers", "0", "--quiet")
    assert p.returncode == 1
    d = hil("campaign", "diff", str(serial), str(tmp_path / "new"), "--html", str(tmp_path / "diff.html"))
    assert d.returncode == 1, d.stdout + d.stderr
    assert "REGRESSION  short_turn.nc on bench.toml: program time (s)" in d.stdout
    assert "regressions" in d.stdout and "compared       13 cases" in d.stdout
    assert "border:3px solid" in (tmp_path / "diff.html").read_text()
    same = hil("campaign", "diff", str(serial), str(serial))
    assert same.returncode == 0 and "regressions    0" in same.stdout


@pytest.mark.parametrize("text, field", [
    ("[campaign]\nprograms = ['nope*.nc']\nbenches = ['bench.toml']\n", "campaign.programs[0]"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\noverrides = [100, 'fast']\n",
     "campaign.overrides[1]"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\nbuses = ['ethercat:eth0']\n",
     "campaign.buses[0]"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\nfeeds = [1]\n", "campaign.feeds"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n[faults]\nx = ['t=0.1:explode']\n",
     "benches (bench.toml)"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n[checks]\nmax_following_error = {Q = 1}\n",
     "checks.max_following_error.Q"),
    ("[[case]]\nprogram = 'short_turn.nc'\n", "case[0].bench"),
    ("[campaign\n", "not valid TOML"),
    # an MLC no case could load: the file's error (as `hil run --mlc` refuses it), not an alarm 0x0000 per case (campaigns.md: exit 2)
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\nmlc = 'nosuchmodule'\n",
     "campaign.mlc: MLC module nosuchmodule failed to load: ModuleNotFoundError"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\nmlc = 'gone.py'\n",
     "campaign.mlc: MLC module "),
    # a parameter the bench file itself refuses (B89): the name, or a value out of its range
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n[params]\n'N9.999' = [1, 2]\n",
     "params.'N9.999': unknown parameter (did you mean N1.299?)"),
    ("[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n[params]\n'N1.053' = [0.01, 99999]\n",
     "params.'N1.053': must be within [0, 10] (mm), got 99999"),
    ("[[case]]\nprogram = 'short_turn.nc'\nbench = 'bench.toml'\nparams = {'N9.999' = 1}\n",
     "case[0].params.N9.999: unknown parameter"),
])
def test_a_bad_campaign_file_names_the_field(tmp_path, text, field):
    p = run_quiet(with_data(tmp_path, "bad.toml", text), tmp_path / "o")
    assert p.returncode == 2, p.stdout + p.stderr
    assert field in p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "o" / "results.parquet").exists()


# ---- a cluster of separate processes on loopback -------------------------------------------------------
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask(*argv: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_" + argv[0], *argv[1:]], env=ENV,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


@pytest.fixture
def cluster():
    """A scheduler and three single-threaded workers (no nanny, so a killed worker stays dead)."""
    from distributed import Client

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")]
    workers = {}
    try:
        time.sleep(1.0)
        for name in ("wa", "wb", "wc"):
            workers[name] = _dask("worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                  "--name", name, "--host", "127.0.0.1")
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(3, timeout=60)
            yield address, client, workers | {"scheduler": procs[0]}
    finally:
        for p in [*workers.values(), *procs]:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
            p.wait()


def campaign_on(address: str, campaign: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "hil.cli", "campaign", str(campaign), "--out", str(out),
                             "--scheduler", address, "--quiet"], env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _kill_while_busy(client, workers: dict, name: str, deadline: float = 60.0) -> bool:
    """SIGKILL worker `name` as soon as it is running a case."""
    end = time.monotonic() + deadline
    while time.monotonic() < end:
        info = client.scheduler_info()["workers"]  # one snapshot: workers come and go under load
        busy = {info[w]["name"]: tasks for w, tasks in client.processing().items() if w in info}
        if busy.get(name):
            os.kill(workers[name].pid, signal.SIGKILL)
            return True
        time.sleep(0.02)
    return False


def test_scheduler_and_workers_as_processes_run_the_campaign_and_survive_a_killed_worker(serial, cluster,
                                                                                       tmp_path):
    address, client, workers = cluster
    run = campaign_on(address, DATA / "campaign.toml", tmp_path / "r")
    assert _kill_while_busy(client, workers, "wa")
    out, err = run.communicate(timeout=240)
    assert run.returncode == 1, out + err
    assert rows(tmp_path / "r") == rows(serial)  # every case completed, the killed one elsewhere
    assert "worker_lost" not in out
    # the case the killed worker ran (and one queued behind it, B101) ran twice, and its row says so
    attempts = sorted(r["attempts"] for r in pq.read_table(tmp_path / "r" / "results.parquet").to_pylist())
    assert attempts[:-2] == [1] * 11 and 2 in attempts[-2:] and max(attempts) == 2, attempts
    # the team's scheduler keeps its own allowed failures once the campaign is done
    assert client.run_on_scheduler(lambda dask_scheduler: dask_scheduler.allowed_failures) == 3


def test_a_case_that_keeps_losing_its_worker_is_marked_worker_lost(cluster, tmp_path):
    address, client, workers = cluster
    with_data(tmp_path, "campaign.toml",
              (DATA / "campaign.toml").read_text().replace('name = "test"', 'name = "test"\nretries = 1'))
    run = campaign_on(address, tmp_path / "campaign.toml", tmp_path / "r")
    assert _kill_while_busy(client, workers, "wb")
    out, err = run.communicate(timeout=240)
    assert run.returncode == 1
    rs = pq.read_table(tmp_path / "r" / "results.parquet").to_pylist()
    assert len(rs) == 13
    lost = [r for r in rs if r["status"] == "worker_lost"]
    # Dask counts a lost worker against every case it held: the one running and, with the
    # scheduler's default worker saturation (1.1 tasks a thread), possibly one queued behind it.
    assert 1 <= len(lost) <= 2 and all("KilledWorker" in r["message"] for r in lost)
    assert sum(r["status"] in ("completed", "alarm") for r in rs) == 13 - len(lost)
    assert "worker_lost" in out


def test_kept_traces_form_a_partitioned_dataset_and_canopen_runs_like_sim(tmp_path):
    campaign = with_data(tmp_path, "traced.toml", "[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n"
                         "buses = ['sim', 'canopen:virtual']\ntrace = true\n")
    p = run_quiet(campaign, tmp_path / "o")
    assert p.returncode == 0, p.stdout + p.stderr
    rs = {r["bus"]: r for r in pq.read_table(tmp_path / "o" / "results.parquet").to_pylist()}
    assert set(rs) == {"sim", "canopen:virtual"} and all(r["status"] == "completed" for r in rs.values())
    # the same program on the two buses takes the same simulated time, to the cycle
    assert rs["sim"]["program_time_s"] == pytest.approx(rs["canopen:virtual"]["program_time_s"], abs=0.005)
    dataset = pq.read_table(tmp_path / "o" / "traces")  # Hive partitions become columns
    assert {"program", "bench", "case"} <= set(dataset.column_names)
    assert set(dataset.column("case").to_pylist()) == {r["input_hash"] for r in rs.values()}
    assert set(dataset.column("program").to_pylist()) == {"short_turn.nc"}
    for r in rs.values():
        assert (tmp_path / "o" / r["trace"]).exists()
        assert (tmp_path / "o" / "reports" / r["input_hash"] / "index.html").exists()
    summary = (tmp_path / "o" / "summary.html").read_text()
    assert "reports/" in summary and "canopen:virtual" in summary


def test_a_run_past_max_time_is_a_timeout_and_params_sweep_is_a_variant(tmp_path):
    campaign = with_data(tmp_path, "t.toml", "[campaign]\nprograms = ['short_turn.nc']\nbenches = ['bench.toml']\n"
                         "max_time = 0.4\n[params]\n'N1.040' = [0.01, 0.02]\n")
    p = run_quiet(campaign, tmp_path / "o")
    assert p.returncode == 1
    rs = pq.read_table(tmp_path / "o" / "results.parquet").to_pylist()
    assert sorted(r["params"] for r in rs) == ["N1.040=0.01", "N1.040=0.02"]
    # alarm 0xDE03 at max_time, then the channel stops along the path before the run ends
    assert {r["status"] for r in rs} == {"timeout"} and all(0.4 <= r["program_time_s"] <= 0.6 for r in rs)
    assert all(r["program_time_s"] < r["sim_time_s"] < 0.9 for r in rs)


def test_a_scheduler_that_goes_away_ends_the_campaign_resumably(serial, cluster, tmp_path):
    """Decision B76: the scheduler killed mid-campaign: what finished is written, no case that never ran is a
    row (they were `worker_lost` failures), no distributed traceback, exit 3; the same command resumes."""
    address, client, workers = cluster
    run = campaign_on(address, DATA / "campaign.toml", tmp_path / "r")
    end = time.monotonic() + 60
    while not client.processing() or not any(client.processing().values()):
        assert time.monotonic() < end and run.poll() is None
        time.sleep(0.02)
    os.killpg(workers["scheduler"].pid, signal.SIGKILL)
    out, err = run.communicate(timeout=120)
    assert run.returncode == 3, out + err
    assert f"hil campaign: lost the connection to the scheduler {address} after " in err
    assert "run the same command again (with a scheduler) to resume" in err
    assert "Traceback" not in err and "worker_lost" not in out
    done = pq.read_table(tmp_path / "r" / "results.parquet").to_pylist()
    assert all(r["status"] != "worker_lost" for r in done) and len(done) < 13
    # resumed on a cluster of its own: the rest runs, and the matrix is the serial one
    p = hil("campaign", str(DATA / "campaign.toml"), "--out", str(tmp_path / "r"), "--workers", "0", "--quiet")
    assert p.returncode == 1, p.stdout + p.stderr
    assert f"({len(done)} already done, {13 - len(done)} run)" in p.stdout
    assert rows(tmp_path / "r") == rows(serial)
