"""Checks on a trace: following error, contour error against the programmed path, setpoint v/a/j
limits, thread phase on each pass, and cycle jitter. Each check returns a `CheckResult` that names
the worst (or first offending) cycle, its time and its program line.

Checks read only the columns they need, so a long Parquet trace costs a few columns of memory.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from hil.bench import FILTER_MS, Bench, ChecksConfig
from hil.contour_distance import FEED_KINDS, contour_distances
from hil.trace import axes_of, spindles_of
from hil.trace_read import TraceFile
from nc.alarms import NcAlarm
from nc.interp import Interpreter
from nc.moves import Move, MoveBatch, MoveList
from nc.profiles import make_profile
from nc.program import Program

# How many cycles the actual position may trail the interpolator's line: the drive's following
# lag and the bus latency (a few cycles at a 1 ms cycle), plus the position filter's span
# (default 16+16 ms at 1 ms when the bench is not known).
SERVO_LAG_CYCLES = 20
LAG_CYCLES = int(2 * FILTER_MS) + SERVO_LAG_CYCLES


@dataclass
class CheckResult:
    name: str
    ok: bool
    value: float = 0.0
    limit: float = 0.0
    unit: str = ""
    cycle: int | None = None
    line: int | None = None
    t: float | None = None
    detail: str = ""
    skipped: bool = False

    def __str__(self) -> str:
        if self.skipped:
            return f"SKIP  {self.name}: {self.detail}"
        head = "ok  " if self.ok else "FAIL"
        where = ""
        if self.cycle is not None:
            where = f" at cycle {self.cycle}"
            if self.t is not None:
                where += f" (t={self.t:.3f} s)"
            if self.line:
                where += f", line {self.line}"
        cmp = "<=" if self.ok else ">"
        text = f"{head}  {self.name}: {_fmt(self.value, self.unit)} {cmp} {_fmt(self.limit, self.unit)}{where}"
        return text + (f"; {self.detail}" if self.detail else "")

    def as_dict(self) -> dict:
        return {"check": self.name, "ok": self.ok, "skipped": self.skipped, "value": self.value, "limit": self.limit,
                "unit": self.unit, "cycle": self.cycle, "line": self.line, "t": self.t, "detail": self.detail}


def _fmt(v: float, unit: str) -> str:
    if unit == "s":
        return f"{v * 1e6:.1f} µs"
    return f"{v:.4g} {unit}".strip()


class _Cols:
    """The trace's columns, loaded once each on first use."""

    def __init__(self, trace: TraceFile) -> None:
        self.trace = trace
        self._c: dict[str, np.ndarray] = {}

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._c:
            self._c.update(self.trace.arrays([name]))
        return self._c[name]

    def where(self, i: int) -> dict:
        return {"cycle": int(self["cycle"][i]) if "cycle" in self.trace.columns else i + 1,
                "line": int(self["line"][i]), "t": float(self["t"][i])}


NO_PROGRAM = "needs the program (--program)"


def program_row(trace: TraceFile | _Cols) -> int | None:
    """Index of the trace's last row before the program's first block (line 0 up to it: power-up and drive
    homing), the row the program starts from; None when no block ran or the trace has no line column."""
    cols = trace if isinstance(trace, _Cols) else _Cols(trace)
    if "line" not in cols.trace.columns:
        return None
    ran = np.flatnonzero(cols["line"] > 0)
    return max(int(ran[0]) - 1, 0) if ran.size else None


def program_start(trace: TraceFile | _Cols, axes: list[str]) -> dict[str, float] | None:
    """Where the run's program started: each axis's actual position in `program_row`, which the NC took as its
    start (decision B51). On a real bus the axes stand wherever they were left, and drive homing moves and
    renames them, so the bench's power-on `start` is not where the first move begins. None where unknown."""
    cols = trace if isinstance(trace, _Cols) else _Cols(trace)
    row = program_row(cols)
    if row is None:
        return None
    return {a: float(cols[f"{a}_act"][row]) for a in axes if f"{a}_act" in cols.trace.columns}


