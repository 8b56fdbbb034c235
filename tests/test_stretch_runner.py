"""The stretch runner (hil/stretch.py, issue 17, decision B20) gives the trace cycle-by-cycle stepping gives:
each run below is made with stretches off (DELTAHIL_STRETCH=0) and on, and every trace column (MLC devices
included, wall-clock period/late aside), the alarms, handshakes, end record and final positions are
compared; each run must also have taken stretches, so the comparison covers them."""

from __future__ import annotations

import hashlib
from dataclasses import replace

import pyarrow.parquet as pq
import pytest

from benchmarks.trace_ab import SIGNALS, compare, one
from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from hil.stretch import ENV
from hil.trace import open_trace
from nc.alarms import SERVO_ALARM
from nc.program import parse_program
from tests.conftest import ROOT

DEMO = str(ROOT / "examples" / "lathe_demo.nc")


def _both(monkeypatch, tmp_path, program: str, **kw) -> tuple:
    """(stepped, stretched) runs as trace_ab compares them, and the stretched run's result."""
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(program, kw, tmp_path / f"{on}.parquet", kept))
    assert kept[0].run.stretched == 0
    return out[0], out[1], kept[1]


def test_lathe_demo_stretched_equals_stepped(monkeypatch, tmp_path):
    a, b, r = _both(monkeypatch, tmp_path, DEMO)
    assert compare(a, b) == []
    assert r.run.ok
    assert r.run.stretched > 0.8 * r.run.cycles  # most of the demo's cycles go in stretches


@pytest.mark.parametrize("events", [
    ["t=2:feed-hold", "t=2.6:cycle-start", "t=4:set D21002=50"],  # hold, resume, feed override 50 %
    ["t=3:estop", "t=3.02:set D21002=50"],  # an event while the drives brake (recovery after it: B58)
    ["t=2.0005:set D21002=70", "t=2.0205:set D21002=120"],  # override changes inside a stretch's span
    ["line=12:set D21002=60", "Z<-30:set D21002=80", "cycle=9000:set D21002=100"],  # line, position, cycle
])
def test_operator_events_land_on_the_same_cycles(monkeypatch, tmp_path, events):
    a, b, r = _both(monkeypatch, tmp_path, DEMO, events=events)
    assert compare(a, b) == []
    assert r.run.stretched > 1000
    assert [c for c in b[0]["event"] if c]  # events fired, in the same rows (compared above)


def test_overrides_at_power_on(monkeypatch, tmp_path):
    a, b, r = _both(monkeypatch, tmp_path, DEMO, feed_override=70.0, spindle_override=110.0)
    assert compare(a, b) == []
    assert r.run.stretched > 1000


def _direct(monkeypatch, tmp_path, on: str, program: str, tweak) -> tuple:
    """A BenchRunner on the default lathe with its drives changed by `tweak`, traced; (rows, result)."""
    monkeypatch.setenv(ENV, on)
    bench = default_lathe()
    drives = sim_slaves(bench)
    tweak(drives)
    runner = BenchRunner(bench, SimLink(drives, bench.cycle))
    path = tmp_path / f"d{on}.parquet"
    runner.trace = open_trace(path, runner.trace_columns())
    result = runner.run_program(parse_program(program))
    table = pq.read_table(path)
    rows = {c: table.column(c).to_pylist() for c in table.column_names if c not in ("period", "late")}
    return rows, result


# the spindle turns first: its drive stretches once its index is latched (a thread's sync)
PROGRAMS = {"following error": "G98\nM03 S500\nG04 X0.3\nG01 Z-20. F600\nG01 Z-160. F9000\nM30\n",
            "overspeed": "G98\nM03 S500\nG04 X0.3\nG01 X100. Z-20. F600\nM30\n"}


