"""Issue 15 budgets: canned cycles and repeats expand lazily (memory flat for any K, P, Q, R) and
the run can be stopped while they run (decisions B1)."""

from __future__ import annotations

import dataclasses
import itertools
import tracemalloc
from pathlib import Path

import pytest

from hil import api
from nc.interp import Interpreter
from nc.moves import Move
from nc.profiles import make_profile
from nc.program.blocks import parse_program

ROOT = Path(__file__).resolve().parents[1]

HUGE = {
    # milling G81 with K999999999 incremental holes, 1 mm apart
    "g81_k": ("nc5-mill", "G90 G00 X0 Y0 Z10.\nG91 G81 X1. Y0 Z-5. R-2. F500 K999999999\nG80\nM30\n"),
    # milling G83, a 1 µm peck (legal) on a 50 mm hole, repeated K99999999 times
    "g83_k": ("nc5-mill", "G90 G00 X0 Y0 Z10.\nG91 G83 X1. Z-50. R-2. Q1 F500 K99999999\nM30\n"),
    # lathe G74 face grooving, P1 Q1 (1 µm shift and peck) over 20 mm x 205 mm
    "g74_p1q1": ("nc5-lathe-a", "G00 X0 Z5. M03 S1000\nG74 R0.5\nG74 X20. Z-200. P1 Q1 F0.1\nM30\n"),
    "g75_p1q1": ("nc5-lathe-a", "G00 X60. Z5. M03 S1000\nG75 R0.5\nG75 X10. Z-200. P1 Q1 F0.1\nM30\n"),
    # lathe G73 pattern repeat with R99999999 passes
    "g73_r": ("nc5-lathe-a", "G00 X60. Z5. M03 S1000\nG73 U5. W0. R99999999\nG73 P10 Q20 U0.2 W0.1 F0.2\n"
                             "N10 G00 X20.\nG01 Z-20.\nN20 X50.\nM30\n"),
    # lathe G83 with a large K
    "g83_lathe_k": ("nc5-lathe-a", "G00 X0 Z5. M03 S1000\nG83 Z-300. R-1. Q1 F0.1 K999999999\nM30\n"),
}


@pytest.mark.parametrize("case", sorted(HUGE))
def test_huge_repeat_streams_with_flat_memory(case: str) -> None:
    """The first 20,000 moves of a cycle with ~1e8-1e13 of them come out at once, in a few MB."""
    profile, text = HUGE[case]
    interp = Interpreter(make_profile(profile))
    events = interp.run(parse_program(text, f"{case}.nc"))
    tracemalloc.start()
    try:
        moves = [e for e in itertools.islice(events, 20_000) if isinstance(e, Move)]
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(moves) > 10_000
    assert peak < 30e6, f"{case}: {peak / 1e6:.0f} MB for 20,000 events"


def test_first_holes_of_k_cycle_are_where_programmed() -> None:
    """Lazy does not change the path: G91 G81 K holes step 1 mm in X, drill 2+5 mm below Z10."""
    interp = Interpreter(make_profile("nc5-mill"))
    events = interp.run(parse_program(HUGE["g81_k"][1], "k.nc"))
    cuts = [e for e in itertools.islice(events, 400) if isinstance(e, Move) and "cut" in e.tags]
    assert [round(c.end["X"], 6) for c in cuts[:5]] == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert all(abs(c.start["Z"] - 8.0) < 1e-9 and abs(c.end["Z"] - 3.0) < 1e-9 for c in cuts)


def test_finite_k_still_ends_where_the_last_hole_is() -> None:
    """`host.position` moves to the cycle's end once the lazy cycle is done: the next block starts there."""
    text = "G90 G00 X0 Y0 Z10.\nG91 G83 X2. Z-5. R-2. Q2. F500 K3\nG80\nG90 G01 Y5. F100\nM30\n"
    moves = [e for e in Interpreter(make_profile("nc5-mill")).run(parse_program(text, "k3.nc"))
             if isinstance(e, Move)]
    pecks = [m for m in moves if "peck" in m.tags]
    assert len(pecks) == 3 * 3  # R8 to the bottom at Z3 by Q2: pecks to 6, 4 and 3
    last = moves[-1]
    assert last.start["X"] == pytest.approx(6.0) and last.end["Y"] == pytest.approx(5.0)


def _bench(tmp_path: Path, name: str, max_time: float) -> Path:
    text = (ROOT / "benches" / name).read_text()
    text = text.split("[checks]")[0].replace("cycle_ms", f"max_time = {max_time}\ncycle_ms", 1)
    out = tmp_path / name
    out.write_text(text)
    return out