def program_moves(program: Program, bench: Bench, start: dict[str, float] | None = None) -> list[Move]:
    """The programmed path in machine coordinates, from `start` (`program_start` of a run's trace), else from
    the axes' power-on positions."""
    profile = make_profile(bench.profile, bench.axis_names, bench.params)
    interp = Interpreter(profile, {a.name: a.start for a in bench.axes} | (start or {}))
    # runs of plain G0/G1 blocks read in bulk (issue 16's MoveBatch, a cycle's MoveList): the same
    # Move objects, a third of the interpreter's time on a 5,000-block CAM program (issue 17)
    interp.bulk = True
    out: list[Move] = []
    for ev in interp.run(program):
        if type(ev) is MoveBatch:
            out += ev.moves()
        elif type(ev) is MoveList:
            out += ev.items
        elif isinstance(ev, Move):
            out.append(ev)
    return out


def offline_moves(program: Program, bench: Bench, start: dict[str, float] | None = None
                  ) -> tuple[list[Move] | None, str]:
    """`program_moves`, or None and why: a program that reads what only a run answers (servo
    parameters, MLC registers) alarms offline, and its path checks are skipped saying so."""
    try:
        return program_moves(program, bench, start), NO_PROGRAM
    except NcAlarm as e:
        return None, f"the program does not run offline, so its path is unknown here: alarm {e}"


def run_checks(trace: TraceFile, checks: ChecksConfig, bench: Bench | None = None,
               moves: list[Move] | None = None, no_moves: str = NO_PROGRAM) -> list[CheckResult]:
    """`no_moves` says why `moves` is None (the skipped path checks print it)."""
    cols = _Cols(trace)
    axes = axes_of(trace.columns)
    out: list[CheckResult] = []
    for axis, limit in checks.max_following_error.items():
        out.append(check_following_error(cols, axis, limit, _unit(bench, axis)) if axis in axes else
                   CheckResult(f"following error {axis}", False, detail=f"no column {axis}_ferr in the trace"))
    if checks.contour_error is not None:
        if moves is None:
            out.append(CheckResult("contour error", True, skipped=True, detail=no_moves))
        else:
            lag, independent = LAG_CYCLES, False
            if bench is not None:
                cfg = bench.motion_config()
                # the longest filter of the settings G05 may switch to (decision language L25-1)
                span = max(sum(c.filter_cycles()) for c in bench.motion_configs().values())
                lag, independent = span + SERVO_LAG_CYCLES, cfg.rapid_independent
            out.append(check_contour(cols, axes, moves, checks.contour_error, lag, independent))
    if checks.limits:
        if bench is None:
            out.append(CheckResult("setpoint limits", True, skipped=True, detail="needs the bench (--bench)"))
        else:
            out += check_limits(cols, bench, checks.limit_tolerance)
    if checks.thread_phase is not None:
        out.append(check_thread_phase(cols, axes, spindles_of(trace.columns), moves, checks.thread_phase, no_moves))
    jitter = [(n, getattr(checks, k)) for n, k in (("p99", "jitter_p99"), ("p99.9", "jitter_p999"),
                                                    ("max", "jitter_max")) if getattr(checks, k) is not None]
    if jitter:
        out += check_jitter(cols, bench.cycle if bench else None, jitter)
    return check_finite(cols) + out


def check_finite(cols: _Cols) -> list[CheckResult]:
    """A NaN (or ±inf) in a column a check read makes every comparison on it false, so the check
    would pass on missing data: each such column fails here instead, naming its first bad cycle."""
    out = []
    for name, col in sorted(cols._c.items()):
        if col.dtype.kind != "f":
            continue
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            out.append(CheckResult(f"trace data {name}", False, detail=f"{bad.size} cycles hold no number "
                                   f"(NaN/inf), first at cycle {cols.where(int(bad[0]))['cycle']}"))
    return out


# ---- individual checks ----------------------------------------------------------------------
def _unit(bench: Bench | None, axis: str) -> str:
    """A rotary axis (units = "deg") reports degrees; linear axes, and axes of an unknown bench, mm."""
    ax = next((a for a in bench.axes if a.name == axis), None) if bench is not None else None
    return "deg" if ax is not None and ax.units == "deg" else "mm"


