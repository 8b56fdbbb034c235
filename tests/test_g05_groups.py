"""G05 P1-P20 parameter groups take effect (N§3.8.2; decision language L25-1).

The same 100 mm X line at F6000 runs with the bench's settings, after `G05 Pn` with group n's, and after
`G05 P0` with the bench's again. What a user checks on the trace: each line's peak tangential acceleration
(the tangential share 0.5 of the axis acceleration), its speed (N1.033 limits the programmed feed) and its time,
against the jerk-limited profile's own T = L/v + v/a + a/j (a, j the tangential budgets), in simulated time.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.api import run
from hil.bench_file import BenchFileError, parse_bench
from hil.cli import main
from hil.trace_read import TraceFile
from nc.interp import Interpreter
from nc.motion.limits import AxisLimits, MotionConfig
from nc.motion.offline import run as offline_run
from nc.profiles import make_profile
from nc.store import ProgramStore
from tests.motion_helpers import MILL_AXES, profile_time

# The mill bench with the position filter off (so a line's time is the raw profile's), and four groups.
BENCH = """
name = "mill-g05"
profile = "nc5-mill"
[params]
"N1.036" = 0.0
"N1.037" = 0.0
""" + MILL_AXES + """
[param_groups.1]                      # a lower X acceleration: the rest (filter off, no feed limit) the bench's
limits.X = { acceleration = 2000.0 }

[param_groups.2]                      # N1.033 cutting command maximum feed
"N1.033" = 1200.0

[param_groups.3]                      # the look-ahead filter on: 16 ms + 16 ms
"N1.036" = 16.0
"N1.037" = 16.0
"""
PROGRAM = ("G90 G01 X100. F6000.\nG05 P1\nX0\nG05 P0\nX100.\nG05 P2\nX0\nG05 P3\nX100.\nG05 P0\nX0\nM30\n")
V, J = 100.0, 0.5 * 250000.0  # F6000 in mm/s; the tangential jerk budget of X


@pytest.fixture(scope="module")
def lines(tmp_path_factory):
    """Per program line: (cycles on it × 1 ms, peak |v| mm/s, peak |a| mm/s², cycles the acceleration takes from
    0 to its peak) of X's setpoints."""
    d = tmp_path_factory.mktemp("g05")
    (d / "bench.toml").write_text(BENCH)
    (d / "p.nc").write_text(PROGRAM)
    r = run(str(d / "p.nc"), str(d / "bench.toml"), trace=str(d / "t.parquet"))
    assert r.ok, r.alarms
    t = r.trace.load(["line", "X_cmd"]).to_pandas()
    x, line = t.X_cmd.to_numpy(), t.line.to_numpy()
    v = np.diff(x) / 0.001
    a = np.diff(v) / 0.001
    out = {}
    for n in (1, 3, 5, 7, 9, 11):
        k = np.flatnonzero(line == n)
        lo, hi = k[0] - 1, k[-1]  # the differences over the line's cycles (and the step into its first)
        acc = np.abs(a[lo:hi - 1])
        ramp = int(np.argmax(acc > 0.99 * acc.max()) - np.argmax(acc > 1e-6))
        out[n] = (len(k) * 0.001, np.abs(v[lo:hi]).max(), acc.max(), ramp)
    out["meta"] = TraceFile(d / "t.parquet").meta
    return out


def test_a_group_acceleration_takes_effect_from_g05_and_p0_restores_the_bench(lines):
    t1, v1, a1, _ = lines[1]
    t3, v3, a3, _ = lines[3]
    assert a1 == pytest.approx(2500.0, rel=0.002)  # 0.5 × the bench's 5000 mm/s²
    assert a3 == pytest.approx(1000.0, rel=0.002)  # 0.5 × group 1's 2000 mm/s²
    assert v1 == pytest.approx(V, rel=1e-6) and v3 == pytest.approx(V, rel=1e-6)
    assert t1 == pytest.approx(profile_time(100.0, V, 2500.0, J), abs=0.0025)  # 1.060 s
    assert t3 == pytest.approx(profile_time(100.0, V, 1000.0, J), abs=0.0025)  # 1.108 s
    assert lines[5][:3] == lines[1][:3] and lines[11][:3] == lines[1][:3]  # G05 P0: the bench's settings again


