"""Issue 15, inputs at the boundary: bench values, interface names, bad traces, atomic reports.

Every case runs `hil` as a user would and asserts the exit code and that the message names the file
and the field; none may end in a traceback or an internal error."""
from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from fieldbus.factory import parse_bus
from hil.bench_file import BenchFileError, parse_bench

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "hil" / "shipped" / "benches" / "lathe-2axis.toml"
PROGRAM = ROOT / "examples" / "lathe_demo.nc"
LONG_IFACE = "e" * 60  # pysoem 1.x segfaults on this (heap corruption in SOEM's name copy)


def hil(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "hil.cli", *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=120)


def assert_clean(p: subprocess.CompletedProcess, code: int, *needles: str) -> None:
    out = p.stdout + p.stderr
    assert p.returncode == code, out
    assert "Traceback" not in out and "internal error" not in out.lower(), out
    for n in needles:
        assert n in out, out


def bench_with(tmp_path: Path, *subs: tuple[str, str]) -> Path:
    text = BENCH.read_text()
    for old, new in subs:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "bench.toml"
    path.write_text(text)
    return path


# --- item 1: bench validation ------------------------------------------------------------------------

def test_param_typo_suggests_the_manual_name(tmp_path):
    b = bench_with(tmp_path, ('"N1.040" = 0.01', '"N1.O40" = 0.01'))
    assert_clean(hil("run", str(PROGRAM), "--bench", str(b)), 2, str(b), "params.N1.O40",
                 "did you mean N1.040?")


@pytest.mark.parametrize("line, field, says", [
    ('"max blocks" = 0', "params.'max blocks'", "endless-loop guard"),
    ('"macro statements per cycle" = 1e300', "params.'macro statements per cycle'", "must be within"),
    ('"N1.040" = -1.0', "params.N1.040", "must be within [0, 10]"),
    ('"N1.040" = nan', "params.N1.040", "finite"),
])
def test_param_values_in_documented_range(tmp_path, line, field, says):
    b = bench_with(tmp_path, ('"N1.040" = 0.01', line))
    with pytest.raises(BenchFileError) as e:
        parse_bench(b.read_text(), str(b))
    assert f"{field}: " in str(e.value) and says in str(e.value), str(e.value)


@pytest.mark.parametrize("old, new, field", [
    ("jerk = 150000.0", "jerk = 1e200", "axes[0].limits.jerk"),
    ("acceleration = 3000.0", "acceleration = 1e-50", "axes[0].limits.acceleration"),
    ("velocity = 300.0", "velocity = inf", "axes[0].limits.velocity"),
    ("soft_limits = [-5.0, 200.0]", "soft_limits = [-inf, inf]", "axes[0].soft_limits"),
])
def test_implausible_bench_numbers_refused_naming_the_field(tmp_path, old, new, field):
    b = bench_with(tmp_path, (old, new))
    with pytest.raises(BenchFileError) as e:
        parse_bench(b.read_text(), str(b))
    assert str(b) in str(e.value) and f"{field}: " in str(e.value), str(e.value)


def test_implausible_bench_exits_2_from_hil_run(tmp_path):
    b = bench_with(tmp_path, ("jerk = 150000.0", "jerk = 1e200"))
    assert_clean(hil("run", str(PROGRAM), "--bench", str(b)), 2, str(b), "axes[0].limits.jerk")


# --- item 2: interface names -------------------------------------------------------------------------

def test_long_interface_name_crashes_pysoem_unguarded():
    """The reason for the check: SOEM copies the name unchecked and the process dies (SIGSEGV)."""
    pytest.importorskip("pysoem")
    p = subprocess.run([sys.executable, "-c", f"import pysoem; pysoem.Master().open({LONG_IFACE!r})"],
                       capture_output=True, timeout=60)
    assert p.returncode != 0


@pytest.mark.parametrize("args", [
    ("scan", "--bus", f"ethercat:{LONG_IFACE}"),
    ("run", str(PROGRAM), "--bench", str(BENCH), "--bus", f"ethercat:{LONG_IFACE}"),
    ("servo", "get", "X", "P1-01", "--bench", str(BENCH), "--bus", f"ethercat:{LONG_IFACE}"),
])
def test_invalid_interface_refused_before_pysoem(args):
    assert_clean(hil(*args), 2, "interface name")


