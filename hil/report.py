"""HTML report with PNG plots of a trace: the path commanded against actual, following error,
velocity and torque, the cycle-jitter histogram and the MLC signal timeline.

Plots are matplotlib Figures with their own canvas (no display, no pyplot: importing this never
changes a notebook's backend). Long traces are decimated
for drawing (every k-th row, keeping each plotted series' extremes visible through min/max
envelopes on the time plots), never for the numbers in the summary.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hil.atomic_dir import atomic_dir
from hil.bench import Bench
from hil.checks import CheckResult
from hil.contour_distance import polyline
from hil.figures import subplots
from hil.trace import axes_of, spindles_of, trace_columns
from hil.trace_read import TraceFile
from hil.trace_summary import format_summary, summarise
from nc.moves import Move

MAX_POINTS = 20_000  # points per plotted series


@dataclass
class Report:
    out: Path
    html: Path
    images: list[Path] = field(default_factory=list)
    interactive: Path | None = None  # report.html: Plotly, self-contained


def _env(t: np.ndarray, y: np.ndarray, n: int = MAX_POINTS // 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Min/max envelope of y over n time buckets, so peaks survive decimation."""
    if len(y) <= 2 * n:
        return t, y, y
    k = len(y) // n
    m = k * n
    yy = y[:m].reshape(n, k)
    return t[:m:k], yy.min(axis=1), yy.max(axis=1)


def _plot_series(ax, t, y, label, **kw):
    tt, lo, hi = _env(t, y)
    if lo is hi:
        ax.plot(tt, lo, label=label, lw=0.9, **kw)
    else:
        ax.fill_between(tt, lo, hi, label=label, alpha=0.7, step="mid", **kw)


def _decimate(*arrays: np.ndarray) -> list[np.ndarray]:
    n = len(arrays[0])
    k = max(1, n // MAX_POINTS)
    return [a[::k] for a in arrays]


def path_axes(axes: list[str], profile: str | None) -> tuple[str, str] | None:
    """The plane to draw: ZX on a lathe (Z across, X up), XY on a mill."""
    if "Z" in axes and "X" in axes and (profile is None or profile != "nc5-mill") and "Y" not in axes:
        return "Z", "X"
    if "X" in axes and "Y" in axes:
        return "X", "Y"
    return (axes[0], axes[1]) if len(axes) >= 2 else None


def write_report(trace_path: str | Path, out: str | Path, bench: Bench | None = None,
                 moves: list[Move] | None = None, checks: list[CheckResult] | None = None,
                 title: str | None = None, interactive: bool = True) -> Report:
    """`interactive=False`: the PNG report only, without report.html (campaigns at scale)."""
    tf = TraceFile(trace_path)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(20, "not a directory", str(out))
    from hil.report_html import write_html_report

    with atomic_dir(out) as tmp:  # an existing report stays whole until the new one is complete
        rep = Report(tmp, tmp / "index.html")
        figs = [_save(fig, tmp / name, rep, caption) for name, caption, fig in trace_figures(tf, bench, moves)]
        summary = format_summary(tf, summarise(tf))
        rep.html.write_text(_html(title or f"Bench report: {tf.path.name}", summary, checks, figs, interactive),
                            encoding="utf-8")
        if interactive:
            write_html_report(tf, tmp / "report.html", path_axes(axes_of(tf.columns), bench.profile if bench else None),
                              title, summary)
    done = Report(out, out / "index.html", [out / p.name for p in rep.images])
    done.interactive = out / "report.html" if interactive else None
    return done


def trace_figures(trace: str | Path | TraceFile, bench: Bench | None = None,
                  moves: list[Move] | None = None) -> list[tuple[str, str, Any]]:
    """The report's plots as matplotlib Figures, (file name, caption, figure) each: a notebook shows
    them, `write_report` saves them."""
    tf = trace if isinstance(trace, TraceFile) else TraceFile(trace)
    cols = tf.arrays()
    axes, spindles = axes_of(tf.columns), spindles_of(tf.columns)
    t = cols["t"]
    figs: list[tuple[str, str, Any]] = []

    plane = path_axes(axes, bench.profile if bench else None)
    if plane is not None:
        h, v = plane
        fig, ax = subplots(figsize=(8, 6), dpi=110)
        if moves:
            names = [a for a in axes if any(a in m.end for m in moves)]
            if h in names and v in names:
                a, b = polyline([m for m in moves if m.kind != "dwell"], names)
                ih, iv = names.index(h), names.index(v)
                pts = np.vstack([a, b[-1:]]) if len(a) else a
                if len(pts):
                    ax.plot(pts[:, ih], pts[:, iv], color="0.6", lw=3, label="programmed", zorder=1)
        ch, cv, ah, av = _decimate(cols[f"{h}_cmd"], cols[f"{v}_cmd"], cols[f"{h}_act"], cols[f"{v}_act"])
        ax.plot(ch, cv, lw=1.2, color="tab:blue", label="commanded", zorder=2)
        ax.plot(ah, av, lw=0.8, ls="--", color="tab:red", label="actual (feedback)", zorder=3)
        ax.set_xlabel(f"{h} (machine, mm)")
        ax.set_ylabel(f"{v} (machine{', radius' if v == 'X' and h == 'Z' else ''}, mm)")
        ax.set_title(f"Path {h}{v}: commanded vs actual")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
        figs.append(("path.png", f"Path in the {h}{v} plane, commanded against actual", fig))

    fig, ax = subplots(figsize=(10, 4), dpi=110)
    for a in axes:
        _plot_series(ax, t, cols[f"{a}_ferr"] * 1000.0, a)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("following error (µm)")
    ax.set_title("Following error per axis")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    figs.append(("following_error.png", "Following error over time", fig))

    fig, (ax1, ax2) = subplots(2, 1, figsize=(10, 6), dpi=110, sharex=True)
    for a in axes:
        _plot_series(ax1, t, cols[f"{a}_vel"], a)
        _plot_series(ax2, t, cols[f"{a}_torque"], a)
    for s in spindles:
        _plot_series(ax2, t, cols[f"{s}_torque"], s)
    ax1.set_ylabel("velocity (mm/s or deg/s)")
    ax1.set_title("Axis velocity (feedback) and torque")
    ax2.set_ylabel("torque (% rated)")
    ax2.set_xlabel("time (s)")
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    figs.append(("velocity_torque.png", "Velocity and torque", fig))

    period = cols.get("period")
    fig, ax = subplots(figsize=(8, 4), dpi=110)
    if period is not None and len(period):
        nominal = bench.cycle if bench else round(float(np.median(period)), 7)
        jit = (period - nominal) * 1e6
        ax.hist(jit, bins=100, color="tab:purple", log=True)
        p99 = float(np.percentile(np.abs(jit), 99))
        ax.set_title(f"Cycle period − {nominal * 1e3:g} ms: p99 |jitter| {p99:.1f} µs, max {np.max(np.abs(jit)):.1f} µs")
    ax.set_xlabel("period deviation (µs)")
    ax.set_ylabel("cycles (log)")
    ax.grid(True, alpha=0.3)
    figs.append(("jitter.png", "Cycle jitter histogram", fig))

    standard = set(trace_columns(axes, spindles))
    signals = [c for c in tf.columns if c not in standard and np.issubdtype(cols[c].dtype, np.number)]
    rows = ["line"] + [f"{s}_rpm_cmd" for s in spindles] + signals
    fig, axs = subplots(len(rows), 1, figsize=(10, 1.0 + 0.9 * len(rows)), dpi=110, sharex=True, squeeze=False)
    for ax, name in zip(axs[:, 0], rows):
        tt, y = _decimate(t, cols[name].astype(float))
        ax.step(tt, y, where="post", lw=1.0)
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=7)
    alarm_t = [float(t[i]) for i, a in enumerate(cols.get("alarm", [])) if a]
    for ax in axs[:, 0]:
        for at in alarm_t[:50]:
            ax.axvline(at, color="red", lw=1.0)
    axs[0, 0].set_title("Program line, spindle command and MLC signals" + (" (red: alarms)" if alarm_t else ""))
    axs[-1, 0].set_xlabel("time (s)")
    figs.append(("signals.png", "MLC signal timeline", fig))

    return figs