def test_a_group_feed_limit_n1033_caps_the_programmed_feed(lines):
    t7, v7, a7, _ = lines[7]
    assert v7 == pytest.approx(1200.0 / 60.0, rel=1e-6)  # F6000 limited to N1.033 = 1200 mm/min
    assert t7 == pytest.approx(profile_time(100.0, 20.0, 2500.0, J), abs=0.0025)  # 5.028 s
    assert lines[9][1] == pytest.approx(V, rel=1e-6)  # group 3 does not set N1.033: the bench's (none)


def test_a_group_filter_takes_effect(lines):
    """Group 3's 16 + 16 ms moving averages (N1.036/N1.037): the acceleration that rises in a/j = 20 ms without
    the filter rises over the windows too, and the line lasts longer by the time the filter takes to settle."""
    t1, _, _, ramp1 = lines[1]
    t9, v9, a9, ramp9 = lines[9]
    assert ramp1 in (19, 20) and lines[11][3] == ramp1  # 2500 / 125 000 s without the filter (the bench's, P0)
    assert 30 <= ramp9 <= 20 + 16 + 1
    assert v9 == pytest.approx(V, rel=1e-6) and a9 == pytest.approx(2500.0, rel=0.002)
    assert 0.010 <= t9 - t1 <= 0.034


def test_the_trace_records_the_groups(lines):
    groups = lines["meta"]["bench"]["param_groups"]
    assert groups["1"] == {"params": {}, "limits": {"X": {"acceleration": 2000.0}}}
    assert groups["2"]["params"] == {"N1.033": 1200.0}


def _run_text(tmp_path, program: str, bench: str = BENCH):
    (tmp_path / "bench.toml").write_text(bench)
    (tmp_path / "p.nc").write_text(program)
    return run(str(tmp_path / "p.nc"), str(tmp_path / "bench.toml"))


def test_an_undefined_group_is_0x120d_at_the_g05_block_after_the_motion_before_it(tmp_path):
    r = _run_text(tmp_path, "G90 G01 X10. F3000.\nG05 P4\nX0\nM30\n")
    assert [a.code_text for a in r.alarms] == ["0x120D"]
    al = r.alarms[0]
    assert (al.line, al.block) == (2, "G05 P4") and "param_groups.4" in al.message
    assert r.run.final["X"] == pytest.approx(10.0, abs=1e-6)  # the line before ran out; X0 never started


def test_a_bench_without_groups_runs_g05_p0_and_alarms_on_p1(tmp_path):
    plain = BENCH.split("[param_groups.1]")[0]
    ok = _run_text(tmp_path, "G05 P0\nG90 G01 X10. F3000.\nM30\n", plain)
    assert ok.ok and ok.run.final["X"] == pytest.approx(10.0, abs=1e-6)
    bad = _run_text(tmp_path, "G05 P1\nG90 G01 X10. F3000.\nM30\n", plain)
    assert [a.code_text for a in bad.alarms] == ["0x120D"] and bad.run.final["X"] == pytest.approx(0.0)


def test_p_outside_0_20_keeps_its_argument_alarm(tmp_path):
    r = _run_text(tmp_path, "G05 P21\nM30\n")
    assert [a.code_text for a in r.alarms] == ["0x0243"]


def test_n1033_in_params_limits_the_feed_from_the_start(tmp_path):
    bench = BENCH.replace('"N1.037" = 0.0\n', '"N1.037" = 0.0\n"N1.033" = 3000.0\n', 1)
    r = _run_text(tmp_path, "G90 G01 X50. F6000.\nM30\n", bench)
    assert r.ok
    # 50 mm at 50 mm/s (the limit, not F6000's 100 mm/s): 1.04 s (F6000 would take 0.56 s)
    assert r.run.program_time == pytest.approx(profile_time(50.0, 50.0, 2500.0, J), abs=0.003)