@pytest.mark.parametrize("name", ["eth 0", "../eth0", "a" * 16, "..", "eth\x07"])
def test_interface_name_rules(name):
    with pytest.raises(ValueError, match="interface name"):
        parse_bus(f"ethercat:{name}")
    assert parse_bus("ethercat:enp3s0").interface == "enp3s0" and parse_bus("ethercat:" + "a" * 15)


def test_bench_bus_with_invalid_interface(tmp_path):
    b = bench_with(tmp_path, ('bus = "sim"', f'bus = "ethercat:{LONG_IFACE}"'))
    assert_clean(hil("run", str(PROGRAM), "--bench", str(b)), 2, str(b), "bus: ", "at most 15")


# --- bounded property test: a mutated shipped bench is refused with a field name ------------------------

_NUMBER_LINES = [("counts_per_rev = 1280000", "counts_per_rev = {v}"), ("lead = 5.0", "lead = {v}"),
                 ("cycle_ms = 1.0", "cycle_ms = {v}"), ("jerk = 150000.0", "jerk = {v}"),
                 ("acceleration = 3000.0", "acceleration = {v}"), ("velocity = 300.0", "velocity = {v}"),
                 ('"N1.040" = 0.01', '"N1.040" = {v}'), ("soft_limits = [-5.0, 200.0]", "soft_limits = [{v}, 200.0]")]
_BAD = st.sampled_from(["inf", "-inf", "nan", "-1.0", "1e300", "-1e300", "1e-300", "0"])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_NUMBER_LINES), _BAD), min_size=1, max_size=3),
       st.sampled_from(["", "N1.O40", "N1.04O", "max block", "N8.018 bit10"]))
def test_mutated_bench_never_crashes(mutations, typo):
    text = BENCH.read_text()
    changed = False
    for (old, new), v in mutations:
        if old in text:
            text, changed = text.replace(old, new.format(v=v), 1), True
    if typo:
        text = text.replace('"N1.040" =', f'"{typo}" =', 1)
    try:
        b = parse_bench(text, "mutated.toml")
    except BenchFileError as exc:
        msg = str(exc)
        assert "mutated.toml" in msg and ": " in msg
        return
    # Accepted: every number the bench carries must then be finite and the typo must not have passed.
    assert not typo
    for a in b.axes:
        for v in (a.limits.max_velocity, a.limits.max_acceleration, a.limits.max_jerk, a.scaling.lead, a.start):
            assert math.isfinite(v) and abs(v) < 1e12


# --- item 3: bad traces ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def good_trace(tmp_path_factory) -> Path:
    """A real trace: 0.3 s of the demo program (max_time ends it: exit 1, the trace is complete)."""
    d = tmp_path_factory.mktemp("trace")
    bench = d / "bench.toml"
    bench.write_text(BENCH.read_text().replace("cycle_ms = 1.0", "cycle_ms = 1.0\nmax_time = 0.3"))
    p = hil("run", str(PROGRAM), "--bench", str(bench), "--trace", str(d / "good.parquet"))
    assert p.returncode in (0, 1), p.stderr
    return d / "good.parquet"


