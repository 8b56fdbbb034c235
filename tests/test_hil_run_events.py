"""`hil run --at TRIGGER:ACTION` / `--events FILE`: timed pokes at MLC devices, checked on the trace in
simulated time (hil/run_events.py)."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from hil.cli import main
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")
LATHE_IO = str(ROOT / "benches" / "lathe-io.toml")
M96 = str(ROOT / "examples" / "m96_interrupt.nc")
CUT = "G90 G54 G17 G21 G94\nG01 X100. F3000\nM30\n"  # 50 mm/s along X on the mill


def read(path) -> dict[str, np.ndarray | list[str]]:
    rows = list(csv.DictReader(open(path)))
    cols: dict = {c: np.array([float(r[c]) for r in rows]) for c in rows[0] if c not in ("alarm", "event")}
    cols["event"] = [r["event"] for r in rows]
    return cols


def run(tmp_path, program: str, *args: str, bench: str = MILL) -> tuple[int, str, dict]:
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    trace = tmp_path / "t.csv"
    code = main(["run", str(prog), "--bench", bench, "--trace", str(trace), "--no-check", *args])
    return code, str(trace), read(trace) if trace.exists() else {}


def test_pulse_m21019_at_1_1_s_runs_the_m96_interrupt_program(tmp_path, capsys):
    trace = tmp_path / "m96.csv"
    code = main(["run", M96, "--bench", MILL, "--at", "t=1.1:pulse M21019", "--trace", str(trace),
                 "--trace-signals", "M31031", "--no-check"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "events         1 applied" in out and "t=1.100 s  cycle 1100  line 3  pulse M21019   [t=1.1]" in out
    c = read(trace)
    on = np.flatnonzero(c["M21019"] == 1)
    assert list(c["t"][on]) == [1.1] and c["event"][on[0]] == "pulse M21019"  # ON for exactly one scan
    busy = np.flatnonzero(c["M31031"] == 1)
    assert len(busy) > 100 and c["t"][busy[0]] > 1.1  # O0050 ran after the trigger, with M31031 ON
    # the cut stopped half way (X ≈ 50 at 50 mm/s after 1.1 s), O0050 lifted Z by 10 there and came back
    x_stop = c["X_cmd"][busy[0]]
    assert 45.0 < x_stop < 60.0
    z_up = c["Z_cmd"][busy].max()
    assert abs(z_up - 110.0) < 0.05 and np.allclose(c["X_cmd"][busy[1:-1]], x_stop, atol=1e-3)
    assert abs(c["Z_cmd"][: busy[0] - 1].max() - 100.0) < 1e-9  # no lift before M31031 (one scan late)
    assert np.allclose([c["X_cmd"][-1], c["Y_cmd"][-1], c["Z_cmd"][-1]], [0.0, 50.0, 100.0], atol=1e-6)
    # `hil trace` lists the applied events from the trace
    assert main(["trace", str(trace)]) == 0
    assert "events         1\n  pulse M21019 at cycle 1100 (t=1.100 s), line 3" in capsys.readouterr().out


def test_feed_override_set_mid_move_halves_the_path_speed_from_then_on(tmp_path, capsys):
    code, _, c = run(tmp_path, CUT, "--at", "t=0.8:set D21002=50")
    assert code == 0, capsys.readouterr().out
    t, x = c["t"], c["X_cmd"]
    v = np.diff(x) / np.diff(t)  # commanded speed between rows, mm/s
    tv = t[1:]
    assert np.allclose(v[(tv > 0.3) & (tv <= 0.8)], 50.0, atol=1e-6)  # 100 % up to the scan at 0.8 s
    assert c["D21002"][t < 0.8].max() == 100 and np.all(c["D21002"][t >= 0.8] == 50)
    cruise = (tv > 1.0) & (x[1:] < 99.0)
    assert cruise.sum() > 1000 and np.allclose(v[cruise], 25.0, atol=1e-6)  # 50 % of F3000
    # 0.8 s at 50 mm/s = 40 mm, the other 60 mm at 25 mm/s: the program takes ≈ 3.2 s, not 2.0 s
    assert 3.1 < t[np.argmax(x > 100.0 - 1e-6)] < 3.4


def test_line_trigger_fires_into_the_scan_after_the_first_cycle_of_that_line(tmp_path):
    program = "G90 G54 G17 G21 G94\nG01 X10. F3000\nG01 Y10.\nG01 X0\nM30\n"
    code, _, c = run(tmp_path, program, "--at", "line=3:set D21006=7", "--at", "cycle=400:pulse M21500")
    assert code == 0
    first = int(np.argmax(c["line"] == 3))  # the first cycle the channel executes line 3
    assert c["line"][first - 1] == 2 and 0.1 < c["t"][first] < 0.5
    assert c["D21006"][first] != 7 and np.all(c["D21006"][first + 1:] == 7)
    assert c["event"][first + 1] == "set D21006=7"
    fired = sorted(int(c["cycle"][i]) for i, e in enumerate(c["event"]) if e)
    assert fired == sorted([int(c["cycle"][first + 1]), 400])
    assert list(c["cycle"][c["M21500"] == 1]) == [400]


def test_axis_trigger_and_remote_inputs_through_the_terminal(tmp_path, capsys):
    # lathe-io: X5 is point 5 of station EIO-501; the event switches the simulated terminal
    program = "G18 G21 G98\nG00 X20. Z0\nG01 Z-20. F600\nG00 Z0\nM30\n"  # 10 mm/s
    code, _, c = run(tmp_path, program, "--at", "Z<-10:set X5=1", "--at", "t=2.5:reset X5",
                     "--at", "Z<-15:pulse X6", bench=LATHE_IO)
    out = capsys.readouterr().out
    assert code == 0, out
    on = np.flatnonzero(c["X5"] == 1)
    assert len(on) and c["Z_act"][on[0] - 1] < -10.0 <= c["Z_act"][on[0] - 2]  # crossed one cycle before
    assert abs(c["t"][on[-1] + 1] - 2.5) < 1e-9 and c["X5"][-1] == 0
    assert len(np.flatnonzero(c["X6"] == 1)) == 1  # ON for one scan
    assert "never triggered" not in out


def test_events_file_and_named_operator_actions(tmp_path, capsys):
    events = tmp_path / "ev.txt"
    events.write_text("# feed hold for 0.6 s mid-cut\nt=0.5 : feed hold   # M21001\nt=1.1:cycle-start\n"
                      "line=99:set M21500=1\n")
    code, _, c = run(tmp_path, CUT, "--events", str(events), "--allow-unfired")  # line 99 never comes
    out = capsys.readouterr().out
    assert code == 0, out
    assert "feed-hold (pulse M21001)" in out and "never triggered: line=99:set M21500=1" in out
    t, x = c["t"], c["X_cmd"]
    v = np.diff(x) / np.diff(t)
    stopped = (t[1:] > 0.7) & (t[1:] < 1.1)
    assert np.allclose(v[stopped], 0.0, atol=1e-9) and 24.0 < x[t == 0.9][0] < 27.0
    assert np.allclose(v[(t[1:] > 1.3) & (x[1:] < 97.0)], 50.0, atol=1e-6)  # resumed at F3000


@pytest.mark.parametrize("spec, message", [
    ("t=1.1 pulse M21019", "expected TRIGGER:ACTION"),
    ("t=abc:pulse M21019", "expected t=SECONDS"),
    ("t=1:pulse M21019x", "neither a device address nor a signal name"),
    ("t=1:pulse NO_SUCH_SIGNAL", "neither a device address nor a signal name"),
    ("t=1:set M31031=1", "M31031 (M96_ACTIVE) is NC → MLC status"),
    ("t=1:set D31048=5", "NC → MLC status"),
    ("t=1:set M29032=1", "NC → MLC status"),
    ("t=1:pulse D21002", "a D register has no ON/OFF"),
    ("t=1:set M21019=2", "is a bit"),
    ("t=1:set D21002=70000", "takes 0…65535"),
    ("t=1:set D21002=12.5", "has a fraction"),
    ("Q<5:set M21019=1", "axis Q is not on the bench"),
    ("line=0:set D21006=1", "program lines start at 1"),  # it fired after the program's end, where line is 0
    ("cycle=0:feed-hold", "bench cycles start at 1"),
    ("t=1:frobnicate", "expected set DEVICE=VALUE"),
])
def test_bad_event_specs_exit_2_with_a_message(tmp_path, capsys, spec, message):
    prog = tmp_path / "p.nc"
    prog.write_text(CUT)
    code = main(["run", str(prog), "--bench", MILL, "--at", spec])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err, err
    assert err.startswith("hil run: --at: ")


def test_bad_events_file_names_file_and_line_and_basic_mlc_is_refused(tmp_path, capsys):
    prog = tmp_path / "p.nc"
    prog.write_text(CUT)
    ev = tmp_path / "ev.txt"
    ev.write_text("t=1:feed-hold\n\nt=2:set Y3\n")
    assert main(["run", str(prog), "--bench", MILL, "--events", str(ev)]) == 2
    assert f"{ev}:3: action 'set Y3'" in capsys.readouterr().err
    assert main(["run", str(prog), "--bench", MILL, "--events", str(tmp_path / "missing.txt")]) == 2
    assert "cannot read events file" in capsys.readouterr().err
    assert main(["run", str(prog), "--bench", MILL, "--mlc", "basic", "--at", "t=1:feed-hold"]) == 2
    assert "need a Delta MLC" in capsys.readouterr().err