def test_the_channel_switches_the_planner_at_rest():
    """Through the channel alone (nc.motion.offline): the planner after G05 P1 has group 1's settings, after
    G05 P0 the original object again; the position stream is continuous across both switches."""
    lim = {a: AxisLimits(500.0, 5000.0, 250000.0) for a in "XYZ"}
    cfg0 = MotionConfig(axes=("X", "Y", "Z"), limits=lim)
    cfg1 = MotionConfig(axes=("X", "Y", "Z"), limits={**lim, "X": AxisLimits(500.0, 2000.0, 250000.0)})
    store = ProgramStore()
    prog = store.add_text("G90 G01 X100. F6000.\nG05 P1\nX0\nG05 P0\nX100.\nM30\n")[0]
    it = Interpreter(make_profile("nc5-mill"), store=store)
    seen: dict[int, set] = {}

    def on_cycle(n, ch):
        seen.setdefault(ch.planner.line, set()).add(id(ch.planner.cfg))

    st = offline_run(it.run(prog), cfg0, {"X": 0.0, "Y": 0.0, "Z": 0.0}, on_cycle=on_cycle, param_groups={1: cfg1})
    assert not st.alarms
    assert seen[3] == {id(cfg1)} and seen[5] == {id(cfg0)}
    _v, a, _j = st.derivatives()
    assert np.abs(a[:, 0]).max() == pytest.approx(2500.0, rel=0.002)
    x = st.positions[:, 0]
    on3 = np.flatnonzero(st.lines == 3)
    assert np.abs(np.diff(np.diff(x[on3[0] - 1:on3[-1] + 1]))).max() / 1e-6 == pytest.approx(1000.0, rel=0.002)


@pytest.mark.parametrize("table,key,says", [
    ('[param_groups.0]\n"N1.036" = 1.0\n', "param_groups.0", "numbered 1-20"),
    ("[param_groups.21]\n", "param_groups.21", "numbered 1-20"),
    ('[param_groups.2]\n"N1.040" = 0.1\n', "param_groups.2.N1.040", "G05 does not switch N1.040"),
    ('[param_groups.2]\n"N2.024 X" = 100\n', "param_groups.2.'N2.024 X'", "limits.<axis>.acceleration"),
    ('[param_groups.2]\n"N1.O36" = 3\n', "param_groups.2.N1.O36", "did you mean N1.036"),
    ('[param_groups.2]\n"N1.036" = 5000\n', "param_groups.2.N1.036", "within [0, 1000]"),
    ("[param_groups.2]\nlimits.Q = { velocity = 1.0 }\n", "param_groups.2.limits.Q", "no axis 'Q'"),
    ("[param_groups.2]\nlimits.X = { acceleration = 9000.0 }\n", "param_groups.2.limits.X.acceleration",
     "above the axis's own limit 5000"),
    ("[param_groups.2]\nlimits.X = { speed = 1.0 }\n", "param_groups.2.limits.X.speed", "unknown key"),
])
def test_a_bad_group_is_a_bench_error_naming_the_file_and_key(table, key, says):
    text = BENCH.split("[param_groups.1]")[0] + table
    with pytest.raises(BenchFileError) as e:
        parse_bench(text, "benches/g05.toml")
    msg = str(e.value)
    assert f"benches/g05.toml: {key}: " in msg and says in msg


def test_hil_run_reports_a_bad_group_as_a_bench_error(tmp_path, capsys):
    (tmp_path / "b.toml").write_text(BENCH.split("[param_groups.1]")[0] + '[param_groups.3]\n"N2.024 X" = 50\n')
    (tmp_path / "p.nc").write_text("M30\n")
    assert main(["run", str(tmp_path / "p.nc"), "--bench", str(tmp_path / "b.toml")]) == 2
    err = capsys.readouterr().err
    assert "param_groups.3.'N2.024 X': G05 switches N2.024" in err and "Traceback" not in err


def test_hil_run_says_which_group_the_motion_used_from_where(tmp_path, capsys):
    (tmp_path / "b.toml").write_text(BENCH)
    (tmp_path / "p.nc").write_text("G90 G01 X10. F3000.\nG05 P2\nX0\nG05 P0\nX5.\nM30\n")
    assert main(["run", str(tmp_path / "p.nc"), "--bench", str(tmp_path / "b.toml")]) == 0
    assert "parameter groups  G05 P2 at line 2, G05 P0 at line 4\n" in capsys.readouterr().out
    assert main(["run", str(tmp_path / "p.nc"), "--bench", str(tmp_path / "b.toml"), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["param_groups"] == [{"line": 2, "group": 2}, {"line": 4, "group": 0}]
