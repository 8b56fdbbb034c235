"""benchmarks/bench_wall.py: the figures a user's `hil run` gives by the clock on the wall (issue 17) are read off
the runs themselves: the simulated time from the run's summary, the process from fork to exit."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_wall_benchmark_reports_the_lathe_demos_process():
    out = subprocess.run([sys.executable, "benchmarks/bench_wall.py", "--repeat", "1", "--only", "lathe", "--json"],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    (row,) = data["rows"]
    assert row["simulated_s"] == 14.396  # the lathe demo's 14,396 cycles of 1 ms, as `hil run` prints them
    assert 0 < data["python_pass_s"] < row["wall_best_s"]  # the process includes the interpreter's start
    # x real time is simulated / wall before either is rounded for the table: one rounding step apart at most
    assert abs(row["x_real_wall"] - 14.396 / row["wall_best_s"]) <= 0.1
    assert 0 < row["imports_s"] < row["wall_best_s"] and row["modules"] > 100
    # rs274 cannot read the lathe demo (Fanuc lathe T-words): skipped with its reason, or absent
    assert row["rs274_wall_s"] is None and row["rs274_note"].startswith("skipped: rs274")
