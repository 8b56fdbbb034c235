"""G00 rapid N1.030-N1.032, cutting N1.034/N1.035 and axis rapid N2.020-N2.022 (decisions motion 90-92,
language L26-1).

What a controller engineer checks on the trace of `hil run`: a G00 of 100 mm runs at N1.030, its peak
acceleration is N1.030 / N1.031 and the acceleration builds up in N1.032; a G01 runs with N1.033 / N1.034 and
N1.035; the line's time in simulated time is the jerk-limited profile's T = L/v + v/a + a/j; a G05 group switches
them; neither ever exceeds an axis's own limits; bad values are bench errors naming the file and key.
"""

from __future__ import annotations

import numpy as np
import pytest

from hil.api import run
from hil.bench_file import BenchFileError, parse_bench
from hil.trace_read import TraceFile
from nc.interp import Interpreter
from nc.motion.limits import AxisLimits, MotionConfig, MoveKindLimits
from nc.motion.offline import run as offline_run
from nc.profiles import make_profile
from nc.store import ProgramStore
from tests.motion_helpers import MILL_AXES as AXES, profile_time

# The position filter off, so a line's time and peaks are the raw profile's.
HEAD = 'name = "mill-accel"\nprofile = "nc5-mill"\n[params]\n"N1.036" = 0.0\n"N1.037" = 0.0\n'
PARAMS = """"N1.030" = 12000.0    # G00 200 mm/s
"N1.031" = 50.0       # ms from rest to N1.030: 4000 mm/s²
"N1.032" = 20.0       # ms: jerk 4000 / 0.020 = 200 000 mm/s³
"N1.033" = 6000.0     # cutting 100 mm/s
"N1.034" = 100.0      # ms: 1000 mm/s²
"N1.035" = 20.0       # ms: jerk 50 000 mm/s³
"""
GROUPS = """
[param_groups.1]
"N1.031" = 25.0       # 200 / 0.025 = 8000 mm/s²: above X's own 5000, so 5000
"N1.034" = 50.0       # 100 / 0.05 = 2000 mm/s²
"""
BENCH = HEAD + PARAMS + AXES + GROUPS
PROGRAM = "G90 G00 X100.\nG01 X0 F6000.\nG05 P1\nG00 X100.\nG01 X0\nG05 P0\nG00 X100.\nM30\n"


def _peaks(r, axis: str, lines) -> dict:
    """Per program line: (cycles on it × 1 ms, peak |v|, peak |a|, cycles the acceleration takes from 0 to its
    peak, peak |jerk|) of `axis`'s setpoints."""
    t = r.trace.load(["line", f"{axis}_cmd"]).to_pandas()
    x, line = t[f"{axis}_cmd"].to_numpy(), t.line.to_numpy()
    v = np.diff(x) / 0.001
    a = np.diff(v) / 0.001
    j = np.diff(a) / 0.001
    out = {}
    for n in lines:
        k = np.flatnonzero(line == n)
        lo, hi = k[0] - 1, k[-1]
        acc = np.abs(a[lo:hi - 1])
        ramp = int(np.argmax(acc > 0.99 * acc.max()) - np.argmax(acc > 1e-6))
        out[n] = (len(k) * 0.001, np.abs(v[lo:hi]).max(), acc.max(), ramp, np.abs(j[lo:hi - 2]).max())
    return out


@pytest.fixture(scope="module")
def lines(tmp_path_factory):
    d = tmp_path_factory.mktemp("accel")
    (d / "bench.toml").write_text(BENCH)
    (d / "p.nc").write_text(PROGRAM)
    r = run(str(d / "p.nc"), str(d / "bench.toml"), trace=str(d / "t.parquet"))
    assert r.ok, r.alarms
    out = _peaks(r, "X", (1, 2, 4, 5, 7))
    out["meta"] = TraceFile(d / "t.parquet").meta
    return out


