"""A stretch pass that reads nothing (a program's tail: its end was read) marks before a refill every few parts
(hil.stretch_pass.REMARK, issue 17, decision bench B199): the step it refuses at its end replays at most that many
parts from the last mark, not every refill since the pass's start, and the run's trace is stepping's, column by
column (as tests/test_stretch_cam.py compares)."""

from __future__ import annotations

import hil.stretch_pass as sp
from benchmarks.bench_motion import cam_program
from benchmarks.trace_ab import compare, one
from hil.stretch import ENV
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")


def test_the_tail_pass_replays_few_parts_and_its_trace_is_steppings(monkeypatch, tmp_path):
    replays = []  # (reads, parts taken since the mark) of each refused step that had to be undone
    real = sp.Pass._rewind

    def rewind(self):
        replays.append((self.reads, len(self.parts) - self._mark[2]))
        real(self)

    monkeypatch.setattr(sp.Pass, "_rewind", rewind)
    prog = tmp_path / "cam.nc"
    prog.write_text(cam_program(600))
    kw = {"bench": MILL, "trace_signals": None}
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), kw, tmp_path / f"{on}.parquet", kept))
    assert compare(out[0], out[1]) == []
    assert kept[1].run.ok and kept[1].run.stretched > 0.4 * kept[1].run.cycles
    tail = [n for reads, n in replays if not reads]
    # the last pass takes the program's last blocks (≈ 30 refills) after its end was read: one refused step
    assert tail and max(tail) <= sp.REMARK, replays
