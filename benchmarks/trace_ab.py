"""A/B of the bench cycle's shortcuts (issue 17): the same runs with a shortcut off and on must give
the same Parquet trace, column by column (every column but the wall-clock `period`/`late`, MLC device
columns included), the same end record, alarms, handshakes and final positions.

    python benchmarks/trace_ab.py [--quick]      # --quick: the three short runs only
    PYTHONPATH=/work/main python benchmarks/trace_ab.py --save DIR     # one tree's runs, kept in DIR
    python benchmarks/trace_ab.py --against DIR  # this tree's runs against those (tree A/B)

Shortcuts compared: `mlc-on-change` (the lathe MLC's user scan skipped while nothing it read changed,
mlc/on_change.py), `stretch` (quiet cycles a stretch at a time, hil/stretch.py; DELTAHIL_STRETCH=0 is off). Prints one line per run and per shortcut, exits 1 on any difference.

    python benchmarks/trace_ab.py --writer [--callgrind] [TRACE.parquet ...]

The Parquet writer's option sets (`WRITER_SETS`, bench decision B139) on the traces given (default: the CAM run of
5,000 blocks and the lathe demo, made here): each trace's table written by pyarrow's writer with each set, in memory;
prints the file's size, the best of 15 writes' wall time and, with --callgrind, the instructions of one write
(valgrind: a child writing it 3 times less one writing it 0 times, after a first write as the trace's warm-up
makes); exits 1 if a set's file does not read back to the same values, bit for bit.
"""

from __future__ import annotations

import json
import pickle
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))  # PYTHONPATH first: --save runs the tree it names

from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.api import run  # noqa: E402

SIGNALS = ("M_STROBE,S_STROBE,T_STROBE,MST_FINISH,M_CODE,S_CODE,T_CODE,SPINDLE1_FWD,SPINDLE1_REV,"
           "SPINDLE_ANALOG_1,SPINDLE1_SPEED_REACHED,PROGRAM_END,M21013,M31016,M31017,D30272,D30240,M21019,"
           # the drive status the NC writes (issue 17: written when it changed)
           "D30242,D30274,D30338,D30400,D30401,M31256,M31272,M31464,M31480,M31497,M31034,D31026,D31028,M31705,"
           "M31352,M31353")  # the axes at 0 (the planner position the NC reads before its step)
LATHE, LATHE_C, MILL = (str(ROOT / "benches" / f) for f in ("lathe-2axis.toml", "lathe-c-axis.toml", "mill-3axis.toml"))


def runs(tmp: Path, quick: bool) -> Iterator[tuple[str, str, dict]]:
    """(name, program path, hil.api.run keywords)."""
    demo = str(ROOT / "examples" / "lathe_demo.nc")
    cam = tmp / "cam800.nc"
    cam.write_text(cam_program(800))
    yield "C-axis drilling", str(ROOT / "examples" / "lathe_face_drilling_c.nc"), {"bench": LATHE_C}
    yield "M96 interrupt", str(ROOT / "examples" / "m96_interrupt.nc"), {"bench": MILL, "events": ["t=1.1:pulse M21019"]}
    yield "CAM 800 blocks", str(cam), {"bench": MILL}
    # without device columns the mill keeps its basic MLC: stretches cross the cruise's blocks (decision B25)
    yield "CAM 800 blocks, basic MLC", str(cam), {"bench": MILL, "trace_signals": None}
    if quick:
        return
    yield "lathe demo", demo, {}
    yield "hold/resume/override", demo, {"events": ["t=2:feed-hold", "t=2.6:cycle-start", "t=4:set D21002=50"]}
    # the run ends at its E-stop (`hil run` refuses events after it: recovery is `hil script`'s)
    yield "E-stop", demo, {"events": ["t=3:estop"]}
    yield "overrides 70/110 %", demo, {"feed_override": 70.0, "spindle_override": 110.0}
    yield "overrides 110/70 %", demo, {"feed_override": 110.0, "spindle_override": 70.0, "rapid_override": 70.0}
    yield "G71/G70/G76 threads", str(ROOT / "examples" / "lathe_part_g71_g70_g76.nc"), {"spindle_override": 80.0}


@contextmanager
def mlc_on_change(on: bool) -> Iterator[None]:
    import mlc.lathe

    old = mlc.lathe.SCAN_ON_CHANGE
    mlc.lathe.SCAN_ON_CHANGE = on
    try:
        yield
    finally:
        mlc.lathe.SCAN_ON_CHANGE = old


@contextmanager
def stretches(on: bool) -> Iterator[None]:
    import os

    from hil.stretch import ENV

    old = os.environ.get(ENV)
    os.environ[ENV] = "1" if on else "0"
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = old


