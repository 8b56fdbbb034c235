"""Drives are disabled only at standstill, judged on position feedback (decision B15).

Delta drives report velocity (0x606C) in 0.1 rpm of the motor: it reads 0 below 1 rpm, i.e.
16.7 mm/s on a 10 mm lead at 1,280,000 counts/rev. The stop path used it as its standstill test,
so once the units were right it disabled axes that were still moving and left them a count off
their end point. The runner now waits until the position feedback has stood still and no
following error is left."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hil import api
from hil.runner import REST_CYCLES
from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
PROGRAM = "G90 G54 G17 G21 G94\nG01 X37.123 Y12.5 F3000\nG00 Z80.\nM30\n"


def test_drives_disable_only_once_the_position_feedback_stands(tmp_path):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    r = api.run(prog, ROOT / "benches" / "mill-3axis.toml", trace=tmp_path / "t.parquet", check=False)
    assert r.completed
    c = TraceFile(tmp_path / "t.parquet").arrays()
    for axis, end in (("X", 37.123), ("Y", 12.5), ("Z", 80.0)):
        enabled = (c[f"{axis}_sw"].astype(int) & 0x6F) == 0x27
        off = int(np.flatnonzero(enabled)[-1]) + 1  # the first row after Operation Enabled
        before = c[f"{axis}_act"][off - REST_CYCLES:off]
        assert np.all(before == before[-1]), (axis, before)  # no motion in the last cycles before disable
        assert np.all(c[f"{axis}_ferr"][off - REST_CYCLES:off] == 0.0), axis
        counts = {"X": 10.0, "Y": 10.0, "Z": 10.0}[axis] / 1_280_000
        assert abs(c[f"{axis}_act"][off - 1] - end) <= counts / 2 + 1e-12, (axis, c[f"{axis}_act"][off - 1])