def check_following_error(cols: _Cols, axis: str, limit: float, unit: str = "mm") -> CheckResult:
    ferr = np.abs(cols[f"{axis}_ferr"])
    if ferr.size == 0:
        return CheckResult(f"following error {axis}", True, 0.0, limit, unit, detail="empty trace")
    i = int(np.argmax(ferr))
    over = np.flatnonzero(ferr > limit)
    detail = f"{over.size} cycles over, first at cycle {cols.where(int(over[0]))['cycle']}" if over.size else ""
    return CheckResult(f"following error {axis}", not over.size, float(ferr[i]), limit, unit, detail=detail,
                       **cols.where(i))


def check_contour(cols: _Cols, axes: list[str], moves: list[Move], limit: float,
                  lag_cycles: int = LAG_CYCLES, independent_rapids: bool = False) -> CheckResult:
    """Distance of the actual position from the programmed path, on cycles executing a feed move.

    A cycle's line is the block the interpolator is in; the position the drives were given trails
    it by up to the post-interpolation filter's span (a weighted mean of the last T1+T2 of
    interpolated points) and the drive by its following lag. So the candidates for a run of
    cycles on line L are the moves of every line the trace shows within `lag_cycles` before the
    run (on 0.05 mm CAM blocks that is a dozen blocks back), and their neighbours, because a
    move's corner may be blended."""
    mv_axes = [a for a in axes if any(a in m.end for m in moves)]
    if not any(m.kind in FEED_KINDS for m in moves):
        return CheckResult("contour error", True, 0.0, limit, "mm", detail="no feed moves in the program")
    line = cols["line"]
    act = np.column_stack([cols[f"{a}_act"] for a in mv_axes]) if mv_axes else np.zeros((len(line), 0))
    dist = contour_distances(act, line, moves, mv_axes, lag_cycles, independent_rapids)
    # An E-stop's (or a failed cycle's) rows, where the drives brake on their own quick stop and leave the path
    # by design (stop category 1, B10/B12), are not judged as path: the quick stop check judges them (B102)
    braking = np.zeros(len(line), dtype=bool)
    for a in mv_axes:
        followed = _commanded_rows(cols, a, len(line))
        if followed is not None:
            braking |= ~followed
    off = dist[braking & (dist > 0.0)]
    dist = np.where(braking, 0.0, dist)
    i = int(np.argmax(dist))
    over = np.flatnonzero(dist > limit)
    detail = f"{over.size} cycles over, first at cycle {cols.where(int(over[0]))['cycle']}" if over.size else ""
    if off.size:  # said, not judged: how far the drives' own stop took the tool off the path
        detail += ("; " if detail else "") + (f"not judged: {off.size} cycles the drives braked on their own "
                                               f"(quick stop, fault), up to {off.max():.4g} mm off the path")
    return CheckResult("contour error", not over.size, float(dist[i]), limit, "mm", detail=detail, **cols.where(i))


def _median(a: np.ndarray) -> float:
    """np.median of a 1-D array, its very arithmetic (the middle one, or np.mean of the middle two; nan where a nan is
    in it), without np.median's first call importing numpy.ma (≈ 9 ms of a `hil run` whose bench has checks)."""
    s = np.sort(a)
    if s.size and np.isnan(s[-1]):
        return float("nan")
    h = s.size // 2
    return float(np.mean(s[h - 1:h + 1] if s.size % 2 == 0 else s[h:h + 1]))


