"""What a `hil run` imports (issue 17: the user times the whole process, imports included): the scipy.special
package (≈ 0.17 s) is not imported for the corner blends' Fresnel integrals, whose values stay scipy's (bench
decision B47), and a Parquet trace does not import pandas (≈ 0.17 s), its columns the same (B48)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

ROOT = Path(__file__).resolve().parent.parent


def _python(code: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


def test_the_blends_fresnel_integrals_are_scipys_without_importing_scipy_special():
    code = ("import sys, numpy as np; from nc.motion.clothoid import fresnel; "
            "before = 'scipy.special' in sys.modules; "
            "x = np.concatenate([np.linspace(-40, 40, 100001), [0.0, 5e-324, 1e-300, 1e300, np.inf, -np.inf]]); "
            "s, c = fresnel(x); "
            "import scipy.special as sp; s2, c2 = sp.fresnel(x); "
            "same = lambda a, b: np.array_equal(a, b, equal_nan=True); "  # 1e300: nan from both
            "print(before, same(s, s2), same(c, c2), fresnel is sp.fresnel)")
    assert _python(code) == ["False", "True", "True", "True"]


def test_a_run_with_blends_and_a_parquet_trace_imports_neither_scipy_special_nor_pandas(tmp_path):
    trace = tmp_path / "t.parquet"
    code = ("import sys; from hil.cli import main; import nc.motion.clothoid as c; calls = []; f = c.fresnel; "
            "c.fresnel = lambda x: calls.append(1) or f(x); "  # counted: the demo's corners are blended
            f"rc = main(['run', 'examples/lathe_demo.nc', '--trace', {str(trace)!r}]); "
            "print(rc, len(calls) > 0, *(m in sys.modules for m in ('scipy.special', 'pandas', 'numpy.ma')))")
    out = _python(code)
    assert out[-5:] == ["0", "True", "False", "False", "False"]  # numpy.ma: np.unique's first call imports it
    t = pq.read_table(trace)
    assert t.num_rows == 14396 and t.column("X_cmd").to_pylist()[-1] == pytest.approx(50.0)


def test_a_trace_in_several_parts_is_joined_without_pandas_and_holds_what_pyarrow_converts(tmp_path):
    """Rows and column blocks, a row group of 100: the parts are written and read back for the join."""
    trace = tmp_path / "p.parquet"
    code = ("import sys, numpy as np; from hil.trace_parquet import ParquetTrace; "
            f"w = ParquetTrace({str(trace)!r}, ['t', 'line', 'alarm', 'X_cmd', 'X_sw'], row_group=100); "
            "[w.write([k * 0.001, k // 10, '' if k % 7 else '0x1001', k * 0.5, k]) for k in range(150)]; "
            "ks = np.arange(150, 420); w.write_columns([(ks * 0.001).tolist(), (ks // 10).tolist(), "
            "['' if k % 9 else 'ü' for k in ks], ks * 0.5, ks.tolist()], len(ks)); "
            "w.close({'reason': 'completed'}); print('pandas' in sys.modules)")
    assert _python(code) == ["False"]
    ks = range(420)
    want = pa.table({"t": pa.array([k * 0.001 for k in ks]), "line": pa.array([k // 10 for k in ks]),
                     "alarm": pa.array([(None if k % 7 else "0x1001") if k < 150 else (None if k % 9 else "ü")
                                        for k in ks]),
                     "X_cmd": pa.array([k * 0.5 for k in ks]), "X_sw": pa.array(list(ks), type=pa.uint16())})
    got = pq.read_table(trace)
    assert pq.ParquetFile(trace).metadata.num_row_groups == 5
    assert got.select(want.column_names).equals(want.cast(got.select(want.column_names).schema))


def test_the_hil_command_starts_no_openblas_threads_unless_the_user_asks():
    """numpy's OpenBLAS starts a thread per core at import, ≈ 0.1 s of CPU in every `hil` process (B47)."""
    import os

    code = ("import os, sys; from hil.cli import main; rc = main(['path', 'examples/lathe_demo.nc']); import numpy; "
            "print(len(os.listdir('/proc/self/task')), os.environ.get('OPENBLAS_NUM_THREADS'))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    plain = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env)
    asked = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                           env={**env, "OPENBLAS_NUM_THREADS": "2"})
    (n_plain, set_plain), (n_asked, set_asked) = (p.stdout.split()[-2:] for p in (plain, asked))
    assert (set_plain, set_asked) == ("1", "2")
    if (os.cpu_count() or 1) >= 2:  # OpenBLAS starts one thread fewer than the threads it is allowed
        assert int(n_plain) == int(n_asked) - 1


