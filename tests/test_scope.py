"""hil run --scope: a page on 127.0.0.1 streams the run's trace columns while a lock-step run goes.
In headless chromium the page loads with no console errors and the plotted point count grows during
the run; after the browser has the last rows the command ends by itself with the run's exit code."""

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hil.scope import ScopeTap, choose_columns, default_columns
from hil.trace import trace_columns
from tests.browser_helpers import chromium_driver, console_errors

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benches" / "lathe-2axis.toml"
# about 5 s of simulated time: long enough to watch it stream in lock-step
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nG04 X4.\nG01 Z2.\nM30\n"
# ≈ 42 s simulated: long enough in wall time for the page to sample a lock-step run twice while it goes,
# however fast the cycle runs (a 6 s program ended within a second on a quiet machine)
LONG_PROGRAM = PROGRAM.replace("G04 X4.", "G04 X40.")
POINTS = ("return (document.getElementById('scope').data || [])"
          ".reduce((n, d) => n + d.x.length, 0);")


def test_default_and_chosen_columns():
    cols = trace_columns(["X", "Z"], ["S1"])
    assert default_columns(cols) == ["X_cmd", "X_act", "X_ferr", "Z_cmd", "Z_act", "Z_ferr",
                                     "S1_rpm_cmd", "S1_rpm_act"]
    assert choose_columns("Z_ferr, S1_rpm_act", cols) == ["Z_ferr", "S1_rpm_act"]
    with pytest.raises(ValueError, match="unknown column.*Y_cmd"):
        choose_columns("Y_cmd", cols)


def test_tap_hands_newest_rows_to_the_reader_and_passes_every_row_on():
    class Inner:
        rows: list = []

        def write(self, row):
            self.rows.append(row)

    inner = Inner()
    tap = ScopeTap(inner, ["t", "line"])
    for i in range(5):
        tap.write([i * 0.001, 1])
    assert len(inner.rows) == 5
    assert [seq for seq, _ in tap.newer_than(3)] == [4, 5] and tap.newer_than(5) == []


def test_unknown_scope_column_is_bad_usage(tmp_path):
    (tmp_path / "p.nc").write_text(PROGRAM)
    p = subprocess.run([sys.executable, "-m", "hil.cli", "run", str(tmp_path / "p.nc"), "--scope",
                        "--scope-columns", "Q_cmd"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "unknown column(s) Q_cmd" in p.stderr and "X_ferr" in p.stderr


@pytest.mark.parametrize("args, code, message", [
    (["missing.nc"], 1, "ALARM 0x0002"),
    (["p.nc", "--at", "t=1:frobnicate"], 2, "expected set DEVICE=VALUE"),
    (["p.nc", "--scope-columns", "Q_cmd"], 2, "unknown column(s) Q_cmd"),
    (["p.nc", "--bench", "missing.toml"], 2, "missing.toml"),
], ids=["no-program", "bad-event", "bad-column", "no-bench"])
def test_scope_wait_refuses_bad_input_before_waiting_for_a_browser(tmp_path, args, code, message):
    """--scope-wait held a run with a missing program or a bad option until a browser opened the page, and only then
    said the input was bad: the inputs are checked first, the wait comes right before the drives are enabled."""
    (tmp_path / "p.nc").write_text(PROGRAM)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}  # (run from tmp_path: this tree's hil, not an installed one)
    p = subprocess.run([sys.executable, "-m", "hil.cli", "run", *args, "--scope", "--scope-wait"], cwd=tmp_path,
                       env=env, capture_output=True, text=True, timeout=60)
    assert p.returncode == code and message in p.stdout + p.stderr, p.stdout + p.stderr
    assert "waiting for a browser" not in p.stderr and "Traceback" not in p.stderr


def test_sigterm_while_scope_waits_ends_the_command_with_143_and_no_trace(tmp_path):
    """The wait for a browser is part of the run now (its inputs checked, its trace open): a SIGTERM there ends the
    command as before the run, `stopped by SIGTERM` and 143, and leaves no trace (nor its .part)."""
    (tmp_path / "p.nc").write_text(PROGRAM)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", "p.nc", "--scope", "--scope-wait", "--trace", "t.csv"],
                         cwd=tmp_path, env=env, stderr=subprocess.PIPE, text=True)
    try:
        for line in p.stderr:
            if "waiting for a browser" in line:
                break
        p.terminate()
        err = p.stderr.read()
        assert p.wait(timeout=30) == 143 and "hil run: stopped by SIGTERM" in err and "Traceback" not in err, err
    finally:
        if p.poll() is None:
            p.kill()
    assert not list(tmp_path.glob("t.csv*"))


def test_scope_streams_while_lock_step_run_goes(tmp_path):
    driver = chromium_driver()
    (tmp_path / "p.nc").write_text(LONG_PROGRAM)
    proc = subprocess.Popen([sys.executable, "-m", "hil.cli", "run", str(tmp_path / "p.nc"), "--bench", str(BENCH),
                             "--scope", "--scope-wait", "--scope-linger", "20"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            # every cycle stepped: in stretches (hil/stretch.py) the 42 s run ends in about a second,
                            # before the page has polled twice
                            text=True, env={**os.environ, "PYTHONPATH": str(ROOT), "DELTAHIL_STRETCH": "0"})
    try:
        first = proc.stderr.readline()
        m = re.match(r"scope: (http://127\.0\.0\.1:\d+/) \(127\.0\.0\.1 only\)", first)
        assert m, first
        driver.get(m.group(1))
        counts, running = [], []
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(counts) < 4:
            n = driver.execute_script(POINTS)
            status = driver.execute_script("return document.getElementById('status').textContent")
            if n:
                counts.append(n)
                running.append(not status.startswith("run ended"))
            time.sleep(0.5)
        assert all(running[:2]), "the run ended before the page had streamed twice"
        assert counts[1] > counts[0], counts  # points grow while the run goes
        assert console_errors(driver) == []
        assert driver.execute_script("return document.getElementById('scope').data.length") == 8
        if os.environ.get("HIL_GUIDE_SHOTS"):  # HIL_GUIDE_SHOTS=1 refreshes the guide's screenshot
            driver.save_screenshot(str(ROOT / "docs" / "guide" / "img" / "scope.png"))
        out, err = proc.communicate(timeout=120)  # ends once the browser has the last rows
        assert proc.returncode == 0, err
        assert "result         completed" in out
        final = driver.execute_script(POINTS)
        assert final >= counts[-1]
        # the run ends once the server has sent the last rows; the page shows them when its script has taken
        # that answer, a moment later on a loaded machine (CI under load: still "running" at the first look)
        deadline, status = time.monotonic() + 10, ""
        while time.monotonic() < deadline and "run ended" not in status:
            status = driver.execute_script("return document.getElementById('status').textContent")
            time.sleep(0.1)
        assert "run ended" in status, status
    finally:
        driver.quit()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