def test_a_g00_runs_at_n1030_with_n1031_acceleration_and_n1032_s_curve(lines):
    t, v, a, ramp, j = lines[1]
    assert v == pytest.approx(200.0, rel=1e-6)  # N1.030 = 12000 mm/min
    assert a == pytest.approx(4000.0, rel=0.002)  # N1.030 / N1.031 = 200 / 0.050: the axis's 5000 not reached
    assert ramp in (19, 20)  # N1.032 = 20 ms from 0 to the peak acceleration
    assert j == pytest.approx(200_000.0, rel=0.002)  # 4000 / 0.020
    assert t == pytest.approx(profile_time(100.0, 200.0, 4000.0, 200_000.0), abs=0.0025)  # 0.570 s


def test_a_g01_runs_with_the_cutting_acceleration_n1034_and_s_curve_n1035(lines):
    t, v, a, ramp, j = lines[2]
    assert v == pytest.approx(100.0, rel=1e-6)
    assert a == pytest.approx(1000.0, rel=0.002)  # N1.033 / N1.034 = 100 / 0.100
    assert ramp in (19, 20)  # N1.035 = 20 ms
    assert j == pytest.approx(50_000.0, rel=0.002)
    assert t == pytest.approx(profile_time(100.0, 100.0, 1000.0, 50_000.0), abs=0.0025)  # 1.120 s


def test_a_g05_group_switches_them_and_the_axis_limits_still_cap(lines):
    t4, v4, a4, ramp4, j4 = lines[4]
    assert a4 == pytest.approx(5000.0, rel=0.002)  # 8000 asked, X's own 5000 in force
    assert j4 == pytest.approx(250_000.0, rel=0.002)  # 5000 / 0.020 = X's own jerk
    assert t4 == pytest.approx(profile_time(100.0, 200.0, 5000.0, 250_000.0), abs=0.0025)  # 0.560 s
    t5, v5, a5, ramp5, j5 = lines[5]
    assert a5 == pytest.approx(2000.0, rel=0.002)  # group 1's N1.034 = 50 ms; N1.035 the bench's 20 ms
    assert j5 == pytest.approx(100_000.0, rel=0.002)
    assert t5 == pytest.approx(profile_time(100.0, 100.0, 2000.0, 100_000.0), abs=0.0025)  # 1.070 s
    assert lines[7][1:4] == lines[1][1:4] and lines[7][0] == pytest.approx(lines[1][0], abs=0.0015)  # G05 P0


def test_the_trace_records_the_parameters_in_force(lines):
    bench = lines["meta"]["bench"]
    assert bench["params"]["N1.031"] == 50.0 and bench["params"]["N1.034"] == 100.0
    assert bench["param_groups"]["1"]["params"] == {"N1.031": 25.0, "N1.034": 50.0}


def _run(tmp_path, bench: str, program: str, axis: str, lines):
    (tmp_path / "bench.toml").write_text(bench)
    (tmp_path / "p.nc").write_text(program)
    r = run(str(tmp_path / "p.nc"), str(tmp_path / "bench.toml"), trace=str(tmp_path / "t.parquet"))
    assert r.ok, r.alarms
    return r, _peaks(r, axis, lines)


def test_without_the_parameters_a_g00_keeps_the_tangential_share(tmp_path):
    """No acc. and dec. or S-curve time: today's planning, half the axis's acceleration (decision motion 71);
    N1.030 alone caps the speed only."""
    _r, p = _run(tmp_path, HEAD + '"N1.030" = 6000.0\n' + AXES, "G90 G00 X100.\nM30\n", "X", (1,))
    t, v, a, _ramp, j = p[1]
    assert v == pytest.approx(100.0, rel=1e-6) and a == pytest.approx(2500.0, rel=0.002)
    assert j == pytest.approx(125_000.0, rel=0.002)
    assert t == pytest.approx(profile_time(100.0, 100.0, 2500.0, 125_000.0), abs=0.0025)