def test_a_run_whose_bench_has_checks_reads_its_trace_back_without_pandas(tmp_path):
    """The post-run checks of benches/mill-3axis.toml read the trace's columns as numpy arrays (B48)."""
    from benchmarks.bench_motion import cam_program

    prog, trace = tmp_path / "cam.nc", tmp_path / "cam.parquet"
    prog.write_text(cam_program(300))
    code = ("import sys; from hil.cli import main; "
            f"rc = main(['run', {str(prog)!r}, '--bench', 'benches/mill-3axis.toml', '--trace', {str(trace)!r}]); "
            "print(rc, 'pandas' in sys.modules, 'numpy.ma' in sys.modules)")  # numpy.ma: np.median's first call
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.split()[-3:] == ["0", "False", "False"], out.stderr
    assert "ok    contour error:" in out.stdout and "ok    jerk X:" in out.stdout


def test_trace_columns_read_as_numpy_equal_pyarrows_to_numpy():
    import numpy as np

    from hil.trace_read import _numbers

    parts = [pa.array([1.5, -2.0, np.nan, 4.0]), pa.array([5.0, 6.0])]
    for col in (pa.chunked_array(parts), pa.chunked_array([parts[0].slice(1, 2)]), pa.chunked_array([], pa.float64()),
                pa.chunked_array([pa.array([1, 65535], pa.uint16()), pa.array([7], pa.uint16()).slice(0, 1)]),
                pa.chunked_array([pa.array([3, None], pa.int64())])):
        got, want = _numbers(col), col.to_numpy()
        assert got.dtype == want.dtype and np.array_equal(got, want, equal_nan=True)
        assert got.flags.writeable == want.flags.writeable


def test_a_run_without_a_trace_does_not_import_pyarrow():
    """pyarrow (≈ 45 ms with its ssl and socket) is for a Parquet trace; the stretch's trace columns ask for it only
    where one is open (hil/stretch_bulk.py)."""
    code = ("import sys; from hil.cli import main; rc = main(['run', 'examples/lathe_demo.nc']); "
            "print(rc, 'pyarrow' in sys.modules)")
    assert _python(code)[-2:] == ["0", "False"]


def test_the_collector_is_paused_until_the_cycles_and_left_as_the_caller_had_it(tmp_path):
    """hil.api.run keeps the cyclic collector off while it imports and builds (≈ 90 collections, ≈ 20 ms of a
    `hil run`: B47); the cycles meet it as before, and afterwards it is on, nothing frozen, as the caller had it."""
    code = "\n".join([
        "import gc, sys",
        "n = [0]",
        "gc.callbacks.append(lambda p, i: p == 'stop' and n.__setitem__(0, n[0] + 1))",
        "import hil",
        "from hil.session import InputError",
        "r = hil.run('examples/lathe_demo.nc')",
        "print(r.run.ok, gc.isenabled(), gc.get_freeze_count(), n[0] < 40)",  # ≈ 20 in all, ≈ 95 without B47
        "try:",
        "    hil.run('no/such/file.nc')",
        "except InputError:",
        "    pass",
        "print(gc.isenabled(), gc.get_freeze_count())",
        "gc.disable()",
        "hil.run('examples/lathe_demo.nc')",
        "print(gc.isenabled(), gc.get_freeze_count())"])
    assert _python(code) == ["True", "True", "0", "True", "True", "0", "False", "0"]


def test_a_lockstep_runs_young_collections_are_rare_and_the_callers_thresholds_come_back():
    """Decision bench B150: while a lock-step run's cycles go, the collector stays on (a user's MLC or script that makes
    reference cycles still has them collected) with its young threshold at 50,000 new containers, not CPython's 700:
    the lathe demo's cycles meet no young collection where they met 3 (the CAM program's 72 and 6 middle ones). Afterwards the caller's thresholds are back,
    whatever they were."""
    code = "\n".join([
        "import gc",
        "import hil",
        "from hil.runner import BenchRunner",
        "seen, inside = [], [False]",
        "gc.callbacks.append(lambda p, i: p == 'start' and inside[0] and seen.append(i['generation']))",
        "run_events = BenchRunner.run_events",
        "def spy(self, events, planner=None):",
        "    print(gc.isenabled(), *gc.get_threshold())",
        "    inside[0] = True",
        "    try:",
        "        return run_events(self, events, planner)",
        "    finally:",
        "        inside[0] = False",
        "BenchRunner.run_events = spy",
        "r = hil.run('examples/lathe_demo.nc')",
        "print(r.run.ok, seen.count(0), *gc.get_threshold())",
        "gc.set_threshold(1000, 5, 7)",
        "hil.run('examples/lathe_demo.nc')",
        "print(gc.isenabled(), *gc.get_threshold())"])
    assert _python(code) == ["True", "50000", "10", "10", "True", "0", "700", "10", "10",
                             "True", "50000", "5", "7", "True", "1000", "5", "7"]