SHORTCUTS: dict[str, Callable[[bool], object]] = {"mlc-on-change": mlc_on_change, "stretch": stretches}


def one(program: str, kw: dict, trace: Path, keep: list | None = None) -> tuple:
    """(trace columns, summary) of a run; `keep` receives the run's result (tests/test_stretch_runner.py)."""
    r = run(program, trace=str(trace), check=False, **({"trace_signals": SIGNALS} | kw))
    if keep is not None:
        keep.append(r)
    table = pq.read_table(trace)
    cols = {c: table.column(c).to_pylist() for c in table.column_names if c not in ("period", "late")}
    hs = getattr(getattr(r.runner, "mlc", None), "link", None)
    handshakes = list(getattr(hs, "handshake_log", []))
    meta = {k: json.loads(v) for k, v in (table.schema.metadata or {}).items()}
    for m in meta.values():
        if isinstance(m, dict):
            m.pop("written", None)  # the wall-clock date of the file
            if isinstance(m.get("program_file"), dict):  # (decision B75) its path: the CAM runs' program is written
                m["program_file"].pop("path", None)  # to a new temporary folder each time; its SHA-256 is compared
    summary = (r.run.cycles, [a.code_text for a in r.alarms], r.run.final, r.run.finished, handshakes, meta)
    return cols, summary


def compare(a: tuple, b: tuple) -> list[str]:
    (ca, sa), (cb, sb) = a, b
    out = [f"column {c}: first difference at row {next(i for i, (x, y) in enumerate(zip(ca[c], cb[c])) if x != y)}"
           for c in ca if c in cb and len(ca[c]) == len(cb[c]) and ca[c] != cb[c]]
    if set(ca) != set(cb) or any(len(ca[c]) != len(cb.get(c, ())) for c in ca):
        out.append(f"shape: {len(next(iter(ca.values())))} vs {len(next(iter(cb.values())))} rows")
    for name, x, y in zip(("cycles", "alarms", "final", "finished", "handshakes", "metadata"), sa, sb):
        if x != y:
            out.append(f"{name}: {x!r:.200} vs {y!r:.200}")
    return out


def _floats(schema, pick=lambda name: True) -> dict[str, str]:
    return {f.name: "BYTE_STREAM_SPLIT" for f in schema if str(f.type) == "double" and pick(f.name)}


def _with(schema, **kw) -> dict:
    from hil.trace_parquet import writer_options

    opts = writer_options(schema)
    enc = {**(opts["column_encoding"] or {}), **kw.pop("column_encoding", {})}
    return {**opts, **kw, "column_encoding": enc or None}


# the writer's option sets compared by --writer: name -> options of pyarrow's ParquetWriter for a schema
WRITER_SETS: dict[str, Callable] = {
    "pq defaults (before B139)": lambda s: _with(s, use_dictionary=True, column_encoding={}) | {"column_encoding": None},
    "no dictionary": lambda s: _with(s, use_dictionary=False) | {"column_encoding": None},
    "B139": lambda s: _with(s),
    "B139, byte_stream_split t, *_cmd": lambda s: _with(s, column_encoding=_floats(s, lambda c: c == "t" or
                                                                                     c.endswith("_cmd"))),
    "B139, byte_stream_split floats": lambda s: _with(s, column_encoding=_floats(s)),
    "B139, zstd level -1": lambda s: _with(s, compression_level=-1),
    "B139, zstd level 3": lambda s: _with(s, compression_level=3),
    "B139, no statistics": lambda s: _with(s, write_statistics=False),
}

_CG_CHILD = """
import sys, pyarrow as pa
sys.path.insert(0, sys.argv[1])
from benchmarks.trace_ab import WRITER_SETS, _write_with
from hil.trace_parquet import _Writer
import pyarrow._parquet as pqi
r = pqi.ParquetReader(); r.open(sys.argv[2]); table = r.read_all()
opts = WRITER_SETS[sys.argv[3]](table.schema)
_write_with(table, opts)  # the first file's lazy set-up (a run's trace makes it in _warm_up)
for _ in range(int(sys.argv[4])):
    _write_with(table, opts)
"""


def _write_with(table, opts: dict):
    """The file pyarrow's writer makes of the table with these options, in memory."""
    import pyarrow as pa

    from hil.trace_parquet import _Writer

    buf = pa.BufferOutputStream()
    w = _Writer(buf, table.schema, **opts)
    w.write_table(table, row_group_size=None)
    w.close()
    return buf.getvalue()