def _bad_traces(good: Path) -> dict[str, tuple[Path, str]]:
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    d, t = good.parent, pq.read_table(good)
    out: dict[str, tuple[Path, str]] = {}

    def put(name: str, table: pa.Table, says: str) -> None:
        pq.write_table(table, d / name)
        out[name] = (d / name, says)
    put("strt.parquet", t.set_column(0, "t", t["t"].cast(pa.string())), "column 't' must hold numbers")
    put("strsw.parquet", t.set_column(t.column_names.index("X_sw"), "X_sw", t["X_sw"].cast(pa.string())),
        "column 'X_sw' must hold numbers")
    put("noline.parquet", t.drop(["line"]), "no 't' and 'line' columns")
    raw = bytearray(good.read_bytes())
    for i in range(200, len(raw) // 2, 97):
        raw[i] ^= 0x5A
    (d / "corrupt.parquet").write_bytes(bytes(raw))
    out["corrupt.parquet"] = (d / "corrupt.parquet", "trace")
    (d / "empty.parquet").write_bytes(b"")
    out["empty.parquet"] = (d / "empty.parquet", "not a readable trace")
    (d / "garbage.csv").write_text("t,line,X_cmd\n0.001,1,abc\n\x00zz,,\n")
    out["garbage.csv"] = (d / "garbage.csv", "damaged trace")
    return out


@pytest.mark.parametrize("command", ["check", "report", "trace"])
def test_bad_traces_exit_2_naming_file(good_trace, tmp_path, command):
    bad = _bad_traces(good_trace)
    names = list(bad) if command == "check" else ["strt.parquet", "corrupt.parquet"]  # same reader: keep CI short
    for name in names:
        path, says = bad[name]
        args = {"check": ("check", str(path), "--bench", str(BENCH), "--max-ferr", "1"),
                "report": ("report", str(path), "--out", str(tmp_path / f"rep_{name}")),
                "trace": ("trace", str(path), "--out", str(tmp_path / f"{name}.csv"))}[command]
        p = hil(*args)
        assert_clean(p, 2, name, says)
        assert "0x0000" not in p.stdout + p.stderr


@settings(max_examples=25, deadline=None)
@given(st.dictionaries(st.sampled_from(["t", "line", "cycle", "X_cmd", "X_act", "X_sw", "alarm", "junk"]),
                       st.sampled_from(["int", "float", "str", "nan"]), max_size=6))
def test_random_trace_tables_never_internal_error(tmp_path_factory, cols):
    """Random column sets and types: a TraceReadError with the file name, or a readable table."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from hil.trace_read import TraceFile, TraceReadError
    make = {"int": pa.array([1, 2, 3]), "float": pa.array([0.0, 0.001, 0.002]), "str": pa.array(["a", "b", "c"]),
            "nan": pa.array([float("nan")] * 3)}
    path = tmp_path_factory.mktemp("rnd") / "rnd.parquet"
    pq.write_table(pa.table({c: make[k] for c, k in cols.items()}) if cols else pa.table({}), path)
    try:
        TraceFile(path).arrays()
    except TraceReadError as exc:
        assert "rnd.parquet" in str(exc)


# --- item 5: hil report is all or nothing -------------------------------------------------------------------

def test_failing_report_leaves_the_earlier_one_untouched(good_trace, tmp_path, monkeypatch):
    import hil.report as report
    from hil.trace_read import TraceReadError

    out = tmp_path / "rep"
    assert_clean(hil("report", str(good_trace), "--out", str(out)), 0, "index.html")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "notes.txt").write_text("mine")
    real = report.trace_figures

    def dies_midway(*a, **k):  # the trace's damage shows after the first figure was drawn
        it = iter(real(*a, **k))
        yield next(it)
        raise TraceReadError(f"{good_trace}: damaged trace (page 3)")
    monkeypatch.setattr(report, "trace_figures", dies_midway)
    import pyarrow.parquet as pq
    half = tmp_path / "half.parquet"  # another trace, so its first figure differs from the old one
    t = pq.read_table(good_trace)
    pq.write_table(t.slice(0, t.num_rows // 2), half)
    with pytest.raises(TraceReadError):
        report.write_report(half, out)
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.name != "notes.txt"}
    assert after == before  # same files, same bytes; no temporary folder left
    assert (out / "notes.txt").read_text() == "mine"


# --- item 4: a bench with [checks] whose bus never opens -----------------------------------------------------

def test_checks_bench_whose_bus_never_opens(tmp_path):
    """The shipped bench has [checks]; on a bus that cannot open, the bus alarm is the result (exit 1),
    not an internal error from judging an empty trace."""
    b = bench_with(tmp_path, ('bus = "sim"', 'bus = "ethercat:nope0"'))
    p = hil("run", str(PROGRAM), "--bench", str(b), "--no-progress")
    assert_clean(p, 1, "ALARM")
    assert "0x0000" not in p.stdout + p.stderr