def test_the_checks_median_is_numpys():
    import numpy as np

    from hil.checks import _median

    rng = np.random.default_rng(7)
    for a in [rng.normal(size=n) for n in (1, 2, 3, 4, 101, 1000)] + [np.full(6, 0.001), np.array([2.0, np.nan, 1.0])]:
        want = float(np.median(a))
        assert _median(a) == want or (np.isnan(want) and np.isnan(_median(a)))


def test_a_run_without_events_imports_no_event_player_and_builds_no_whole_signal_table():
    """hil.run_events is for --at/--events (B65); the lathe MLC's signal names are resolved from the general block's
    and channel 1's rows, not from the 4-channel table of 5,308 signals (≈ 10 ms of a `hil run`'s start)."""
    code = ("import sys; from hil.cli import main; import mlc.signals as s; rc = main(['run', 'examples/lathe_demo.nc']); "
            "print(rc, 'hil.run_events' in sys.modules, s.signal_table.cache_info().currsize, "
            "s._by_name.cache_info().currsize, "  # (B91: nor channel 1's whole name index)
            "s.resolve('MST_FINISH') is s.signal_table((1, 2, 3, 4))['M21016'])")  # M2x016: the same object
    assert _python(code)[-5:] == ["0", "False", "0", "0", "True"]


def test_a_name_resolves_to_the_name_indexs_signal():
    """B91: a name is looked up in the rows that can hold it; the object is the one the whole index (first in its
    order) gives, for every name of the general block and channels 1-4 (and 0, 5: the general block alone), and
    what the index does not know stays unknown."""
    import mlc.signals as s

    for ch in range(6):
        index = s._by_name(ch)
        assert all(s._named(ch, name) is sig for name, sig in index.items())
        for name in ("NOPE", "MST_FINISH_X", "JOG_FWD", "JOG_FWD_", "M21016", "", "PULSE_50MS_1"):
            assert s._named(ch, name) is index.get(name)
    assert s.resolve(" jog_fwd_z ", 2) is s._by_name(2)["JOG_FWD_Z"] and s.resolve("ALWAYS_ON").address == "M29035"


def test_an_event_after_a_run_without_events_in_one_process_still_fires_and_holds():
    """The stretch runner looks the EventPlayer class up once a run imported it (hil/stretch_state.py): a feed hold
    scripted in a second run of the same process runs as in a process of its own, stretches included."""
    held = "b = hil.run('examples/lathe_demo.nc', events=['t=2:feed-hold', 't=2.6:cycle-start']); "
    show = "print(b.run.ok, all(e.fired_cycle is not None for e in b.events), b.run.cycles, b.run.stretched)"
    alone = _python("import hil; " + held + show)[-4:]
    second = _python("import hil; a = hil.run('examples/lathe_demo.nc'); " + held + show)[-4:]
    assert alone[:2] == ["True", "True"] and second == alone
    assert int(alone[2]) > 14396 + 550  # the hold's 0.6 s and the ramps around it, at 1 ms a cycle


# What a lathe demo run with a Parquet trace must not import (B84): each costs every run and only some runs use it
NOT_IN_A_LATHE_RUN = {
    "multiprocessing.connection": "hil.fit_ahead's pipes: only a real-time run that fits ahead (B86)",
    "mlc.remote_io": "a bench's remote I/O stations ([[io]]); mlc.program names IoMap in annotations only",
    "scipy.special": "the blends' Fresnel integrals load the extension alone (B47)",
    "pandas": "the trace's columns from numpy buffers (B48)",
    "numpy.ma": "np.unique / np.median spelt without it (session 16)",
    "hil.run_events": "--at/--events only (B65)",
    "numpy.polynomial": "the spline fit's quadrature nodes, worked out at the first fit (B84, session 18 lead)",
    "importlib.metadata": "the trace's deltahil version is the source's, hil/version.py (B90)",
    "nc.motion.spline_runs": "the fit of runs of short lines, imported by the first window fitted (B91)",
    "nc.motion.spline_fit": "as nc.motion.spline_runs (B91)",
    "pyarrow.fs": "pyarrow.parquet's module, with ssl and the cloud file systems: the trace through pyarrow's writer (B92)",
    "ctypes.util": "mlockall's libc look-up (and subprocess): a real-time run's (B91)",
    "xml.etree.ElementTree": "--junit's report (B91)",
    "csv": "a CSV trace's writer, not a Parquet trace's (B91)",
}