@pytest.mark.parametrize("case,bench", [("g81_k", "mill-3axis.toml"), ("g74_p1q1", "lathe-2axis.toml")])
def test_huge_cycle_is_stopped_by_max_time(tmp_path: Path, case: str, bench: str) -> None:
    """The run does not first expand the cycle: it moves, and the bench's max_time stops it."""
    prog = tmp_path / f"{case}.nc"
    prog.write_text(HUGE[case][1])
    r = api.run(prog, _bench(tmp_path, bench, 0.5), mlc="basic")
    assert not r.completed
    assert [a.code for a in r.alarms] and "max_time" in r.alarms[0].message
    assert r.run.cycles <= 0.5 / r.bench.cycle + 2000  # stopped, not run to the end


WHILE_100K = "#1=0\n#2=0\nWHILE[#1LT100000]DO1\n#1=#1+1\n#2=#2+2\nEND1\nG01 X[#1/10000] F1000\nM30\n"


def test_100k_while_is_spread_over_cycles_with_right_values(tmp_path: Path) -> None:
    """400,003 statements at 40 per cycle: no cycle runs more than its budget, the loop takes
    10,000 cycles (10 s) of simulated time, and the variables and the move after it are right."""
    prog = tmp_path / "while.nc"
    prog.write_text(WHILE_100K)
    r = api.run(prog, ROOT / "benches" / "mill-3axis.toml", check=False)
    assert r.completed and not r.alarms
    interp = r.runner._interp
    assert interp.vars.get(1) == 100000 and interp.vars.get(2) == 200000
    budget = interp.budget
    assert budget.limit == 40 and budget.peak == 40  # the budget was used, never exceeded
    statements = 2 + 100000 * 4 + 1  # #1=, #2=, (WHILE, #1=, #2=, END) per pass, the last WHILE
    assert budget.held_cycles >= statements // 40 - 1
    assert r.run.program_time >= statements / 40 * r.bench.cycle
    assert r.run.final["X"] == pytest.approx(10.0, abs=1e-6)


def test_statement_budget_is_a_profile_parameter(tmp_path: Path) -> None:
    """[params] "macro statements per cycle" = 400: the same loop takes a tenth of the cycles."""
    text = WHILE_100K.replace("100000", "4000").replace("#1/10000", "#1/400")
    times = []
    for per_cycle in (40, 400):
        bench = tmp_path / f"b{per_cycle}.toml"
        bench.write_text((ROOT / "benches" / "mill-3axis.toml").read_text().split("[checks]")[0]
                         + f'\n[params]\n"macro statements per cycle" = {per_cycle}\n')
        prog = tmp_path / "w.nc"
        prog.write_text(text)
        r = api.run(prog, bench, check=False)
        assert r.completed and r.runner._interp.budget.peak == per_cycle
        assert r.runner._interp.vars.get(2) == 8000
        times.append(r.run.program_time)
    statements = 2 + 4000 * 4 + 1
    assert times[0] - times[1] == pytest.approx(statements * 0.001 * (1 / 40 - 1 / 400), abs=0.01)


def test_preview_log_keeps_the_last_statements_only() -> None:
    """The preview log is bounded ("preview log" = 1000 records), keeping the newest."""
    interp = Interpreter(make_profile("nc5-mill"))
    list(interp.run(parse_program(WHILE_100K.replace("100000", "5000"), "w.nc")))
    log = interp.preview_log
    assert len(log) == 1000
    assert log[-1].block == "WHILE[#1LT5000]DO1"  # the newest: the test that ends the loop
    assert [r.block for r in log].count("END1") == 250  # 4 statements a pass: the last 250 passes
    assert interp.vars.get(1) == 5000


def test_absurd_acceleration_alarms_at_once_instead_of_spinning(tmp_path: Path) -> None:
    """acceleration 1e-50 (a bench file refuses it now; a `Bench` built in Python does not): every
    plan ends before its first sample. The planner stops after a bounded number of solves with
    alarm 0xDE10 naming the limits, long before the bench's max_time (decisions B4)."""
    from hil.bench_file import load_bench_file

    bench = load_bench_file(str(_bench(tmp_path, "mill-3axis.toml", 600.0)))
    for ax in bench.axes:
        if ax.name in ("X", "Y"):
            ax.limits = dataclasses.replace(ax.limits, max_acceleration=1e-50)
    prog = tmp_path / "mv.nc"
    prog.write_text("G90 G01 X10. Y5. F1000\nX20.\nM30\n")
    r = api.run(prog, bench, check=False)
    assert not r.completed
    alarm = r.alarms[0]
    assert alarm.code == 0xDE10 and "no progress" in alarm.message and "acceleration" in alarm.message
    assert alarm.line == 1
    assert r.run.cycles < 100  # not the 600,000 cycles of max_time
    assert r.run.final["X"] == pytest.approx(0.0, abs=1e-6)  # nothing moved
