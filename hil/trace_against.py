"""A trace judged against a reference trace of the same program (`hil check TRACE --against REF`, decision B127):
the regression check of a bench — a new NC version, parameter set or drive firmware against a run kept as good.

What a controller engineer compares between two runs of one program:
- the path: every commanded point of each run within `path_tol` of the other run's commanded path (both ways,
  so a corner cut or a section skipped shows as well as a detour), in machine coordinates, from the program's
  first block on. Timing differences do not count here: the same path run a little faster is the same path;
- the program's time (its first block to its last), within `time_tol`;
- how the run ended: the end reason, and the alarm and its line;
- the MLC's signals the two traces both recorded (`hil run --trace-signals`): each device's sequence of values
  (M/S/T strobes, their code data, status relays), in order; when they changed is the time check's business.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from hil.checks import CheckResult, program_row
from hil.trace import axes_of
from hil.trace_read import TraceFile

MAX_POINTS = 4_000_000  # the reference path's samples for the distance search (memory: ~100 MB at 3 axes)
DEVICE = re.compile(r"^[MD]\d+$")


@dataclass
class _Run:
    t: np.ndarray
    line: np.ndarray
    points: np.ndarray  # (rows, axes) commanded positions from the program's start row on
    time: float  # the program's time: its first block's row to its last


def _run(tf: TraceFile, axes: list[str]) -> _Run:
    row = program_row(tf)
    cols = tf.arrays(["t", "line"] + [f"{a}_cmd" for a in axes])
    start = 0 if row is None else row
    t, line = cols["t"][start:], cols["line"][start:]
    pts = np.column_stack([cols[f"{a}_cmd"][start:] for a in axes]) if axes else np.zeros((len(t), 0))
    ran = np.flatnonzero(line > 0)
    time = float(t[ran[-1]] - t[0]) if ran.size else 0.0
    return _Run(t, line, pts, time)


def _moving(points: np.ndarray) -> np.ndarray:
    """The rows where the commanded point changes, and the first: standing rows add nothing to a path."""
    if len(points) < 2:
        return np.arange(len(points))
    step = np.any(points[1:] != points[:-1], axis=1)
    return np.concatenate(([0], np.flatnonzero(step) + 1))


def _dense(points: np.ndarray, h: float) -> tuple[np.ndarray, float]:
    """The polyline through `points` sampled at most `h` apart (h grows where that would exceed MAX_POINTS)."""
    seg = np.diff(points, axis=0)
    lengths = np.linalg.norm(seg, axis=1)
    total = float(lengths.sum())
    if total > 0.0 and total / h > MAX_POINTS:
        h = total / MAX_POINTS
    n = np.maximum(np.ceil(lengths / h).astype(np.int64), 1)
    # each segment's samples at fractions k/n, k = 0 … n-1; the last point closes the path
    owner = np.repeat(np.arange(len(seg)), n)
    first = np.concatenate(([0], np.cumsum(n)[:-1]))
    frac = (np.arange(int(n.sum())) - np.repeat(first, n)) / np.repeat(n, n)
    dense = points[:-1][owner] + seg[owner] * frac[:, None]
    return np.vstack([dense, points[-1:]]), h


def _one_way(a: np.ndarray, b: np.ndarray, h: float) -> tuple[float, int, float]:
    """The largest distance of a's points from b's polyline (the nearest of b's samples at most h apart: at most
    h/2 over the true distance), the index in `a` where it is, and the sample spacing used."""
    from scipy.spatial import cKDTree

    if len(b) == 1:
        d = np.linalg.norm(a - b[0], axis=1)
        return float(d.max()), int(d.argmax()), 0.0
    dense, h = _dense(b, h)
    d, _ = cKDTree(dense).query(a)
    return float(d.max()), int(d.argmax()), h


def _where(run: _Run, i: int, cycle0: int) -> dict:
    return {"cycle": cycle0 + i + 1, "t": float(run.t[i]), "line": int(run.line[i]) or None}


def check_path(run: _Run, ref: _Run, tol: float, cycle0: int) -> CheckResult:
    a_idx, b_idx = _moving(run.points), _moving(ref.points)
    a, b = run.points[a_idx], ref.points[b_idx]
    if not len(a) or not len(b):
        return CheckResult("path vs reference", True, skipped=True, detail="a trace has no rows of its program")
    h = tol / 4.0 if tol > 0 else 1e-6
    d_ab, i_ab, h1 = _one_way(a, b, h)
    d_ba, i_ba, h2 = _one_way(b, a, h)
    res = f"; reference path sampled {max(h1, h2):.3g} mm apart" if max(h1, h2) > h * (1 + 1e-9) else ""
    if d_ab >= d_ba:
        ok = d_ab <= tol
        return CheckResult("path vs reference", ok, d_ab, tol, "mm",
                           detail=("the paths' largest distance" if ok else
                                   "this run's commanded point off the reference's path") + res,
                           **_where(run, int(a_idx[i_ab]), cycle0))
    ok = d_ba <= tol
    where = _where(ref, int(b_idx[i_ba]), 0)
    at = f"t={where['t']:.3f} s (line {where['line']})"
    return CheckResult("path vs reference", ok, d_ba, tol, "mm",
                       detail=(f"the paths' largest distance, at the reference's {at}" if ok else
                               f"the reference's path at its {at} not run by this one") + res)


def check_time(run: _Run, ref: _Run, tol: float | None) -> CheckResult:
    limit = tol if tol is not None else max(0.01 * ref.time, 0.001)
    diff = run.time - ref.time
    return CheckResult("program time vs reference", abs(diff) <= limit, abs(diff) * 1e3, limit * 1e3, "ms",
                       detail=f"{run.time:.3f} s against {ref.time:.3f} s ({'+' if diff >= 0 else '-'}"
                              f"{abs(diff) / ref.time * 100 if ref.time else 0.0:.2f} %)")


def check_end(tf: TraceFile, ref: TraceFile) -> CheckResult:
    keys = ("reason", "alarm", "alarm_line")
    a, b = (tf.meta.get("end") or {}), (ref.meta.get("end") or {})
    if not a or not b:
        return CheckResult("end vs reference", True, skipped=True,
                           detail="a trace has no end record (a CSV without its .meta.json, or a trace cut short)")
    diff = [f"{k} {a.get(k)!r} against {b.get(k)!r}" for k in keys if a.get(k) != b.get(k)]
    return CheckResult("end vs reference", not diff, float(len(diff)), 0.0,
                       detail="; ".join(diff) if diff else f"{a.get('reason')}"
                       + (f", alarm {a.get('alarm')} at line {a.get('alarm_line')}" if a.get("alarm") else ""))


def _changes(v: np.ndarray) -> np.ndarray:
    keep = np.concatenate(([True], v[1:] != v[:-1])) if len(v) else np.zeros(0, bool)
    return v[keep]


def check_signals(tf: TraceFile, ref: TraceFile) -> CheckResult:
    common = [c for c in tf.columns if DEVICE.match(c) and c in ref.columns]
    if not common:
        return CheckResult("signals vs reference", True, skipped=True,
                           detail="no device column in both traces (hil run --trace-signals)")
    mine, theirs = tf.arrays(common), ref.arrays(common)
    diff = []
    for c in common:
        a, b = _changes(mine[c]), _changes(theirs[c])
        if len(a) != len(b) or np.any(a != b):
            k = next((i for i in range(min(len(a), len(b))) if a[i] != b[i]), min(len(a), len(b)))
            got = f"{a[k]:g}" if k < len(a) else "nothing"
            want = f"{b[k]:g}" if k < len(b) else "nothing"
            diff.append(f"{c}: value change {k + 1} is {got}, the reference's {want}")
    return CheckResult("signals vs reference", not diff, float(len(diff)), 0.0,
                       detail="; ".join(diff[:3]) + (f" (+{len(diff) - 3} more)" if len(diff) > 3 else "")
                       if diff else f"{len(common)} device column(s), the same values in the same order")


def check_against(tf: TraceFile, ref: TraceFile, path_tol: float, time_tol: float | None) -> list[CheckResult]:
    """The four comparisons of the module doc. Axes: those both traces have."""
    axes = [a for a in axes_of(tf.columns) if a in axes_of(ref.columns)]
    run, base = _run(tf, axes), _run(ref, axes)
    start = program_row(tf) or 0
    return [check_path(run, base, path_tol, start), check_time(run, base, time_tol), check_end(tf, ref),
            check_signals(tf, ref)]
