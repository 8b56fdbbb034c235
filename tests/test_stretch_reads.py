"""The channel's feed inside stretches across a cruise's blocks (issue 17, decision bench B26): the CAM program's
queue refills 4 blocks a cycle, and those cycles now run inside the stretch. The trace equals cycle-by-cycle
stepping's column by column, also where the program reads something else than plain moves in between (an M
code, a macro statement, a dwell, a soft-limit crossing, the program's end), where a stretch must end before
the cycle that reads it."""

from __future__ import annotations

import pytest

import hil.stretch
from benchmarks.bench_motion import cam_program
from benchmarks.trace_ab import compare, one
from hil.stretch import ENV, ENV_READS
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")
KW = {"bench": MILL, "trace_signals": None}  # no device columns: the bench's basic MLC


def _program(blocks: int, inserts: dict[int, str]) -> str:
    lines = cam_program(blocks).splitlines()
    for at in sorted(inserts, reverse=True):
        lines.insert(at, inserts[at])
    return "\n".join(lines) + "\n"


def _both(monkeypatch, tmp_path, text: str) -> tuple[list, list, dict]:
    prog = tmp_path / "cam.nc"
    prog.write_text(text)
    counts = {"feeds": 0}
    real = hil.stretch.sample_reading

    def counted(ch, pl, n, expect):
        smp, feeds = real(ch, pl, n, expect)
        counts["feeds"] += feeds
        return smp, feeds

    monkeypatch.setattr(hil.stretch, "sample_reading", counted)
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), KW, tmp_path / f"{on}.parquet", kept))
    return out, kept, counts


def test_feeds_inside_stretches_equal_stepping(monkeypatch, tmp_path):
    out, (stepped, stretched), counts = _both(monkeypatch, tmp_path, cam_program(2000))
    assert compare(out[0], out[1]) == []
    assert stepped.run.stretched == 0 and stretched.run.ok
    assert counts["feeds"] > 200  # ≈ one cycle in six reads the program
    # B25 alone (stretches end before every reading cycle): 48 % of this run; with the feeds inside 60 %
    assert stretched.run.stretched > 0.55 * stretched.run.cycles, (stretched.run.stretched, stretched.run.cycles)


def test_reads_off_ends_stretches_before_reading_cycles(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_READS, "0")
    out, (_, stretched), counts = _both(monkeypatch, tmp_path, cam_program(2000))
    assert compare(out[0], out[1]) == []
    assert counts["feeds"] == 0 and stretched.run.stretched < 0.5 * stretched.run.cycles


@pytest.mark.parametrize("inserts, alarm", [
    ({300: "M08", 700: "#100=#100+1", 701: "#101=#100*2", 1100: "G04 P10", 1400: "M09"}, None),
    ({900: "X400. Y0.5"}, "0x0A01"),  # beyond the 300 mm soft limit: the moves before it run out, then the alarm
])
def test_other_events_end_a_stretch_before_their_cycle(monkeypatch, tmp_path, inserts, alarm):
    out, (stepped, stretched), counts = _both(monkeypatch, tmp_path, _program(1500, inserts))
    assert compare(out[0], out[1]) == []
    assert counts["feeds"] > 50
    alarms = [a.code_text for a in stretched.alarms]
    assert alarms == ([] if alarm is None else [alarm]), [str(a) for a in stretched.alarms]


def test_macro_loop_spending_its_budget(monkeypatch, tmp_path):
    """Moves made by macro statements (15 a move: four moves a cycle spend the budget of 40, the interpreter
    hands out Busy): a peek stops at them, and the stepped feed reads them back with the budget as it was."""
    body = "\n".join(f"#{10 + k}=#2*{k + 1}" for k in range(12))
    text = ("G90 G17 G94 G01 F3000\n#1=0\nWHILE [#1 LT 1200] DO1\n#2=#1*0.04\n#3=#2*0.5\n" + body
            + "\nX#2 Y#3\n#1=#1+1\nEND1\nM30\n")
    out, (stepped, stretched), counts = _both(monkeypatch, tmp_path, text)
    assert compare(out[0], out[1]) == []
    assert stretched.run.ok and stretched.run.stretched > 0
    budget = stretched.runner._interp.budget
    assert budget.held_cycles > 0  # the budget was spent: Busy was handed out
    assert budget.held_cycles == stepped.runner._interp.budget.held_cycles