def test_a_cutting_acceleration_time_never_raises_the_cutting_budget(tmp_path):
    """N1.033 / N1.034 = 10 000 mm/s² asks more than a G01's tangential share (2500): the share stays, since
    corners and arcs take the rest of the axis's budget (decision motion 91)."""
    bench = HEAD + '"N1.033" = 6000.0\n"N1.034" = 10.0\n' + AXES
    _r, p = _run(tmp_path, bench, "G90 G01 X100. F6000.\nM30\n", "X", (1,))
    assert p[1][2] == pytest.approx(2500.0, rel=0.002)


def test_an_axis_rapid_speed_and_acceleration_n2020_n2021_hold_each_axis(tmp_path):
    """A diagonal G00: X within its N2.020 X = 100 mm/s and N2.021 X's 2000 mm/s², so Y (the same
    component) too; the path is a line (the composite at 141 mm/s)."""
    bench = HEAD + '"N2.020 X" = 6000.0\n"N2.021 X" = 50.0\n' + AXES
    r, p = _run(tmp_path, bench, "G90 G00 X100. Y100.\nM30\n", "X", (1,))
    t, v, a, _ramp, j = p[1]
    assert v == pytest.approx(100.0, rel=1e-6)
    assert a == pytest.approx(2000.0, rel=0.002)  # 100 / 0.050, the axis's whole budget (a time is given)
    assert j == pytest.approx(250_000.0, rel=0.002)  # no N2.022: X's own jerk
    assert t == pytest.approx(profile_time(100.0, 100.0, 2000.0, 250_000.0), abs=0.0025)
    assert r.run.final["X"] == pytest.approx(100.0, abs=1e-6) and r.run.final["Y"] == pytest.approx(100.0, abs=1e-6)


def test_g00_and_g01_meet_at_rest_and_the_filtered_run_stays_within_the_axis_limits(tmp_path):
    """A junction between a G00 and a G01 (different limits) is a stop (`Limits.junction`: 0 at a rapid's
    either end), with the look-ahead filter on (the bench default 16 + 16 ms) too; the rapid at X's whole
    acceleration passes `[checks] limits` (decision motion 93)."""
    bench = ('name = "mill-accel-f"\nprofile = "nc5-mill"\n[params]\n"N1.030" = 24000.0\n"N1.031" = 20.0\n'
             '"N1.032" = 20.0\n"N1.033" = 6000.0\n"N1.034" = 100.0\n"N1.035" = 20.0\n'
             '[checks]\nlimits = true\n' + AXES)
    prog = "G90 G00 X100.\nG01 X150. Y40. F6000.\nG00 X0 Y0\nM30\n"
    (tmp_path / "bench.toml").write_text(bench)
    (tmp_path / "p.nc").write_text(prog)
    r = run(str(tmp_path / "p.nc"), str(tmp_path / "bench.toml"), trace=str(tmp_path / "t.parquet"))
    assert r.ok, (r.alarms, [c for c in r.checks if not c.ok])
    t = r.trace.load(["line", "X_cmd", "Y_cmd"]).to_pandas()
    pos = np.stack([t.X_cmd.to_numpy(), t.Y_cmd.to_numpy()], axis=1)
    speed = np.hypot(*np.diff(pos, axis=0).T) / 0.001
    line = t.line.to_numpy()[1:]
    at = [0]
    for n, end in ((1, (100.0, 0.0)), (2, (150.0, 40.0))):  # the filtered setpoints pass the vertex at rest:
        k = np.flatnonzero(line == n)[-1]  # no blending of a G00-G01 corner (around the block's last cycle, within
        near = np.hypot(*(pos[k - 40:k + 40] - end).T)  # the filter's 32 ms lag)
        i = int(np.argmin(near))
        assert near[i] < 1e-9 and speed[k - 40 + i - 1:k - 40 + i + 1].max() < 1e-3
        at.append(k - 40 + i)
    acc = np.hypot(*np.diff(np.diff(pos, axis=0), axis=0).T) / 1e-6
    # from rest to rest: the G00 at X's own 5000 (400 / 0.020 = 20 000 asked), the G01 at the cutting 1000
    assert acc[at[0]:at[1]].max() == pytest.approx(5000.0, rel=0.01)
    assert acc[at[1]:at[2]].max() == pytest.approx(1000.0, rel=0.01)


