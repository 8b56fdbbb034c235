"""The M/S/T handshake, program-flow status and the decisions of docs/decisions/mlc.md,
through `hil run` and through the scripting Machine (the real channel, the default lathe MLC)."""

from __future__ import annotations

import csv
from types import SimpleNamespace

import pytest

from hil.bench import default_lathe
from hil.scripting import Machine
from mlc.machine import Mlc
from tests.conftest import ROOT

SIGNALS = "M31064,M31065,M31066,M21016,D31048,D31050,D31052,M31037,M31021,M31023,M31016"


def _edges(rows, col):
    """(row index, new value) at each change of a column."""
    out, prev = [], 0
    for i, r in enumerate(rows):
        v = int(float(r[col]))
        if v != prev:
            out.append((i, v))
            prev = v
    return out


def test_program_runs_through_every_strobe_and_finish_in_order(hil, tmp_path):
    prog = tmp_path / "mst.nc"
    prog.write_text("M03 S1200\nM08\nT0202\nG00 X40. Z50.\nM00\nG01 Z40. F600\nM30\n")
    trace = tmp_path / "mst.csv"
    r = hil("run", str(prog), "--mlc", "lathe", "--trace", str(trace), "--trace-signals", SIGNALS)
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    # one handshake per code, strobe and data, in program order: S, M03, M08, T
    events = []
    for col in ("M31064", "M31065", "M31066", "M21016"):
        for i, v in _edges(rows, col):
            events.append((i, col, v))
    events.sort()
    strobes = [(col, int(float(rows[i]["D31048"])) if col == "M31064" else None) for i, col, v in events
               if v == 1 and col != "M21016"]
    assert [c for c, _ in strobes] == ["M31065", "M31064", "M31064", "M31066"]
    assert [m for c, m in strobes if c == "M31064"] == [3, 8]
    # every strobe rises before its finish, the finish before the strobe drops, and the finish
    # drops before the next strobe rises
    seq = [(col if col != "M21016" else "FIN", v) for _, col, v in events]
    for k in range(0, len(seq), 4):
        strobe = seq[k][0]
        assert seq[k:k + 4] in ([(strobe, 1), ("FIN", 1), (strobe, 0), ("FIN", 0)],
                                [(strobe, 1), ("FIN", 1), ("FIN", 0), (strobe, 0)]), seq[k:k + 4]
    # data registers hold the codes
    last = rows[-1]
    assert int(float(last["D31050"])) == 1200 and int(float(last["D31052"])) == 202
    # M00 held the program until the simulated operator pressed cycle start (0.5 s)
    hold = [i for i, r_ in enumerate(rows) if r_["M31037"] == "1"]
    assert hold and 0.49 <= float(rows[hold[-1]]["t"]) - float(rows[hold[0]]["t"]) <= 0.51
    assert all(r_["M31016"] == "0" for r_ in rows[hold[0]:hold[-1] + 1])  # not "running" while held
    # M30: program end and M30 status, no strobe for it
    assert last["M31021"] == "1" and last["M31023"] == "1"
    assert "20.0000" in r.out and "40.0000" in r.out


class HoldFinish:
    """An MLC that answers every strobe but releases the finish only when told to."""

    def __init__(self):
        self.release = False

    def scan(self, mlc):
        strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")
        if strobe:
            mlc.set("MST_FINISH")
        elif self.release:
            mlc.set("MST_FINISH", False)


def _machine(program=None) -> Machine:
    bench = default_lathe()
    mlc = Mlc(program, axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config())
    m = Machine(bench, mlc)
    m.power_up()
    return m


def test_next_strobe_waits_until_the_finish_drops():
    prog = HoldFinish()
    m = _machine(prog)
    m.mlc.mem.set_u16(21000, 0)
    from nc.channel import Channel
    from nc.interp import Interpreter
    from nc.motion import Planner
    from nc.profiles import make_profile
    from nc.program import parse_program

    r = m.runner
    interp = Interpreter(make_profile("nc5-lathe-a"), dict(zip(r.axes, r.actual.tolist())))
    ch = r.channel = Channel(Planner(m.bench.motion_config(), dict(zip(r.axes, r.actual.tolist()))))
    ch.load(interp.run(parse_program("M08\nM09\n", name="t")))
    m.pulse(21000)
    m.cycle(50)
    mem = m.mlc.mem
    # M08 was finished; the finish is still ON, so M09 is not handed over yet
    assert mem.u32(31048) == 8 and not mem.bit(31064) and mem.bit(21016)
    released = m.mlc.link.cycle
    prog.release = True
    m.cycle(5)
    handed = [c for c, kind, v in m.mlc.link.handshake_log if kind == "M" and v == 9]
    assert mem.u32(31048) == 9 and handed and handed[0] > released


def test_mst_lock_runs_motion_without_handing_codes_over():
    m = _machine()
    m.mlc.mem.set_bit(21011, True)
    m.run_program("M08\nG00 X50.\nT0303\nM30\n", timeout=10)
    mem = m.mlc.mem
    assert mem.u32(31048) == 0 and mem.u32(31052) == 0
    assert abs(m.command("X") - 25.0) < 1e-6
    assert m.mlc.link.handshake_log == []


def test_several_m_codes_in_one_block_are_handed_over_one_after_another():
    m = _machine()
    seen = []
    m.watchers.append(lambda mm: seen.append(mm.mlc.mem.u32(31048)) if mm.mlc.mem.bit(31064) else None)
    m.run_program("M08 M10 M11 M09\nM30\n", timeout=10)
    assert list(dict.fromkeys(seen)) == [8, 10, 11, 9]


