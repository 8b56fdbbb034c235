"""Stretches across a cruise's blocks (issue 17, decisions B25 and motion 44): a CAM program of 0.01-0.1 mm G01
blocks at F3000 on benches/mill-3axis.toml (basic MLC: nothing reads the look-ahead queue) runs about one block
a cycle, so its stretches must span blocks; they end where the channel reads the program again. The trace
equals cycle-by-cycle stepping's, column by column (as tests/test_stretch_runner.py compares)."""

from __future__ import annotations

import pytest

from benchmarks.bench_motion import cam_program
from benchmarks.trace_ab import compare, one
from hil.stretch import ENV
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")


@pytest.mark.parametrize("blocks, extra", [(2500, {}), (1200, {"feed_override": 80.0})])
def test_cam_program_stretched_across_blocks_equals_stepped(monkeypatch, tmp_path, blocks, extra):
    prog = tmp_path / "cam.nc"
    prog.write_text(cam_program(blocks))
    kw = {"bench": MILL, "trace_signals": None} | extra  # no device columns: the bench's basic MLC
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), kw, tmp_path / f"{on}.parquet", kept))
    assert compare(out[0], out[1]) == []
    stepped, stretched = kept
    assert stepped.run.stretched == 0 and stretched.run.ok
    # blocks last a cycle or two: only stretches that cross blocks reach this share
    assert stretched.run.stretched > 0.4 * stretched.run.cycles, (stretched.run.stretched, stretched.run.cycles)