def test_a_lathe_run_imports_none_of_the_modules_it_does_not_use(tmp_path):
    code = ("import sys; from hil.cli import main; "
            f"rc = main(['run', 'examples/lathe_demo.nc', '--trace', {str(tmp_path / 't.parquet')!r}]); "
            f"print('IMPORTED', rc, *sorted(m for m in {sorted(NOT_IN_A_LATHE_RUN)!r} if m in sys.modules))")
    out = _python(code)
    assert out[out.index("IMPORTED") + 1:] == ["0"]


def test_a_file_a_user_mlc_helper_leaves_open_is_written_and_the_exit_is_quiet(tmp_path):
    """The `hil` command skips the finalization's garbage collections (a freeze at the end of `hil.cli.main`, B83,
    ≈ 35 ms of the exit; B64 before it). What they did for a user must still happen: a user's MLC module whose
    helper opens a log at import and never closes it gets its text, also when the file sits in a reference cycle
    (only a collection would have closed it: flushed at the end); the run's ruckig objects, in the bench's cycles,
    are freed (nanobind prints a leak report on stderr otherwise). Without the flush the cycle's log stays empty;
    without the release in nc/manual.py the exit prints "nanobind: leaked 6 instances" (both tried)."""
    log, held = tmp_path / "mlc.log", tmp_path / "held.log"
    (tmp_path / "mlc_log.py").write_text(
        f"LOG = open({str(log)!r}, 'w')\nLOG.write('loaded\\n')\n\n\n"
        "class Held:  # a file in a reference cycle: freed only by a collection\n"
        f"    def __init__(self):\n        self.file = open({str(held)!r}, 'w')\n        self.me = self\n\n\n"
        "HELD = Held()\n")
    mlc = tmp_path / "user_mlc.py"
    mlc.write_text("import os\nimport sys\n\nsys.path.insert(0, os.path.dirname(__file__))\nfrom mlc_log import HELD, LOG\n\n\n"
                   "def scan(mlc):\n    strobe = mlc.m('M_STROBE') or mlc.m('S_STROBE') or mlc.m('T_STROBE')\n"
                   "    if strobe and not mlc.m('MST_FINISH'):\n        LOG.write(f\"M{int(mlc.d('M_CODE'))}\\n\")\n"
                   "        HELD.file.write(f\"M{int(mlc.d('M_CODE'))}\\n\")\n"
                   "        mlc.set('MST_FINISH')\n    elif not strobe:\n        mlc.set('MST_FINISH', False)\n")
    prog = tmp_path / "p.nc"
    prog.write_text("G00 X10\nM08\nM30\n")
    out = subprocess.run([sys.executable, "-m", "hil.cli", "run", str(prog), "--mlc", str(mlc)],
                         capture_output=True, text=True, cwd=ROOT)
    assert (out.returncode, out.stderr) == (0, "")
    assert log.read_text().split() == ["loaded", "M8"]
    assert held.read_text().split() == ["M8"]


def test_the_spindle_axis_positioning_ruckig_objects_are_freed_at_the_exit():
    """The C-axis switch (M66) positions the spindle with its own ruckig generator, held by the MLC's switch in the
    bench's cycles: released at exit as the manual motion's are (B83), so no leak report follows the summary."""
    out = subprocess.run([sys.executable, "-m", "hil.cli", "run", "examples/lathe_face_drilling_c.nc",
                          "--bench", "benches/lathe-c-axis.toml"], capture_output=True, text=True, cwd=ROOT)
    assert (out.returncode, out.stderr) == (0, "")
    assert "result         completed" in out.stdout


def test_only_the_hil_command_itself_ends_without_collections():
    """Only the `hil` command's own process ends with the freeze (main() without arguments: the console script and
    `python -m hil.cli`); a script or a test calling main(argv) ends as it ends itself."""
    code = ("import sys, hil.cli as c; calls = []; c._end_without_collections = lambda: calls.append(1); "
            "a = c.main(['path', 'examples/lathe_demo.nc']); n = len(calls); "
            "sys.argv = ['hil', 'path', 'examples/lathe_demo.nc']; b = c.main(); "
            "print(a, n, b, len(calls), file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stderr.split() == ["0", "0", "0", "1"]