def test_independent_rapids_take_the_axis_rapid_limits():
    """N1.20 bit 18 = 1 (MotionConfig.rapid_independent): each axis on its own N2.020-N2.022 (N§3.3.1)."""
    lim = {a: AxisLimits(500.0, 5000.0, 250000.0) for a in "XYZ"}
    cfg = MotionConfig(axes=("X", "Y", "Z"), limits=lim, rapid_independent=True,
                       axis_rapid={"X": MoveKindLimits(100.0, 0.05, 0.02)})
    store = ProgramStore()
    prog = store.add_text("G90 G00 X100. Y50.\nM30\n")[0]
    st = offline_run(Interpreter(make_profile("nc5-mill"), store=store).run(prog), cfg,
                     {"X": 0.0, "Y": 0.0, "Z": 0.0})
    assert not st.alarms
    v, a, j = st.derivatives()
    assert np.abs(v[:, 0]).max() == pytest.approx(100.0, rel=1e-3)  # N2.020 X
    assert np.abs(a[:, 0]).max() == pytest.approx(2000.0, rel=0.002)  # N2.020 X / N2.021 X
    assert np.abs(j[:, 0]).max() == pytest.approx(100_000.0, rel=0.002)  # 2000 / N2.022 X
    assert np.abs(a[:, 1]).max() == pytest.approx(5000.0, rel=0.002)  # Y: its own limits
    assert st.positions[-1, :2] == pytest.approx([100.0, 50.0], abs=1e-6)


@pytest.mark.parametrize("params,key,says", [
    ('"N1.031" = -5.0\n"N1.030" = 1000.0\n', "params.N1.031", "within [0, 10000]"),
    ('"N1.032" = 2000.0\n', "params.N1.032", "within [0, 1000]"),
    ('"N1.031" = 50.0\n', "params.N1.031", "needs N1.030 > 0"),
    ('"N1.034" = 50.0\n', "params.N1.034", "needs N1.033 > 0"),
    ('"N2.021 X" = 50.0\n', "params.'N2.021 X'", "needs N2.020 X > 0"),
    ('"N2.020 Q" = 5000.0\n', "params.'N2.020 Q'", "no axis 'Q'"),
    ('"N2.020" = 5000.0\n', "params.N2.020", 'name the axis, "N2.020 X"'),
    ('"N1.030" = "fast"\n', "params.N1.030", "must be a number"),
])
def test_bad_values_are_bench_errors_naming_the_file_and_key(params, key, says):
    _refused(HEAD + params + AXES, key, says)


def _refused(text: str, key: str, says: str) -> None:
    """The bench text is a bench error naming the file, the key and what is wrong."""
    with pytest.raises(BenchFileError) as e:
        parse_bench(text, "benches/accel.toml")
    msg = str(e.value)
    assert f"benches/accel.toml: {key}: " in msg and says in msg, msg


@pytest.mark.parametrize("table,key,says", [
    ('[param_groups.2]\n"N1.034" = 50.0\n', "param_groups.2.N1.034", "needs N1.033 > 0"),
    ('[param_groups.2]\n"N2.022 Q" = 5.0\n', "param_groups.2.'N2.022 Q'", "no axis 'Q'"),
    ('[param_groups.2]\n"N1.035" = 5000.0\n', "param_groups.2.N1.035", "within [0, 1000]"),
])
def test_bad_group_values_are_bench_errors_naming_the_key(table, key, says):
    _refused(HEAD + AXES + table, key, says)


def test_a_group_that_takes_away_the_speed_an_acceleration_time_needs_is_refused():
    bench = HEAD + '"N1.030" = 12000.0\n"N1.031" = 50.0\n' + AXES + '[param_groups.3]\n"N1.030" = 0.0\n'
    with pytest.raises(BenchFileError) as e:
        parse_bench(bench, "benches/accel.toml")
    msg = str(e.value)
    assert "benches/accel.toml: param_groups.3: [params] N1.031 under this group: needs N1.030 > 0" in msg, msg


