"""Bench files: every bad field is named; the shipped example benches load and run."""

from pathlib import Path

import pytest

from hil.bench_file import BenchFileError, parse_bench, load_bench_file
from hil.cli import main

BENCHES = Path(__file__).resolve().parent.parent / "benches"

GOOD = '''
name = "t"
profile = "nc5-lathe-a"
cycle_ms = 1.0
bus = "sim"
[[axes]]
name = "X"
lead = 5.0
start = 10.0
[[axes]]
name = "Z"
'''


def err(text: str) -> str:
    with pytest.raises(BenchFileError) as exc:
        parse_bench(text, "bench.toml")
    return str(exc.value)


@pytest.mark.parametrize("extra, expected", [
    ('[[axes]]\nname = "Y"\ncounts_per_rev = -5\n', "bench.toml: axes[2].counts_per_rev: must be a positive integer, got -5"),
    ('[[axes]]\nname = "Y"\ncounts_per_rev = 1.5\n', "axes[2].counts_per_rev: must be a positive integer, got 1.5"),
    ('[[axes]]\nname = "Y"\nratio = [1, 0]\n', "axes[2].ratio: must be an array of two positive integers"),
    ('[[axes]]\nname = "Y"\nlead = 0\n', "axes[2].lead: must be a positive number, got 0"),
    ('[[axes]]\nname = "Y"\nunits = "inch"\n', "axes[2].units: must be one of 'mm', 'deg', got 'inch'"),
    ('[[axes]]\nname = "Y"\ndirection = 2\n', "axes[2].direction: must be one of 1, -1, got 2"),
    ('[[axes]]\nname = "Y"\nstart = "zero"\n', "axes[2].start: must be a number, got 'zero'"),
    ('[[axes]]\nname = "Y"\nsoft_limits = [5.0, 1.0]\n', "axes[2].soft_limits: lower limit must be below the upper"),
    ('[[axes]]\nname = "Y"\nstart = 50.0\nsoft_limits = [0.0, 10.0]\n', "axes[2].start: 50 lies outside soft_limits"),
    ('[[axes]]\nname = "Y"\nlimits = { velocity = -1.0 }\n', "axes[2].limits.velocity: must be a positive number"),
    ('[[axes]]\nname = "Y"\nlimits = { acceleration = true }\n', "axes[2].limits.acceleration: must be a number, got true"),
    ('[[axes]]\nname = "Y"\nlimits = { jerk = 0 }\n', "axes[2].limits.jerk: must be a positive number"),
    ('[[axes]]\nname = "Y"\nlimits = { speed = 1.0 }\n', "axes[2].limits.speed: unknown key"),
    ('[[axes]]\nname = "Y"\ndrive = { kp = -3.0 }\n', "axes[2].drive.kp: must be a positive number"),
    ('[[axes]]\nname = "Y"\ndrive = { gain = 3.0 }\n', "axes[2].drive.gain: unknown key"),
    ('[[axes]]\nname = "Q"\n', "axes[2].name: must be one axis letter of XYZABCUVW, got 'Q'"),
    ('[[axes]]\nname = "X"\n', "axes[2].name: duplicate axis name 'X'"),
    ('[[axes]]\nlead = 5.0\n', "axes[2].name: missing"),
    ('[[axes]]\nname = "Y"\ncountsperrev = 5\n', "axes[2].countsperrev: unknown key"),
    ('[[spindles]]\nname = "S1"\nmax_rpm = -10\n', "spindles[0].max_rpm: must be a positive number"),
    ('[[spindles]]\nname = "spindle"\n', "spindles[0].name: must be S1, S2, ..., got 'spindle'"),
    ('[realtime]\npriority = 120\n', "realtime.priority: must be at most 99, got 120"),
    ('[realtime]\noverrun = "ignore"\n', "realtime.overrun: must be one of 'warn', 'alarm', got 'ignore'"),
    ('[realtime]\ncpu = -1\n', "realtime.cpu: must be at least 0, got -1"),
    ('[realtime]\nlockstep = "rr"\n', "realtime.lockstep: must be one of 'default', 'fifo', got 'rr'"),
    ('[realtime]\nlockstep = true\n', "realtime.lockstep: must be a non-empty string, got true"),
    ('[realtime]\nlock_step = "fifo"\n', "realtime.lock_step: unknown key"),
    ('[checks]\nmax_following_error = { Y = 0.1 }\n', "checks.max_following_error.Y: no axis 'Y' on this bench"),
    ('[checks]\nmax_following_error = -1\n', "checks.max_following_error: must be a positive number"),
    ('[checks]\ncontour_error = "small"\n', "checks.contour_error: must be a number, got 'small'"),
    ('[checks]\njitter_p99_us = 0\n', "checks.jitter_p99_us: must be a positive number"),
    ('[checks]\nlimits = 1\n', "checks.limits: must be true or false, got 1"),
    ('[checks]\nfollowing = 1\n', "checks.following: unknown key"),
    ('[params]\n"N1.040" = "x"\n', "params.N1.040: must be a number"),
])
def test_each_bad_field_is_named(extra, expected):
    assert expected in err(GOOD + extra)