def _save(fig, path: Path, rep: Report, caption: str) -> tuple[str, str]:
    fig.tight_layout()
    fig.savefig(path)
    rep.images.append(path)
    return path.name, caption


def _html(title: str, summary: str, checks: list[CheckResult] | None, figs: list[tuple[str, str]],
          interactive: bool = True) -> str:
    e = html.escape
    parts = ["<!doctype html><html><head><meta charset='utf-8'>", f"<title>{e(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
             "pre{background:#f4f4f4;padding:1em;overflow-x:auto}td,th{padding:2px 10px;text-align:left}"
             ".ok{color:#060}.fail{color:#b00;font-weight:bold}.skip{color:#888}img{max-width:100%}</style>",
             f"</head><body><h1>{e(title)}</h1>", "<h2>Summary</h2>", f"<pre>{e(summary)}</pre>"]
    if checks:
        verdict = "PASS" if all(c.ok for c in checks) else "FAIL"
        parts.append(f"<h2>Checks: <span class='{'ok' if verdict == 'PASS' else 'fail'}'>{verdict}</span></h2>")
        parts.append("<table><tr><th>result</th><th>check</th><th>value</th><th>limit</th><th>cycle</th>"
                     "<th>t (s)</th><th>line</th><th>detail</th></tr>")
        for c in checks:
            cls, word = ("skip", "skip") if c.skipped else (("ok", "ok") if c.ok else ("fail", "FAIL"))
            parts.append(f"<tr class='{cls}'><td>{word}</td><td>{e(c.name)}</td><td>{c.value:.6g} {e(c.unit)}</td>"
                         f"<td>{c.limit:.6g} {e(c.unit)}</td><td>{c.cycle if c.cycle is not None else ''}</td>"
                         f"<td>{'' if c.t is None else f'{c.t:.3f}'}</td><td>{c.line or ''}</td>"
                         f"<td>{e(c.detail)}</td></tr>")
        parts.append("</table>")
    if interactive:
        parts.append("<p><a href='report.html'>Interactive report</a> (zoomable, linked time axes)</p>")
    for name, caption in figs:
        parts.append(f"<h2>{e(caption)}</h2><img src='{e(name)}' alt='{e(caption)}'>")
    parts.append("</body></html>")
    return "\n".join(parts)
