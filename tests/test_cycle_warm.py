"""The warm-up before a real-time stepped cycle's tick (decision B43) only reads: a lathe demo run that calls it
before and after every cycle gives the same trace, the same MLC memory and the same end as one that never does."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq

import hil.runner as runner_mod
from hil import api
from hil.cycle_lean import warm
from hil.stretch import ENV
from tests.conftest import ROOT

DEMO = str(ROOT / "examples" / "lathe_demo.nc")


def _run(tmp_path, name: str) -> tuple[dict, api.Result]:
    res = api.run(DEMO, trace=tmp_path / f"{name}.parquet", check=False)
    return pq.read_table(tmp_path / f"{name}.parquet").to_pydict(), res


def test_warm_writes_nothing_a_run_reads(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV, "0")  # every cycle through BenchRunner._cycle, none in a stretch
    plain, res0 = _run(tmp_path, "plain")
    calls = []
    cycle = runner_mod.BenchRunner._cycle

    def warmed(self, tx, step=None):
        warm(self, len(self.axes))  # in the slack before the tick (the previous cycle's state)
        cycle(self, tx, step)
        warm(self, len(self.axes))  # and right after the cycle, before its trace row is kept
        calls.append(self.cycle)

    monkeypatch.setattr(runner_mod.BenchRunner, "_cycle", warmed)
    warm_trace, res1 = _run(tmp_path, "warm")
    assert len(calls) == res0.run.cycles > 10_000
    assert warm_trace.keys() == plain.keys()
    for col in plain:
        assert warm_trace[col] == plain[col], col
    m0, m1 = res0.runner.mlc.link.mem, res1.runner.mlc.link.mem
    assert m0.m == m1.m and m0.a == m1.a and np.array_equal(m0.d, m1.d)
    assert res1.run.cycles == res0.run.cycles and res1.run.alarms == res0.run.alarms
    assert np.array_equal(res1.runner.actual, res0.runner.actual)