def _same_bits(a, b) -> bool:
    """Two tables' schema (metadata included) and values equal bit for bit (NaN, -0.0), nulls in the same rows."""
    import numpy as np
    import pyarrow as pa

    if not a.schema.equals(b.schema, check_metadata=True) or a.num_rows != b.num_rows:
        return False
    for x, y in zip(a.columns, b.columns):
        x, y = x.combine_chunks(), y.combine_chunks()
        if x.type == pa.float64():
            if not (x.is_null().equals(y.is_null()) and np.array_equal(
                    x.fill_null(0.0).to_numpy().view(np.int64), y.fill_null(0.0).to_numpy().view(np.int64))):
                return False
        elif not x.equals(y):
            return False
    return True


def _instructions(trace: Path, name: str, writes: int) -> int:
    import os
    import subprocess

    with tempfile.TemporaryDirectory() as d:
        child, out = Path(d) / "child.py", Path(d) / "cg.out"
        child.write_text(_CG_CHILD)
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", os.path.realpath(sys.executable),
                        str(child), str(ROOT), str(trace), name, str(writes)], check=True, capture_output=True,
                       env={**os.environ, "PYTHONHASHSEED": "0"})
        return next(int(line.split()[1]) for line in out.read_text(errors="replace").splitlines()
                    if line.startswith(("summary:", "totals:")))


def writer(argv: list[str]) -> int:
    """--writer: each option set on each trace (module docstring)."""
    import time

    import pyarrow as pa
    import pyarrow.parquet as pq

    callgrind = "--callgrind" in argv
    traces = [Path(a) for a in argv if not a.startswith("--")]
    bad = 0
    with tempfile.TemporaryDirectory() as d:
        if not traces:
            cam = Path(d) / "cam5000.nc"
            cam.write_text(cam_program(5000))
            for name, program, kw in (("cam5000", cam, {"bench": MILL}), ("lathe_demo", ROOT / "examples" /
                                                                          "lathe_demo.nc", {})):
                traces.append(Path(d) / f"{name}.parquet")
                run(str(program), trace=str(traces[-1]), check=False, **kw)
        for trace in traces:
            table = pq.ParquetFile(trace).read()
            print(f"{trace.name}: {table.num_rows} rows, {table.num_columns} columns")
            print(f"  {'option set':34s} {'bytes':>8s} {'ms':>6s} {'instructions':>13s}  values")
            for name, make in WRITER_SETS.items():
                opts = make(table.schema)
                data = _write_with(table, opts)
                best = min(_timed(time.perf_counter, _write_with, table, opts) for _ in range(15))
                same = _same_bits(pq.ParquetFile(pa.BufferReader(data)).read(), table)
                bad += not same
                ir = ""
                if callgrind:
                    ir = f"{(_instructions(trace, name, 3) - _instructions(trace, name, 0)) // 3:,}"
                print(f"  {name:34s} {data.size:8d} {best * 1e3:6.2f} {ir:>13s}  {'same' if same else 'DIFFERENT'}")
    return 1 if bad else 0


def _timed(clock: Callable[[], float], fn: Callable, *args) -> float:
    t0 = clock()
    fn(*args)
    return clock() - t0


def main(argv: list[str]) -> int:
    if "--writer" in argv:
        return writer(argv)
    quick = "--quick" in argv
    save = Path(argv[argv.index("--save") + 1]) if "--save" in argv else None
    against = Path(argv[argv.index("--against") + 1]) if "--against" in argv else None
    bad = 0
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for k, (name, program, kw) in enumerate(runs(tmp, quick)):
            if save is not None or against is not None:
                res = one(program, kw, tmp / "t.parquet")
                res[1][-1].get(b"deltahil", {}).pop("program", None)  # the CAM program's temporary path
                res[1][-1].get(b"deltahil", {}).get("bench", {}).pop("source", None)  # the bench file's tree
                kept = (save or against) / f"run{k}.pickle"
                if save is not None:
                    save.mkdir(parents=True, exist_ok=True)
                    kept.write_bytes(pickle.dumps(res))
                    print(f"{name:24s} saved ({len(next(iter(res[0].values())))} rows)")
                    continue
                diff = compare(pickle.loads(kept.read_bytes()), res)
                print(f"{name:24s} against {against}: {'IDENTICAL' if not diff else 'DIFFERENT'}")
                for line in diff:
                    print("   ", line)
                bad += bool(diff)
                continue
            for shortcut, toggle in SHORTCUTS.items():
                results = []
                for on in (False, True):
                    with toggle(on):  # type: ignore[attr-defined]
                        results.append(one(program, kw, tmp / f"{on}.parquet"))
                diff = compare(*results)
                rows = len(next(iter(results[0][0].values())))
                print(f"{name:24s} {shortcut}: {'IDENTICAL' if not diff else 'DIFFERENT'} ({rows} rows, "
                      f"{len(results[0][0])} columns)")
                for line in diff:
                    print("   ", line)
                bad += bool(diff)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