def check_limits(cols: _Cols, bench: Bench, tolerance: float) -> list[CheckResult]:
    """Velocity, acceleration and jerk of each axis's setpoints (backward differences per cycle)."""
    out = []
    t = cols["t"]
    dt = _median(np.diff(t)) if len(t) > 1 else bench.cycle
    # Before the program's first block the NC sends no path: the drives enable and home themselves, and a homing's
    # new origin is a step of the position, not a speed (decision B51); one mask for every axis
    since = None
    if "line" in cols.trace.columns:
        row = program_row(cols)
        since = np.arange(len(t)) >= (row if row is not None else len(t))
    for ax in bench.axes:
        name = f"{ax.name}_cmd"
        if name not in cols.trace.columns:
            continue
        x = cols[name]
        unit = "deg" if ax.units == "deg" else "mm"
        commanded = _commanded_rows(cols, ax.name, len(x))
        if since is not None:
            commanded = since if commanded is None else commanded & since
        for order, (label, lim) in enumerate((("velocity", ax.limits.max_velocity),
                                              ("acceleration", ax.limits.max_acceleration),
                                              ("jerk", ax.limits.max_jerk)), start=1):
            d = np.abs(np.diff(x, n=order)) / dt ** order
            if commanded is not None and d.size:  # only differences wholly inside the NC's command
                d = np.where(sliding_window_view(commanded, order + 1).all(axis=1), d, 0.0)
            u = f"{unit}/s" + ("" if order == 1 else f"^{order}")
            if d.size == 0:
                out.append(CheckResult(f"{label} {ax.name}", True, 0.0, lim, u))
                continue
            i = int(np.argmax(d))
            bad = np.flatnonzero(d > lim * (1 + tolerance))
            detail = f"{bad.size} cycles over, first at cycle {cols.where(int(bad[0]) + order)['cycle']}" \
                if bad.size else ""
            out.append(CheckResult(f"{label} {ax.name}", not bad.size, float(d[i]), lim, u, detail=detail,
                                   **cols.where(i + order)))
        braking = _braking_check(cols, ax.name, ax.limits.max_acceleration, tolerance, dt, unit)
        if braking is not None:
            out.append(braking)
    return out


QUICK_STOP_ALARMS = ("0x0401", "0x0000")  # E-stop (M2x013), NC internal error: the drives' quick stop follows


def _commanded_rows(cols: _Cols, axis: str, n: int) -> np.ndarray | None:
    """Rows where the axis's drive was in Operation Enabled, i.e. followed the NC's setpoint. In quick
    stop (E-stop, a failed planner) the drive brakes on its own ramp: that is judged by
    _braking_check, not as a setpoint (decision B12)."""
    name = f"{axis}_sw"
    if name not in cols.trace.columns:
        return None
    state = cols[name].astype(np.int64) & 0x6F
    followed = state == 0x27
    if "alarm" in cols.trace.columns:
        # From an E-stop's or a failed cycle's row until the drive takes its quick stop, the bench lets the
        # setpoint coast at the drive's speed (B10, B12): the drive's stop, not the NC's path (decision B82)
        for i in np.flatnonzero(np.isin(cols["alarm"], QUICK_STOP_ALARMS)).tolist():
            taken = np.flatnonzero(state[i:] != 0x27)
            followed[i:i + int(taken[0]) if taken.size else len(state)] = False
    return followed


def _braking_check(cols: _Cols, axis: str, limit: float, tolerance: float, dt: float,
                   unit: str) -> CheckResult | None:
    """The drive's own quick stop (CiA 402 state 0x07) must brake within the axis's acceleration."""
    sw, vel = f"{axis}_sw", f"{axis}_vel"
    if sw not in cols.trace.columns or vel not in cols.trace.columns:
        return None
    quick = (cols[sw].astype(np.int64) & 0x6F) == 0x07
    if not quick.any():
        return None
    a = np.abs(np.diff(cols[vel])) / dt
    a = np.where(quick[1:] | quick[:-1], a, 0.0)
    i = int(np.argmax(a))
    bad = np.flatnonzero(a > limit * (1 + tolerance))
    detail = f"{bad.size} cycles over, first at cycle {cols.where(int(bad[0]) + 1)['cycle']}" if bad.size else ""
    return CheckResult(f"quick stop deceleration {axis}", not bad.size, float(a[i]), limit, f"{unit}/s^2",
                       detail=detail, **cols.where(i + 1))


