"""`Planner._run_target`'s run (distance, end speed, acceleration, jerk, top speed) as a C function (nc.motion.planner
`_target_run`, decision bench B204): it brings the queue's end speeds up to date first (the look-ahead pass its
`self.lookahead()` call made), a look-ahead `limit` ends the run after that many junctions, and a limit beyond a C
integer (absurd limits, test_harden_budgets) is no limit. On benches/mill-3axis.toml's planner, five collinear lines."""

from __future__ import annotations

from pathlib import Path

from hil.bench_file import load_bench_file
from nc.motion.planner import Planner
from nc.moves import Move

BENCH = Path(__file__).resolve().parents[1] / "benches" / "mill-3axis.toml"
LENGTHS = (2.0, 2.37, 2.74, 3.11, 3.48)


def _planner() -> Planner:
    pl = Planner(load_bench_file(BENCH).motion_config())
    x = 0.0
    for k, n in enumerate(LENGTHS):
        pl.push(Move("line", k + 1, f"N{k + 1}", {"X": x, "Y": 0.0, "Z": 0.0}, {"X": x + n, "Y": 0.0, "Z": 0.0},
                     {"X": x + n, "Y": 0.0, "Z": 0.0}, feed=3000.0))
        x += n
    pl.closed = True
    return pl


def test_a_run_brings_the_queues_end_speeds_up_to_date_as_the_look_ahead_pass_does():
    asked, passed = _planner(), _planner()
    passed.lookahead()
    assert asked._pushed > 0  # pushes since the last pass: the run owes one
    run = asked._run_target(asked.blocks[0].cap)
    assert asked._pushed == 0 and asked._need == 0
    assert [b.vend for b in asked.blocks] == [b.vend for b in passed.blocks]
    assert run == passed._run_target(passed.blocks[0].cap)
    dist, v1, _, _, vmax = run
    assert dist == sum(b.length for b in asked.blocks)  # one run to the queue's end (every junction at the cap)
    assert abs(dist - sum(LENGTHS)) < 1e-9
    assert v1 == 0.0 and vmax == asked.blocks[0].cap == 50.0  # 3000 mm/min: stops at the queue's end


def test_a_look_ahead_limit_ends_the_run_and_one_beyond_a_c_integer_is_none():
    pl = _planner()
    cap = pl.blocks[0].cap
    whole = pl._run_target(cap)
    assert pl._run_target(cap, limit=1)[0] == pl.blocks[0].length + pl.blocks[1].length
    assert pl._run_target(cap, limit=3)[0] == sum(b.length for b in list(pl.blocks)[:4])
    assert pl._run_target(cap, limit=2 ** 70) == whole
    assert pl._run_target(cap, limit=10 ** 30, extend=True) == pl._run_target(cap, extend=True)
