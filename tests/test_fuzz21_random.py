"""Seeded random programs (tests/fuzz21_gen.py) through `hil run` and `hil path`, as a user's programs would go.

A legal program runs to its end on the shipped bench with every check passing, ends where `hil path` ends, and
gives the same trace twice; a malformed variant of one is refused with a Delta alarm that names its line and
block, never a traceback. The seeds here are a handful of the hundreds run in session 20 (fuzz21), chosen to
cover every kind of fragment; the bugs they found are pinned one by one in tests/test_fuzz21_programs.py.
"""

from __future__ import annotations

import random
import re
from pathlib import Path

import pytest

import hil as hil_api
from fuzz21_gen import program
from nc.alarms import NcAlarm
from nc.moves import Move

ROOT = Path(__file__).resolve().parent.parent
BENCH = {"mill": ROOT / "benches" / "mill-3axis.toml", "lathe": ROOT / "benches" / "lathe-2axis.toml"}
SEEDS = [("mill", 2164, 7), ("mill", 2012, 7), ("lathe", 2123, 3)]  # 9-10 kinds of fragment a mill seed


@pytest.mark.parametrize("kind, seed, fragments", SEEDS)
def test_a_random_program_runs_clean_and_ends_where_hil_path_ends(tmp_path, kind, seed, fragments):
    prog = tmp_path / f"{kind}_{seed}.nc"
    prog.write_text(program(kind, seed, fragments, quick=True))
    moves = [m for m in hil_api.path(prog, bench=BENCH[kind]) if isinstance(m, Move)]
    r = hil_api.run(prog, bench=BENCH[kind], check=True, trace=tmp_path / "t.parquet")
    assert r.ok, (r.alarms, [str(c) for c in r.checks if not c.ok])
    assert r.final_position == pytest.approx(moves[-1].end, abs=1e-6)
    if seed == 2164:  # lock-step is deterministic: the same program gives the same trace, column for column
        first = r.trace.load()
        again = hil_api.run(prog, bench=BENCH[kind], check=True, trace=tmp_path / "t2.parquet").trace.load()
        for c in first.column_names:
            if c not in ("period", "late"):  # wall-clock columns
                assert first.column(c).equals(again.column(c)), c


JUNK = ["1.2.3", "-", "--5", ".", "+-", "#", "[", "]", "[1+", "#-1", "9" * 30, "1..", "E", "*", "/", "=", "#1=", ","]
CODES = ["G123", "G5.7", "M9999", "G1.5", "G", "M", "D99999", "H-1", "P", "L-2", "K1.5", "O", "GOTO", "END1", "DO9",
         "WHILE", "IF", "THEN", "ELSE", "G65", "M98 P99", "G41 D", "G02", "G10 L99", "G68 R", "G51 P0", "G04 P-5",
         "F-1", "S-1", "EXITW", "@", "é"]


def mutate(r: random.Random, text: str) -> str:
    """One line of `text` broken: truncated, a number made junk, a word dropped or a code added."""
    lines = text.splitlines()
    i = r.randrange(len(lines))
    ln = lines[i]
    k = r.randrange(5)
    nums = list(re.finditer(r"-?\d+\.?\d*", ln))
    if k == 0 and ln:
        lines[i] = ln[: r.randrange(len(ln))]
    elif k == 1 and nums:
        m = r.choice(nums)
        lines[i] = ln[: m.start()] + r.choice(JUNK) + ln[m.end():]
    elif k == 2 and len(ln.split()) > 1:
        words = ln.split()
        del words[r.randrange(len(words))]
        lines[i] = " ".join(words)
    elif k == 3:
        p = r.randrange(len(ln) + 1)
        lines[i] = ln[:p] + r.choice(CODES + JUNK) + ln[p:]
    else:
        lines[i] = ln + " " + r.choice(CODES)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("kind", ["mill", "lathe"])
def test_malformed_variants_end_in_a_delta_alarm_with_line_and_block(tmp_path, kind):
    """100 broken variants a kind, through `hil path`: moves, or an App. A alarm naming line, block and why."""
    alarms = 0
    for s in range(100):
        text = mutate(random.Random(s), program(kind, s, 4))
        prog = tmp_path / f"{kind}_{s}.nc"
        prog.write_text(text)
        try:
            hil_api.path(prog, bench=BENCH[kind])
        except NcAlarm as exc:
            a = exc.alarm
            alarms += 1
            assert isinstance(a.code, int) and a.code > 0 and a.message, (s, a)
            assert a.line is not None and a.block is not None, (s, a)
            assert a.block.strip() == text.splitlines()[a.line - 1].strip() or a.program != prog.name, (s, a)
    assert alarms > 30  # the variants do break programs (a mutation may hit a comment or a skipped branch)