def check_thread_phase(cols: _Cols, axes: list[str], spindles: list[str], moves: list[Move] | None,
                       limit: float, no_moves: str = NO_PROGRAM) -> CheckResult:
    """Each pass of a thread must meet the spindle at the same phase.

    For every threading line, a reference point on the thread axis common to all passes is chosen
    (the middle of their overlap); on each pass the spindle angle when the actual axis position
    crosses it, less the angle that pass's own start offset accounts for (compound infeed shifts
    the start on purpose), must agree across passes within `limit` degrees."""
    name = "thread phase"
    if moves is None:
        return CheckResult(name, True, skipped=True, detail=no_moves)
    if not spindles or f"{spindles[0]}_angle" not in cols.trace.columns:
        return CheckResult(name, True, skipped=True, detail="the trace has no spindle angle column")
    threads: dict[int, list[Move]] = defaultdict(list)
    for m in moves:
        # A pass's chamfer pull-out continues the same pass; it is not a pass of its own.
        if m.kind == "thread" and m.lead and "chamfer" not in m.tags:
            threads[m.line].append(m)
    if not threads:
        return CheckResult(name, True, skipped=True, detail="no thread moves in the program")
    angle = cols[f"{spindles[0]}_angle"]
    line_col = cols["line"]
    worst = CheckResult(name, True, 0.0, limit, "deg")
    for ln, passes in threads.items():
        first = passes[0]
        ax = max((a for a in first.end if a in axes), key=lambda a: abs(first.end[a] - first.start.get(a, 0.0)))
        sign = 1.0 if first.end[ax] > first.start[ax] else -1.0
        lo = max(min(m.start[ax], m.end[ax]) for m in passes)
        hi = min(max(m.start[ax], m.end[ax]) for m in passes)
        ref = 0.5 * (lo + hi)
        pos = cols[f"{ax}_act"]
        rows = np.flatnonzero(line_col == ln)
        crossings = []
        for r in rows:
            if r == 0:
                continue
            p0, p1 = pos[r - 1], pos[r]
            if (p0 - ref) * sign < 0 <= (p1 - ref) * sign:
                f = (ref - p0) / (p1 - p0)
                a0, a1 = angle[r - 1], angle[r]
                da = (a1 - a0 + 180.0) % 360.0 - 180.0
                crossings.append((r, (a0 + f * da) % 360.0))
        if len(crossings) != len(passes):
            return CheckResult(name, False, float(len(crossings)), float(len(passes)), "passes",
                               detail=f"line {ln}: {len(passes)} thread passes programmed, {len(crossings)} "
                                      f"crossed {ax}={ref:.3f}", **(cols.where(crossings[-1][0]) if crossings else {}))
        phases = np.array([(ang - abs(ref - m.start[ax]) / m.lead * 360.0) % 360.0
                           for (_, ang), m in zip(crossings, passes)])
        mean = math.degrees(math.atan2(np.mean(np.sin(np.radians(phases))), np.mean(np.cos(np.radians(phases)))))
        dev = np.abs((phases - mean + 180.0) % 360.0 - 180.0)
        spread = float(2 * np.max(dev))  # peak-to-peak around the circular mean
        k = int(np.argmax(dev))
        if spread >= worst.value:
            worst = CheckResult(name, spread <= limit, spread, limit, "deg",
                                detail=f"line {ln}: {len(passes)} passes, pass {k + 1} farthest from the others",
                                **cols.where(crossings[k][0]))
    return worst


def check_jitter(cols: _Cols, cycle: float | None, limits: list[tuple[str, float]]) -> list[CheckResult]:
    period = cols["period"]
    nominal = cycle if cycle is not None else (round(float(np.median(period)), 7) if period.size else 0.0)
    jit = np.abs(period - nominal)
    out = []
    for label, lim in limits:
        if jit.size == 0:
            out.append(CheckResult(f"jitter {label}", True, 0.0, lim, "s"))
            continue
        value = float(np.max(jit)) if label == "max" else float(np.percentile(jit, float(label[1:])))
        ok = value <= lim
        bad = np.flatnonzero(jit > lim)
        i = int(bad[0]) if (not ok and bad.size) else int(np.argmax(jit))
        detail = f"{bad.size} cycles over {_fmt(lim, 's')}" if bad.size else ""
        out.append(CheckResult(f"jitter {label}", ok, value, lim, "s", detail=detail, **cols.where(i)))
    return out