@pytest.mark.parametrize("what", ["following error", "overspeed"])
def test_a_drive_fault_inside_a_stretch_lands_on_its_cycle(monkeypatch, tmp_path, what):
    """A following-error fault of the Z drive (its window shrunk) and a runaway X drive (its position loop's sign
    flipped: App. A 0x0602 from the bench's overspeed check) happen inside what would be a stretch: the stretch
    ends before that cycle, which runs as a stepped one; the alarm, its cycle and the stop after it are the same."""
    def tweak(drives):
        if what == "following error":
            drives[1].params = replace(drives[1].params, following_error_window=3000)
        else:
            drives[0].params = replace(drives[0].params, kp=-abs(drives[0].params.kp))

    (ra, a), (rb, b) = (_direct(monkeypatch, tmp_path, on, PROGRAMS[what], tweak) for on in ("0", "1"))
    assert ra == rb
    assert [(x.code, x.axis) for x in a.alarms] == [(x.code, x.axis) for x in b.alarms]
    assert a.alarms[0].code == (SERVO_ALARM if what == "following error" else 0x0602)
    assert b.stretched > 0 and a.final == b.final
    first = next(i for i, s in enumerate(rb["alarm"]) if s)
    assert first > 100  # mid-program, after stretches ran


def test_a_hardware_limit_hit_inside_a_stretch_lands_on_its_cycle(monkeypatch, tmp_path):
    """X's drive has its positive limit switch at 85 mm and the program feeds X to 90 mm: the stretch ends before
    the cycle whose sub-steps reach the switch (the drive's limit handling, then the bench's 0x0402), which runs
    as a stepped one; the rows, the alarm and where X is held are the stepped run's."""
    def tweak(drives):
        drives[0].params = replace(drives[0].params, positive_limit=85 * 1_280_000 // 5)

    program = "G98\nM03 S500\nG04 X0.3\nG01 U60. F600\nM30\n"
    (ra, a), (rb, b) = (_direct(monkeypatch, tmp_path, on, program, tweak) for on in ("0", "1"))
    assert ra == rb
    assert [x.code for x in b.alarms] == [0x0402] == [x.code for x in a.alarms]
    assert b.stretched > 1000 and a.final == b.final
    assert 84.9 < b.final["X"] <= 85.0 + 1e-3


_EXCHANGE = BenchRunner._exchange


def _digest(buf) -> bytes:
    """The bytes of a memory area by a 32-byte BLAKE2b digest: equal exactly when the bytes are (bar a collision)."""
    return hashlib.blake2b(memoryview(buf).cast("B")).digest()


def _states(monkeypatch, on: str, program: str, **kw) -> tuple[dict, object]:
    """The machine's state at the start of every stepped cycle: MLC device memory and counters, the runner's
    counters and clock. A stretch's cycles are not stepped; the cycle after one must find what stepping left."""
    monkeypatch.setenv(ENV, on)
    seen: dict[int, tuple] = {}
    original = _EXCHANGE  # not the hook a previous run of the test installed

    def exchange(self: BenchRunner) -> None:
        mlc = self.mlc
        mem = getattr(mlc, "mem", None)
        gate = getattr(mlc, "gate", None)
        pl = self.channel.planner if self.channel is not None else None
        seen[self.cycle] = (
            # the device memory by its digest: 300 kB a cycle kept for every cycle took ~5 GB a run (session 21)
            _digest(mem.m) if mem is not None else None, _digest(mem.d) if mem is not None else None,
            getattr(mlc, "time", None), getattr(getattr(mlc, "link", None), "cycle", getattr(mlc, "cycle", None)),
            (gate.scans, gate.skipped) if gate is not None else None, self.time, list(self._rest),
            list(self._last_position), [m.cycles_in_state for m in self.masters], dict(self.result.max_ferr),
            self.clock._n, self.link.time, self.line, self._commands.tolist(), self.actual.tolist(),
            [(rx.target_position, rx.target_velocity, rx.controlword, rx.mode) for rx in self.rx],
            pl._settle.cycles if pl is not None else None, getattr(getattr(mlc, "caxis", None), "_cycles", None))
        original(self)

    monkeypatch.setattr(BenchRunner, "_exchange", exchange)
    from hil.api import run

    r = run(program, check=False, **kw)
    return seen, r


@pytest.mark.parametrize("kw", [{}, {"mlc": "basic"}, {"feed_override": 80.0, "spindle_override": 110.0}])
def test_the_machine_after_a_stretch_is_the_stepped_one(monkeypatch, kw):
    """Stretches without device columns or events take their cycles after the first at once (hil/stretch_bulk.py):
    whatever a stretch ends in (MLC memory, scan counts, clocks, rest counters, setpoints) is what stepping
    reaches at the same cycle."""
    stepped, a = _states(monkeypatch, "0", DEMO, **kw)
    stretched, b = _states(monkeypatch, "1", DEMO, **kw)
    assert b.run.stretched > 0.8 * b.run.cycles
    assert len(stretched) < 0.2 * len(stepped)
    for cycle, state in stretched.items():
        assert state == stepped[cycle], cycle
    assert (a.run.cycles, a.run.final, a.run.max_ferr) == (b.run.cycles, b.run.final, b.run.max_ferr)


@pytest.mark.parametrize("kw", [{}, {"mlc": "basic", "feed_override": 120.0}, {"aux_timeout": 0.02}])
def test_plain_trace_of_bulk_stretches_equals_stepped(monkeypatch, tmp_path, kw):
    """Without device columns a stretch's cycles are taken at once: the trace and its end record (with the
    slow-answer warnings of a 20 ms aux_timeout) are the stepped ones."""
    import json

    from hil.api import run

    tables, ends = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        r = run(DEMO, trace=str(tmp_path / f"p{on}.parquet"), check=False, **kw)
        t = pq.read_table(tmp_path / f"p{on}.parquet")
        tables.append({c: t.column(c).to_pylist() for c in t.column_names if c not in ("period", "late")})
        ends.append(json.loads(t.schema.metadata[b"deltahil"])["end"])
    assert r.run.stretched > 0.8 * r.run.cycles
    assert tables[0] == tables[1]
    assert ends[0] == ends[1]
    assert bool(ends[1].get("warnings")) == ("aux_timeout" in kw)


def test_max_time_and_a_dwell_inside_stretches(monkeypatch, tmp_path):
    """A dwell between moves and the bench's max_time running out in the middle of a move (deltahil's alarm
    0xDE.., the stop along the path after it): the same rows, alarm and end with stretches on and off."""
    program = "G98\nM03 S500\nG04 X0.3\nG01 Z-40. F600\nG04 X0.2\nG01 X120. Z-140. F900\nM30\n"
    runs = []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        bench = replace(default_lathe(), max_time=3.2)
        runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
        path = tmp_path / f"m{on}.parquet"
        runner.trace = open_trace(path, runner.trace_columns())
        result = runner.run_program(parse_program(program))
        t = pq.read_table(path)
        runs.append(({c: t.column(c).to_pylist() for c in t.column_names if c not in ("period", "late")}, result))
    (ra, a), (rb, b) = runs
    assert ra == rb
    assert [x.code for x in a.alarms] == [x.code for x in b.alarms] and a.alarms
    assert b.stretched > 1000 and a.final == b.final
    first = next(i for i, s in enumerate(rb["alarm"]) if s)
    # raised after cycle 3,200 (max_time / cycle), so in the next cycle's row: not at the end of some stretch
    assert ra["cycle"][first] == 3201


def test_an_aux_wait_stretches_and_warns_on_the_same_cycle(monkeypatch, tmp_path):
    """While an M/S/T code waits for its finish (the spindle running up after M03, the turret indexing) the
    cycles stretch too (the planner standing, nc/motion/stretch.stand_stretch); the finish and the slow-answer
    warning (aux_timeout 20 ms) land on the stepped cycles and times."""
    a, b, r = _both(monkeypatch, tmp_path, DEMO, aux_timeout=0.02)
    assert compare(a, b) == []
    warnings = b[1][-1][b"deltahil"]["end"]["warnings"]
    assert warnings and warnings == a[1][-1][b"deltahil"]["end"]["warnings"]
    assert r.run.stretched > 0.9 * r.run.cycles