@pytest.mark.parametrize("line, expected", [
    ('profile = "nc5-lathe-z"', "profile: must be one of 'nc5-lathe-a'"),
    ('cycle_ms = 0', "cycle_ms: must be at least 0.125, got 0"),
    ('cycle_ms = 500', "cycle_ms: must be at most 100, got 500"),
    ('bus = "profibus"', "bus: unknown bus 'profibus'"),
    ('bus = "ethercat"', "bus: EtherCAT bus needs an interface"),
    ('max_time = -1', "max_time: must be a positive number"),
    ('lookahead = 0', "lookahead: must be a positive integer, got 0"),
    ('lookahead = 12.5', "lookahead: must be a positive integer, got 12.5"),
    ('name = 5', "name: must be a non-empty string, got 5"),
    ('colour = "red"', "bench.toml: colour: unknown key"),
])
def test_top_level_fields(line, expected):
    text = GOOD.replace('name = "t"\nprofile = "nc5-lathe-a"\ncycle_ms = 1.0\nbus = "sim"', "")
    assert expected in err(line + "\n" + text)


def test_all_errors_reported_at_once_and_bad_toml():
    msg = err(GOOD + '[[axes]]\nname = "Y"\ncounts_per_rev = -5\nlead = -1\n')
    assert "axes[2].counts_per_rev" in msg and "axes[2].lead" in msg
    assert "not valid TOML" in err("name = \n")
    assert "axes: missing" in err('name = "x"\n')
    assert "needs X, Y and Z axes" in err(GOOD.replace("nc5-lathe-a", "nc5-mill"))


def test_good_bench_builds_scaling_and_limits():
    b = parse_bench(GOOD + '[[axes]]\nname = "C"\nunits = "deg"\nratio = [3, 1]\nlimits = { velocity = 720.0 }\n'
                    '[checks]\nmax_following_error = 0.02\n[realtime]\noverrun = "alarm"\nbusy_wait_us = 50\n')
    assert b.axis_names == ("X", "Z", "C")
    c = b.axes[2]
    assert c.units == "deg" and c.scaling.lead == 360.0 and c.scaling.gear_motor == 3
    assert c.scaling.counts_per_unit == pytest.approx(1_280_000 * 3 / 360.0)
    assert c.limits.max_velocity == 720.0
    assert b.axes[0].start == 10.0 and b.axes[0].scaling.lead == 5.0
    assert b.checks.max_following_error == {"X": 0.02, "Z": 0.02, "C": 0.02}
    assert b.realtime.overrun == "alarm" and b.realtime.busy_wait == pytest.approx(50e-6)
    assert b.realtime.lockstep == "default"  # a lock-step run is scheduled as any process unless asked
    placed = parse_bench(GOOD + '[realtime]\nlockstep = "fifo"\ncpu = 1\npriority = 40\n').realtime
    assert (placed.lockstep, placed.cpu, placed.priority) == ("fifo", 1, 40)


@pytest.mark.parametrize("name, axes", [("lathe-2axis", ("X", "Z")), ("mill-3axis", ("X", "Y", "Z")),
                                        ("lathe-c-axis", ("X", "Z", "C"))])
def test_example_benches_load(name, axes):
    b = load_bench_file(BENCHES / f"{name}.toml")
    assert b.axis_names == axes and b.bus == "sim" and b.checks.any


def test_cli_bad_bench_exits_2_naming_the_field(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(GOOD + '[[axes]]\nname = "Y"\ncounts_per_rev = -5\n')
    prog = tmp_path / "p.nc"
    prog.write_text("G98\nG01 Z-1. F100.\nM30\n")
    assert main(["run", str(prog), "--bench", str(bad)]) == 2
    assert f"{bad}: axes[2].counts_per_rev: must be a positive integer, got -5" in capsys.readouterr().err


def test_lookahead_depth_from_the_bench_file_bounds_the_queue():
    """`lookahead = 6`: the planner never holds more than 6 blocks (the D3x320 count the MLC sees)
    and the program still ends where it must; by default the depth follows the limits (≥ 100)."""
    from tests.conftest import run_counting_queue

    assert parse_bench(GOOD, "b.toml").motion_config().lookahead_depth() >= 100
    bench = parse_bench(GOOD.replace('bus = "sim"', 'bus = "sim"\nlookahead = 6'), "b.toml")
    assert bench.motion_config().lookahead_depth() == 6
    zs = [f"G01 Z{-0.5 * k:.1f} F600." for k in range(1, 41)]
    runner, result, seen = run_counting_queue(bench, "G98\nG00 X20. Z0.\n" + "\n".join(zs) + "\nM30\n")
    assert result.ok
    assert max(seen) == 6
    assert runner.channel.planner.position.tolist() == pytest.approx([10.0, -20.0])