def test_a_group_may_hold_the_axis_rapid_parameters():
    b = parse_bench(HEAD + AXES + '[param_groups.4]\n"N2.020 X" = 6000.0\n"N2.021 X" = 40.0\n', "accel.toml")
    cfg = b.motion_config(4)
    assert cfg.axis_rapid["X"] == MoveKindLimits(100.0, 0.04, None) and "Y" not in cfg.axis_rapid
    assert b.motion_config(0).axis_rapid == {}


def test_the_guides_group_example_is_a_valid_group():
    """docs/guide/bench-file.md's `[param_groups.1]` example, over a bench with "N2.020 X": what it says it does."""
    from tests.conftest import ROOT
    text = (ROOT / "docs" / "guide" / "bench-file.md").read_text()
    snippet = text.split("```toml\n[param_groups.1]", 1)[1].split("```", 1)[0]
    b = parse_bench(HEAD + '"N2.020 X" = 12000.0\n' + AXES + "[param_groups.1]" + snippet, "guide.toml")
    cfg = b.motion_config(1)
    assert cfg.cutting == MoveKindLimits(50.0, 0.2, None)  # N1.033 3000 mm/min, N1.034 200 ms: 250 mm/s²
    assert cfg.axis_rapid["X"] == MoveKindLimits(200.0, 0.08, None)


@pytest.mark.parametrize("program,params,peak", [
    ("G90 G00 X30.\nM30\n", '"N1.030" = 3000.0\n"N1.031" = 100.0\n', 500.0),  # 50 mm/s / 0.1 s
    ("G90 G01 X30. F3000.\nM30\n", '"N1.033" = 3000.0\n"N1.034" = 100.0\n', 500.0),
    ("G90 G00 X30.\nM30\n", '"N1.030" = 3000.0\n"N1.031" = 25.0\n', 2000.0),  # 50 mm/s / 0.025 s
    ("G90 G01 X30. F3000.\nM30\n", '"N1.033" = 3000.0\n"N1.034" = 25.0\n', 2000.0),
])
def test_under_the_look_ahead_filter_the_acceleration_time_still_holds(tmp_path, program, params, peak):
    """With the bench's default filter (16 + 16 ms) a start or stop from rest is otherwise a velocity step the
    filter shapes (nc.motion.filter_ramps: 50 mm/s over 16 ms, 3125 mm/s²): under an acc. and dec. time the
    move ramps at its own acceleration, which the filter only smooths (decision motion 94): without that the
    2000 mm/s² cases peaked at 3035."""
    bench = 'name = "mill-accel-f"\nprofile = "nc5-mill"\n[params]\n' + params + AXES
    _r, p = _run(tmp_path, bench, program, "X", (1,))
    t, v, a, _ramp, _j = p[1]
    assert v == pytest.approx(50.0, rel=1e-6)
    # the filter's averages round a short plateau off (2000: 9 ms at it between 16 ms jerk phases), never more
    assert 0.9 * peak <= a <= 1.002 * peak
    assert t >= 30.0 / 50.0 + 50.0 / peak  # at least L/v + v/a


def test_a_campaign_sweep_of_a_time_without_its_speed_is_refused_naming_the_key():
    """A `[params]` sweep applies over the bench file (hil/campaign/variant.py): the sweep's N1.034 over a bench
    without N1.033 is the bench error the file would give, not a G01 planned without a cutting acceleration."""
    from types import SimpleNamespace

    from hil.campaign.variant import apply_variant

    case = SimpleNamespace(bus="sim", params=(("N1.034", 50.0),), events=())
    with pytest.raises(BenchFileError) as e:
        apply_variant(HEAD + AXES, "benches/accel.toml", case, None, None)
    assert "benches/accel.toml with the campaign's [params]: params.N1.034: needs N1.033 > 0" in str(e.value)
    ok = SimpleNamespace(bus="sim", params=(("N1.033", 3000.0), ("N1.034", 50.0)), events=())
    assert apply_variant(HEAD + AXES, "benches/accel.toml", ok, None, None).motion_config().cutting.acc_time == 0.05