def test_optional_stop_holds_only_when_switched_on():
    m = _machine()
    m.panel.resume_after = 0.2
    t_off = m.run_program("M01\nM30\n", timeout=10)
    m.mlc.mem.set_bit(21009, True)
    held = []
    m.watchers.append(lambda mm: held.append(mm.mlc.mem.bit(31038)))
    t_on = m.run_program("M01\nM30\n", timeout=10)
    assert t_off < 0.05 and any(held) and t_on >= 0.2


def test_reset_while_a_strobe_is_pending_drops_it_and_stops_the_program():
    silent = SimpleNamespace(scan=lambda mlc: None)  # an MLC that never answers
    m = _machine(silent)
    with pytest.raises(Exception):
        m.run_program("M08\nG00 X10.\nM30\n", timeout=0.2)
    mem = m.mlc.mem
    assert mem.bit(31064) and mem.u32(31048) == 8
    m.reset()
    m.cycle(5)
    assert not mem.bit(31064) and mem.u32(31048) == 8  # strobe dropped, data kept
    assert mem.bit(31019)  # reset finished
    assert not m.runner.channel.busy
    assert abs(m.command("X") - 60.0) < 1e-9  # the block after the M code never ran


def test_exchange_variables_both_ways():
    m = _machine()
    mem = m.mlc.mem
    mem.set_bit(21128 + 5, True)  # M21133 → #25005
    mem.set_s16(21128 + 3, -19)  # D21131 → #25131
    m.run_program("#25256 = #25005\n#25384 = #25131 * 2 - 0.5\n#25385 = 70000\nM30\n", timeout=5)
    assert mem.bit(31128) and mem.s16(31128) == -38 and mem.s16(31129) == 32767


def test_user_alarm_stops_the_program_with_its_code():
    def scan(mlc):
        if mlc.m("M_STROBE") and mlc.d("M_CODE") == 50:
            mlc.alarm(12)
    m = _machine(SimpleNamespace(scan=scan))
    m.run_program("M50\nG00 X10.\nM30\n", timeout=5)
    codes = [a.code for a in m.runner.channel.alarms]
    assert "A12" in codes and m.mlc.mem.bit(31040)
    assert abs(m.command("X") - 60.0) < 1e-9


def test_bad_mlc_module_and_bad_signal_are_usage_errors(hil, tmp_path):
    prog = tmp_path / "p.nc"
    prog.write_text("G00 X10.\nM30\n")
    assert hil("run", str(prog), "--mlc", str(tmp_path / "none.py")).code == 2
    bad = tmp_path / "bad.py"
    bad.write_text("def scan(:\n")
    r = hil("run", str(prog), "--mlc", str(bad))
    assert r.code == 2 and "failed to load" in r.err
    r = hil("run", str(prog), "--mlc", "lathe", "--trace", str(tmp_path / "t.csv"), "--trace-signals", "M31064,Q5")
    assert r.code == 2 and "Q5" in r.err


# ---- the lathe MLC is the default on a lathe, BasicMlc on a mill (session 2) -------------------------------
def _program_time(out: str) -> float:
    return float(next(line.split()[2] for line in out.splitlines() if line.startswith("program time")))


def test_lathe_mlc_is_the_default_and_basic_stays_selectable(hil, tmp_path):
    prog = tmp_path / "sp.nc"
    prog.write_text("M03 S1200\nM05\nM30\n")
    lathe, basic = hil("run", prog), hil("run", prog, "--mlc", "basic")
    assert lathe.code == 0 and basic.code == 0, lathe.out + basic.out
    # the lathe MLC finishes M03 at speed reached and M05 at zero speed; BasicMlc in the next scan
    assert _program_time(basic.out) < 0.01 < 0.2 < _program_time(lathe.out)
    mill = tmp_path / "mill.nc"
    mill.write_text("G21 G17 G90\nM03 S1200\nM05\nM30\n")
    r = hil("run", mill, "--bench", ROOT / "benches" / "mill-3axis.toml")
    assert r.code == 0 and _program_time(r.out) < 0.01, r.out  # a mill keeps BasicMlc


def test_readme_demo_runs_with_the_lathe_mlc(hil, tmp_path):
    trace = tmp_path / "demo.csv"
    r = hil("run", ROOT / "examples" / "lathe_demo.nc", "--trace", trace, "--trace-signals", "M31064,M31066,D31048")
    assert r.code == 0 and "result         completed" in r.out, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    m_codes = [int(float(rows[i]["D31048"])) for i, v in _edges(rows, "M31064") if v == 1]
    assert m_codes == [3, 5] and [v for _, v in _edges(rows, "M31066")] == [1, 0]  # T0101 strobed too


def test_g96_m03_finishes_at_the_css_speed(hil, tmp_path):
    """Speed reached compares the drive with the G96 speed it is given, not with S150 (m/min)."""
    bench = tmp_path / "b.toml"
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    bench.write_text(text.replace("cycle_ms = 1.0", "cycle_ms = 1.0\nmax_time = 20.0"))  # a hang fails fast
    prog = tmp_path / "css.nc"
    prog.write_text("G21 G18 G99\nG50 S2000\nG96 S150 M03\nG01 X80. Z2. F2.\nM05\nM03\nG01 Z0. F0.2\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--bench", bench, "--trace", trace, "--trace-signals", "M31064,M21016,D31048")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    m03 = [i for i, v in _edges(rows, "M31064") if v == 1 and rows[i]["D31048"] == "3"][-1]  # the 2nd M03
    fin = next(i for i, v in _edges(rows, "M21016") if v == 1 and i > m03)
    want = 1000.0 * 150.0 / (3.141592653589793 * 80.0)  # at X80. (diameter), after the first move
    assert float(rows[fin]["S1_rpm_act"]) == pytest.approx(want, rel=0.02)
