"""A trace that cannot be written mid-run (issue 17, bench decision B97): a full disk, a failing file system. The run
raises deltahil's 0xDE04 and stops along the path as for any alarm — the axes decelerate within their limits, the
drives are disabled only at standstill — the partial trace is removed (nothing half-written that looks whole), and
`hil run` prints its summary and exits 1. It used to end as an NC internal error whose stop broke off at the next
row written, leaving the CSV's first 200 kB renamed into place."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
LONG = "G98\nG00 X58. Z98.\nG01 Z-300. F6000\n" + "G01 Z98.\nG01 Z-300.\n" * 63 + "M30\n"
OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)


def _run(trace_path: Path):
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.trace import open_trace
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"
    seen: list[tuple[float, float, int]] = []
    runner = BenchRunner(bench, make_link(bench), None,
                         on_cycle=lambda r: seen.append((r.time, r.scales[1].drive_to_velocity(r.tx[1].velocity_actual),
                                                         r.tx[1].statusword)))
    runner.trace = open_trace(trace_path, runner.trace_columns(), {"program": "long.nc"})
    result = runner.run_program(parse_program(LONG, name="long.nc"))
    return result, np.array(seen)


def _assert_stopped_under_control(result, seen: np.ndarray) -> None:
    assert result.alarms and result.alarms[0].code == 0xDE04, result.alarms
    assert "No space left on device" in result.alarms[0].message and "removed" in result.alarms[0].message
    t, v, sw = seen[:, 0], seen[:, 1], seen[:, 2].astype(int)
    assert 1.0 < t[-1] < 200.0 and np.abs(v).max() > 99  # stopped mid-program, from full speed
    assert np.abs(np.diff(v)).max() / 0.001 <= 4000.0 * 1.001  # Z's acceleration limit: a ramp, no step
    enabled = (sw & 0x6F) == OP_ENABLED
    off = int(np.flatnonzero(enabled)[-1]) + 1
    assert off < len(sw) and abs(v[off - 1]) < 0.01 and not enabled[off:].any()


class FillsUp:
    """The CSV trace's file on a disk with `room` bytes left: the write past it fails as a full disk does."""

    def __init__(self, fh, room: int) -> None:
        self.fh, self.room = fh, room

    def write(self, text: str) -> int:
        self.room -= len(text)
        if self.room < 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return self.fh.write(text)


def test_a_csv_trace_on_a_full_disk_stops_the_run_and_leaves_nothing(tmp_path, monkeypatch):
    """1.5 MB of room: the disk is full some 10 s into the program, Z at 100 mm/s."""
    import csv

    import hil.trace as tr

    real_init = tr.CsvTrace.__init__

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        self._w = csv.writer(FillsUp(self._fh, 1_500_000))

    monkeypatch.setattr(tr.CsvTrace, "__init__", init)
    result, seen = _run(tmp_path / "run.csv")
    assert result.alarms[0].code == 0xDE04
    _assert_stopped_under_control(result, seen)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_parquet_trace_whose_part_cannot_be_written_stops_the_run_and_leaves_nothing(tmp_path, monkeypatch):
    """The Parquet writer thread's write of a part fails as on a full disk (pyarrow raises OSError, ENOSPC)."""
    import hil.trace_parquet as tp

    real = tp.write_table

    def full(table, where, **kwargs):
        if not isinstance(where, (str, Path)):  # the warm-up's write into memory
            return real(table, where, **kwargs)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(tp, "write_table", full)
    result, seen = _run(tmp_path / "run.parquet")
    assert result.alarms[0].code == 0xDE04
    _assert_stopped_under_control(result, seen)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a small tmpfs needs root")
@pytest.mark.parametrize("suffix", ["csv", "parquet"])
def test_hil_run_on_a_full_tmpfs_prints_the_alarm_and_the_summary(tmp_path, suffix):
    """`hil run --trace` onto a 256 kB tmpfs, as an engineer's full disk: alarm, summary, exit 1, the tmpfs empty."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    prog = tmp_path / "long.nc"
    prog.write_text(LONG)
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(mnt)], check=True)
    try:
        p = subprocess.run([sys.executable, "-m", "hil.cli", "run", str(prog), "--bench", str(LATHE), "--no-check",
                            "--trace", str(mnt / f"run.{suffix}")], env={**os.environ, "PYTHONPATH": str(ROOT)},
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 1, p.stdout + p.stderr
        assert "ALARM 0xDE04" in p.stdout and "No space left on device" in p.stdout and "result" in p.stdout
        assert "Traceback" not in p.stderr and "internal error" not in p.stdout + p.stderr
        assert sorted(x.name for x in mnt.iterdir()) == []
    finally:
        subprocess.run(["umount", str(mnt)], check=True)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="/dev/full: a device that is always full")
def test_retentive_variables_on_a_full_disk_keep_the_last_good_file_and_leave_no_temporary(tmp_path):
    """`--retain` onto a full disk: 0x140B as before (the next run would lose them), the last good file kept, and
    now no empty `.NAME.tmp` left beside it (B97)."""
    import hil

    retain = tmp_path / "ret.json"
    retain.write_text('{"2000": 1.5}\n')
    (tmp_path / ".ret.json.tmp").symlink_to("/dev/full")  # the write of the new file meets a full disk
    prog = tmp_path / "p.nc"
    prog.write_text("#2000=2.5\nG00 X50.\nM30\n")
    r = hil.run(str(prog), bench=str(LATHE), retain=str(retain))
    assert [a.code for a in r.alarms] == [0x140B] and "No space left on device" in r.alarms[0].message
    assert retain.read_text() == '{"2000": 1.5}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.nc", "ret.json"]
