"""`hil path` keeps its memory flat in program length (issue 16: under 100 MB for 100k and for 1M
blocks). A 300k-block CAM program is read in place, interpreted in batches and written as it goes:
the process's peak stays far below what holding its 300k output lines (≈ 60 MB of text) would cost.
Before the fix, 256 batches of up to 4,096 lines were gathered before each write: 310 MB."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_hil_path_peak_memory_is_flat_on_a_300k_block_cam_program(tmp_path: Path) -> None:
    prog = tmp_path / "cam.nc"
    with prog.open("w") as f:
        f.write("O1000\nG90 G17 G21\n")
        for i in range(300_000):  # every line G1 X Y Z F, as a CAM post writes it
            f.write(f"G1 X{(i % 1000) * 0.137:.3f} Y{(i % 777) * 0.211:.3f} Z{-(i % 53) * 0.01:.3f} F1200\n")
        f.write("M30\n")
    # the child reports its own peak: VmHWM of its own address space (ru_maxrss of a forked child
    # counts the pages of the parent it was forked from: this pytest process, gigabytes late in a suite)
    wrapper = ("import runpy, sys\n"
               "sys.argv = ['hil', 'path', '--json', '--profile', 'nc5-mill', sys.argv[1]]\n"
               "try:\n"
               "    runpy.run_module('hil.cli', run_name='__main__')\n"
               "finally:\n"
               "    hwm = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0].split()[1]\n"
               "    sys.stderr.write('PEAK_KB %s\\n' % hwm)\n")
    done = subprocess.run([sys.executable, "-c", wrapper, str(prog)], cwd=ROOT, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    assert done.returncode == 0, done.stderr
    peak_mb = int(done.stderr.rsplit("PEAK_KB ", 1)[1].split()[0]) / 1024  # KiB on Linux
    assert done.stdout.count("\n") >= 300_000
    assert done.stdout.rstrip().rsplit("\n", 1)[-1].startswith('{"kind": ')
    assert peak_mb < 100, f"hil path peaked at {peak_mb:.0f} MB"
