"""The filter stop's walks over the look-ahead queue, compiled in nc.motion.planner_cruise (bench B168), give what the
Python they replaced in nc.motion.filter_ramps gave, to the bit: the path left to the end of the queue (None where a
block is not plain or a junction stops), the least cap and junction speed, the least acceleration and jerk. On the
queue of benches/mill-3axis.toml's planner after a few lines, a feed-per-revolution move, a G31 move and an exact stop."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from hil.bench_file import load_bench_file
from nc.motion.planner import Planner
from nc.motion.planner_cruise import least_limits, plain_rest, tail_speed
from nc.moves import Move

BENCH = Path(__file__).resolve().parents[1] / "benches" / "mill-3axis.toml"


def _line(line: int, x0: float, x1: float, y: float, **kw) -> Move:
    return Move("line", line, f"N{line}", {"X": x0, "Y": 0.0, "Z": 0.0}, {"X": x1, "Y": y, "Z": 0.0},
                {"X": x1, "Y": y, "Z": 0.0}, feed=kw.pop("feed", 3000.0), **kw)


def _planner(*extra: Move) -> Planner:
    pl = Planner(load_bench_file(BENCH).motion_config())
    x = 0.0
    for k, y in enumerate((0.0, 0.4, 0.1, 0.9, 0.3)):
        pl.push(_line(k + 1, x, x + 2.0 + 0.37 * k, y))
        x += 2.0 + 0.37 * k
    for mv in extra:
        pl.push(mv)
    pl.closed = True  # nothing more comes: the runs held back are released
    pl.lookahead()
    return pl


def _plain(pl: Planner, b) -> bool:  # FilterStops._plain as it was
    mv = b.move
    return b.kind == "path" and not mv.per_rev and mv.css is None and "G31" not in mv.tags \
        and not (pl.lim.rapid_whole if b.rapid else pl.lim.cut_on)


def _rest_before(pl: Planner, s: float) -> float | None:  # FilterStops._stop_rest's walk as it was
    blocks, rest = pl.blocks, -s
    for k, b in enumerate(blocks):
        if not _plain(pl, b) or (k + 1 < len(blocks) and b.vjunc <= 1e-9):
            return None
        rest += b.length
    return rest


def _tail_before(pl: Planner, cap: float) -> float:  # FilterStops._tail_speed as it was
    vmax = cap
    for k, b in enumerate(pl.blocks):
        vmax = min(vmax, b.cap)
        if k + 1 < len(pl.blocks):
            vmax = min(vmax, b.vjunc)
    return vmax


def _same(x: float | None, y: float | None) -> bool:
    return x == y and (x is None or math.copysign(1.0, x) == math.copysign(1.0, y))


def test_the_walks_give_the_python_answers_on_a_plain_queue():
    pl = _planner()
    blocks = list(pl.blocks)
    assert len(blocks) >= 5
    for s in (0.0, 0.3, blocks[0].length, 1e-13):
        got = plain_rest(pl.blocks, s, pl.lim.rapid_whole, pl.lim.cut_on)
        assert got is not None and _same(got, _rest_before(pl, s)), (s, got)
    assert math.isclose(plain_rest(pl.blocks, 0.0, pl.lim.rapid_whole, pl.lim.cut_on),
                        sum(b.length for b in blocks), rel_tol=1e-12)
    for cap in (1e9, 50.0, min(b.cap for b in blocks), 0.0):
        assert _same(tail_speed(pl.blocks, cap), _tail_before(pl, cap)), cap
    assert least_limits(pl.blocks) == (min(b.a for b in blocks), min(b.j for b in blocks))
    assert least_limits([blocks[2]]) == (blocks[2].a, blocks[2].j)


@pytest.mark.parametrize("extra", [
    {"per_rev": True, "feed": 0.2},  # feed per revolution: not plain
    {"tags": ("G31",)},  # a skip: not plain
    {"exact_stop": True},  # a stop at its end: its junction is 0 before the last block
])
def test_a_block_that_is_not_plain_or_stops_ends_the_walk(extra):
    pl = _planner(_line(6, 13.7, 15.0, 0.2, **extra), _line(7, 15.0, 16.5, 0.0))
    assert _rest_before(pl, 0.0) is None
    assert plain_rest(pl.blocks, 0.0, pl.lim.rapid_whole, pl.lim.cut_on) is None
    assert _same(tail_speed(pl.blocks, 1e9), _tail_before(pl, 1e9))


def test_cut_on_makes_every_cutting_block_not_plain():
    pl = _planner()
    assert plain_rest(pl.blocks, 0.0, pl.lim.rapid_whole, True) is None  # N1.034/N1.035 set (decision motion 94)


def test_the_least_limits_of_an_empty_queue_raise_as_min_does():
    with pytest.raises(ValueError):
        least_limits([])
    assert plain_rest([], 0.25, False, False) == -0.25 and tail_speed([], 7.0) == 7.0


def test_the_finished_segments_kept_are_the_last_history_of_them_and_a_copy_keeps_its_own():
    """The deviation check's path behind (filter_ramps.seg_history over Planner._seg_hist, bench B168): after 150
    finished blocks the last 64 segments, oldest first, through the chain's compactions; the chain a shallow copy
    of the planner holds (hil.stretch_state) still reads the segments it had."""
    from nc.motion.filter_ramps import HISTORY, seg_history
    pl = Planner(load_bench_file(BENCH).motion_config())
    for k in range(160):
        pl.push(_line(k + 1, 3.0 * k, 3.0 * k + 3.0, 0.5 * (k % 2)))
    pl.closed = True
    done, saved = [], None
    for k in range(150):
        done.append(pl.blocks[0].seg)
        pl._finish_block(True)
        got = seg_history(pl._seg_hist)
        assert len(got) == min(k + 1, HISTORY) and all(x is y for x, y in zip(got, done[-HISTORY:])), k
        if k == 70:
            saved = pl._seg_hist
    assert all(x is y for x, y in zip(seg_history(saved), done[71 - HISTORY:71]))
    assert len(seg_history(saved)) == HISTORY
