"""The MLC user scan that runs only when something it read changed (mlc/on_change.py, issue 17):
runs with the shortcut on and off give the same trace, column by column (MLC devices included), the
same handshakes and alarms; a poked device, a timer coming due and an edge still reach the program
in the same cycle."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

import mlc.lathe
from hil.api import run

PART = ("G21 G18 G98\nT0505\nS900 M03\nG00 X40. Z2.\nG01 Z-10. F600\nM08\nG04 P100\n"
        "G96 S120\nG01 X20. F300\nG97 S600\nM09\nM05\nG00 X60. Z20.\nM30\n")
# A user program that declares SCAN_ON_CHANGE: copies D21500 to D21501, answers every strobe 30 ms after
# it rose (timer), counts rising edges of M21501 in D21502 and switches Y-less I/O module 0 point 1.
USER = '''
SCAN_ON_CHANGE = True

def setup(mlc):
    mlc.state["edges"] = 0

def scan(mlc):
    mlc.put("D21501", mlc.d("D21500"))
    if mlc.rising("M21501"):
        mlc.state["edges"] += 1
    mlc.put("D21502", mlc.state["edges"])
    strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")
    if not strobe:
        mlc.set("MST_FINISH", False)
    mlc.io.out(0, 1, mlc.m("M21501"))
    if mlc.timer("fin", 0.03, strobe):
        mlc.set("MST_FINISH")
'''
SIGNALS = "M_STROBE,S_STROBE,T_STROBE,MST_FINISH,SPINDLE1_FWD,SPINDLE_ANALOG_1,D21501,D21502,M21501,D30272"


def _run(tmp_path, on: bool, program: str, **kw):
    trace = tmp_path / f"{'on' if on else 'off'}.parquet"
    old = mlc.lathe.SCAN_ON_CHANGE
    mlc.lathe.SCAN_ON_CHANGE = on
    try:
        r = run(str(program), trace=str(trace), trace_signals=SIGNALS, check=False, **kw)
    finally:
        mlc.lathe.SCAN_ON_CHANGE = old
    table = pq.read_table(trace)
    cols = {c: table.column(c).to_pylist() for c in table.column_names if c not in ("period", "late")}
    return r, cols


def _same(a, b) -> None:
    (ra, ca), (rb, cb) = a, b
    assert ca.keys() == cb.keys()
    for c in ca:
        assert ca[c] == cb[c], f"column {c} differs"
    assert ra.run.final == rb.run.final
    assert [x.code_text for x in ra.alarms] == [x.code_text for x in rb.alarms]
    assert ra.runner.mlc.link.handshake_log == rb.runner.mlc.link.handshake_log


def test_lathe_mlc_skips_quiet_scans_and_leaves_the_trace_as_it_was(tmp_path):
    prog = tmp_path / "part.nc"
    prog.write_text(PART)
    off, on = _run(tmp_path, False, prog), _run(tmp_path, True, prog)
    _same(off, on)
    r, cols = on
    gate = r.runner.mlc.gate
    assert r.completed
    # the turret (T0505: 4 stations, 0.6 s timer), M03/M08/M09/M05 and the G96 part scanned; most cycles not
    assert gate.skipped > gate.scans > 0
    kinds = [k for _, k, _ in r.runner.mlc.link.handshake_log]
    assert kinds.count("FIN") >= 7 and "T" in kinds
    analog = cols["D20160"]  # SPINDLE_ANALOG_1
    assert max(analog) > 0 and analog[-1] == 0  # M05 reached the analog output
    # under G96 the analog output follows X every cycle: those scans all ran
    assert len(set(analog)) > 50


def test_lathe_mlc_e_stop_and_feed_hold_by_events_are_seen_in_the_same_cycle(tmp_path):
    prog = tmp_path / "part.nc"
    prog.write_text(PART)
    events = ["t=1.2:feed-hold", "t=1.5:cycle-start", "t=2.0:estop"]  # (a run ends at its E-stop: B58)
    off, on = _run(tmp_path, False, prog, events=events), _run(tmp_path, True, prog, events=events)
    _same(off, on)
    assert "0401" in ";".join(a.code_text for a in on[0].alarms)


def test_user_program_on_change_sees_pokes_edges_and_timers(tmp_path):
    user = tmp_path / "user_mlc.py"
    user.write_text(USER)
    prog = tmp_path / "p.nc"
    prog.write_text("G21 G18 G98\nS500 M03\nG01 X10. Z-5. F600\nT0202\nM05\nM30\n")
    events = ["cycle=300:set D21500=7", "cycle=420:pulse M21501", "cycle=500:pulse M21501"]

    def both():
        out = []
        for on in (False, True):
            text = USER if on else USER.replace("SCAN_ON_CHANGE = True", "SCAN_ON_CHANGE = False")
            user.write_text(text)
            trace = tmp_path / f"u{on}.parquet"
            r = run(str(prog), mlc=str(user), trace=str(trace), trace_signals=SIGNALS, events=events, check=False)
            t = pq.read_table(trace)
            out.append((r, {c: t.column(c).to_pylist() for c in t.column_names if c not in ("period", "late")}))
        return out

    off, on = both()
    _same(off, on)
    r, cols = on
    assert r.runner.mlc.gate is not None and off[0].runner.mlc.gate is None
    assert r.runner.mlc.gate.skipped > r.runner.mlc.gate.scans
    # the scan that sees the poke (its row names the event) copies it
    i = cols["event"].index("set D21500=7")
    assert cols["D21501"][i - 1] == 0 and cols["D21501"][i] == 7
    assert cols["D21502"][-1] == 2  # both pulses counted once
    fin = [k for _, k, _ in r.runner.mlc.link.handshake_log].count("FIN")
    assert fin == 4  # S, M03, T, M05 each finished by the 30 ms timer


@pytest.mark.parametrize("state", [{"log": []}, {"n": 0}])
def test_a_scan_that_changes_its_state_or_keeps_mutable_state_runs_again(state):
    from mlc.memory import DeviceMemory
    from mlc.on_change import ScanGate
    from mlc.program import ScanContext

    ctx = ScanContext(DeviceMemory())
    ctx.state.update(state)
    gate = ScanGate(ctx)
    calls = []

    def scan(c):
        calls.append(1)
        c.d("D100")
        if "log" in c.state:
            c.state["log"].append(1)  # changed in place: the gate cannot see it, so it never skips

    for _ in range(5):
        if not gate.quiet():
            gate.run(scan)
    assert len(calls) == (5 if "log" in state else 1)
    ctx.mem.set_u16(100, 3)  # an input the scan read changed: it runs again
    if not gate.quiet():
        gate.run(scan)
    assert len(calls) == (6 if "log" in state else 2)
