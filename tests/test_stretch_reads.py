"""The NC's steps inside stretches (issue 17, decisions bench B26/B27): the CAM program's queue refills 4 blocks
a cycle and its blocks are solved where its speed dips, and those cycles now run inside the stretch (the channel's
feed, the planner's block ends and solves). The trace equals cycle-by-cycle stepping's column by column, also
where the program reads something else than plain moves in between (an M code, a macro statement, a dwell, a
soft-limit crossing, the program's end), where a stretch must end before the cycle that reads it."""

from __future__ import annotations

import pytest

import hil.stretch_pass
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
    counts = {"feeds": 0, "passes": 0}
    real = hil.stretch_pass.Pass.run

    def counted(self, n):
        m = real(self, n)
        counts["feeds"] += self.feeds
        counts["passes"] += 1
        return m

    monkeypatch.setattr(hil.stretch_pass.Pass, "run", counted)
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), KW, tmp_path / f"{on}.parquet", kept))
    return out, kept, counts


def test_feeds_inside_stretches_equal_stepping(monkeypatch, tmp_path):
    out, (stepped, stretched), counts = _both(monkeypatch, tmp_path, cam_program(2000))
    assert compare(out[0], out[1]) == []
    assert stepped.run.stretched == 0 and stretched.run.ok
    assert counts["feeds"] > 400  # ≈ one cycle in four reads the program
    # B25 alone (stretches end before every reading cycle and every solve): 48 % of this run; now 94 %
    assert stretched.run.stretched > 0.9 * stretched.run.cycles, (stretched.run.stretched, stretched.run.cycles)


def test_reads_off_ends_stretches_before_reading_cycles(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_READS, "0")
    out, (_, stretched), counts = _both(monkeypatch, tmp_path, cam_program(2000))
    assert compare(out[0], out[1]) == []
    assert counts["passes"] == 0 and stretched.run.stretched < 0.5 * stretched.run.cycles


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


@pytest.mark.parametrize("what", ["following error", "overspeed"])
def test_a_drive_fault_inside_a_pass_lands_on_its_cycle(monkeypatch, tmp_path, what):
    """A drive fault in the middle of a stretch that runs the NC's steps (B27): the stretch ends before that
    cycle; the planner goes back to its last save after a feed and steps again up to there, the drives from the
    start. The rows, the alarm and where the axes stop are the stepped run's."""
    from dataclasses import replace

    import pyarrow.parquet as pq

    from fieldbus.link import SimLink
    from hil.bench_file import load_bench_file
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from hil.trace import open_trace
    from nc.program import parse_program

    text = cam_program(1200).replace("M30", "G01 Z90. F6000\nM30")  # Z moves after the CAM blocks only
    backs = []
    real = hil.stretch_pass.Pass._back
    monkeypatch.setattr(hil.stretch_pass.Pass, "_back", lambda self, stop: backs.append(stop) or real(self, stop))
    runs = []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        bench = load_bench_file(ROOT / "benches" / "mill-3axis.toml")
        drives = sim_slaves(bench)
        p = drives[2].params  # Z: its window shrunk, or its position loop's sign flipped (a runaway: 0x0602)
        drives[2].params = replace(p, following_error_window=6000) if what == "following error" \
            else replace(p, kp=-abs(p.kp))
        runner = BenchRunner(bench, SimLink(drives, bench.cycle))
        runner.trace = open_trace(tmp_path / f"{on}.parquet", runner.trace_columns())
        result = runner.run_program(parse_program(text))
        table = pq.read_table(tmp_path / f"{on}.parquet")
        runs.append(({c: table.column(c).to_pylist() for c in table.column_names if c not in ("period", "late")},
                     result))
    (ra, a), (rb, b) = runs
    assert ra == rb
    assert [(x.code, x.axis) for x in a.alarms] == [(x.code, x.axis) for x in b.alarms] and a.alarms
    assert backs and b.stretched > 0.6 * b.cycles and a.final == b.final


@pytest.mark.parametrize("name", ["polyline", "surface", "mixed", "contour"])
def test_blends_arcs_and_exact_stops_inside_passes_equal_stepping(monkeypatch, tmp_path, name):
    """benchmarks/bench_vs_linuxcnc's programs on the mill: corner blends under the filter (its share λ below 1,
    decision motion 45), chord arcs, 90° corners with exact stops; the passes take their solves and block ends."""
    from benchmarks.bench_vs_linuxcnc import cam_polyline, cam_surface, contour_90, mixed

    prog = {"polyline": lambda: cam_polyline(300), "surface": lambda: cam_surface(300), "mixed": mixed,
            "contour": lambda: contour_90(60.0)}[name]()
    out, (stepped, stretched), counts = _both(monkeypatch, tmp_path, prog.text(False))
    assert compare(out[0], out[1]) == []
    assert stretched.run.ok and counts["passes"] > 0
    assert stretched.run.stretched > 0.9 * stretched.run.cycles, (stretched.run.stretched, stretched.run.cycles)


def test_long_passes_end_before_a_cycle_that_reads_nothing(monkeypatch, tmp_path):
    """Decision B68: a stretch that runs the NC's steps is not bound by the planner's 64-cycle buffer. Past
    PASS_CYCLES it goes on to the first cycle whose feed reads nothing, at most PASS_OVER more, so the next
    stretch can start there (none starts at a reading cycle). Small values here, for many ends in a short run: the
    trace is stepping's, and no pass that ended past PASS_CYCLES before its limit left a cycle whose feed reads
    plain moves only. (A feed that would read another event, the program's M30, ends a pass before its cycle
    whatever its length (B27, `Ahead.peek`): with decision motion 83 (c)'s setpoints one pass past PASS_CYCLES
    meets the M30's feed.)"""
    import hil.stretch
    from hil.stretch_reads import ahead, may_read
    from nc.channel import READS_PER_CYCLE

    monkeypatch.setattr(hil.stretch, "PASS_CYCLES", 40)
    monkeypatch.setattr(hil.stretch, "PASS_OVER", 8)
    ends = []
    real = hil.stretch_pass.Pass.run

    def ended(self, n):
        m = real(self, n)
        ends.append((n, m, hil.stretch_pass._feed_due(self.pl) and may_read(self.ch, self.pl)
                     and ahead(self.ch).peek(READS_PER_CYCLE)))  # (the pass peeked there too: nothing new read)
        return m

    monkeypatch.setattr(hil.stretch_pass.Pass, "run", ended)
    out, (stepped, stretched), _ = _both(monkeypatch, tmp_path, cam_program(1500))
    assert compare(out[0], out[1]) == []
    assert stepped.run.stretched == 0 and stretched.run.ok
    assert ends and all(n <= 48 for n, _, _ in ends)
    past = [(m, reads) for n, m, reads in ends if 40 <= m < n]  # ended by the rule (or by the program's end)
    assert len(past) > 10 and not any(reads for _, reads in past), past
    assert any(m > 40 for m, _ in past)  # some went on past PASS_CYCLES through reading cycles
