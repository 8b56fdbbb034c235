"""The interactive report: one self-contained HTML file (Plotly with its JavaScript embedded, so it
opens offline) with linked, zoomable time axes for following error, velocity / acceleration / jerk
against the bench limits, spindle commanded and actual, cycle jitter and the program line lane,
plus the path with the contour error magnified like a ballbar plot.

The PNG report (hil/report.py) stays for CI; this file is what an engineer opens to look closer."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import numpy as np

from hil.trace import axes_of, spindles_of
from hil.trace_read import TraceFile

MAX_POINTS = 20_000  # points per plotted series: long traces are decimated for drawing only
MAGNIFY = 200.0  # contour error drawn ×200 around the commanded path, as a ballbar plot does


def _step(n: int) -> int:
    return max(1, n // MAX_POINTS)


def _limits(tf: TraceFile) -> dict[str, dict[str, float]]:
    """Axis limits from the trace's provenance (velocity, acceleration, jerk), {} when absent."""
    bench = tf.meta.get("bench") or {}
    return {k: v for k, v in (bench.get("axes") or {}).items() if isinstance(v, dict)}


def title_of(tf: TraceFile, title: str | None = None) -> str:
    """Program, bench, date and deltahil version from the trace's metadata."""
    m = tf.meta
    bench = (m.get("bench") or {}).get("name", "?")
    parts = [title or f"Bench report: {m.get('program') or tf.path.name}", f"bench {bench}",
             m.get("written", ""), f"deltahil {m.get('deltahil_version', '?')}"]
    return " · ".join(p for p in parts if p)


def time_figure(tf: TraceFile) -> Any:
    """Stacked plots sharing one time axis: zooming one zooms them all."""
    from plotly.subplots import make_subplots

    cols, units = tf.arrays(), tf.units()
    axes, spindles = axes_of(tf.columns), spindles_of(tf.columns)
    t = cols["t"]
    k = _step(len(t))
    ts = t[::k]
    lim = _limits(tf)
    rows = ["following error", "velocity", "acceleration", "jerk", "spindle", "cycle jitter", "program line",
            "M/S/T handshake"]
    fig = make_subplots(rows=len(rows), cols=1, shared_xaxes=True, vertical_spacing=0.02, subplot_titles=rows)

    def line(row: int, x, y, name: str, **kw) -> None:
        fig.add_scatter(x=x, y=y, name=name, mode="lines", legendgroup=str(row), row=row, col=1, **kw)

    for a in axes:
        u = units.get(f"{a}_cmd", "mm")
        line(1, ts, cols[f"{a}_ferr"][::k] * 1000.0, f"{a} following error")
        # v, a, j of the commanded setpoints: what the drive is asked to follow each cycle
        dt = np.diff(t, prepend=t[0] - (t[1] - t[0] if len(t) > 1 else 1.0))
        dt[dt <= 0] = np.nan
        v = np.diff(cols[f"{a}_cmd"], prepend=cols[f"{a}_cmd"][0]) / dt
        acc = np.diff(v, prepend=v[0]) / dt
        jerk = np.diff(acc, prepend=acc[0]) / dt
        for row, y, key in ((2, v, "velocity"), (3, acc, "acceleration"), (4, jerk, "jerk")):
            line(row, ts, y[::k], f"{a} {key}")
            if a in lim and key in lim[a]:
                for sign in (1, -1):
                    label = {"annotation_text": f"{a} limit"} if sign > 0 else {}
                    fig.add_hline(y=sign * lim[a][key], line_dash="dash", line_color="red", row=row, col=1, **label)
        fig.update_yaxes(title_text=f"{u}/s", row=2, col=1)
        fig.update_yaxes(title_text=f"{u}/s²", row=3, col=1)
        fig.update_yaxes(title_text=f"{u}/s³", row=4, col=1)
    fig.update_yaxes(title_text="µm", row=1, col=1)
    for s in spindles:
        line(5, ts, cols[f"{s}_rpm_cmd"][::k], f"{s} commanded", line_shape="hv")
        line(5, ts, cols[f"{s}_rpm_act"][::k], f"{s} actual")
    fig.update_yaxes(title_text="rpm", row=5, col=1)
    period = cols.get("period")
    if period is not None and len(period):
        line(6, ts, (period[::k] - float(np.median(period))) * 1e6, "period − median")
    fig.update_yaxes(title_text="µs", row=6, col=1)
    line(7, ts, cols["line"][::k], "program line", line_shape="hv")
    alarm = cols.get("alarm")
    if alarm is not None:
        hit = [i for i, x in enumerate(alarm) if x]
        if hit:
            fig.add_scatter(x=t[hit[:50]], y=cols["line"][hit[:50]], mode="markers", name="alarm",
                            marker={"color": "red", "size": 9}, row=7, col=1)
    fig.update_yaxes(title_text="line", row=7, col=1)
    handshake_lane(fig, cols, 8)
    fig.update_xaxes(title_text="time (s)", row=len(rows), col=1)
    fig.update_layout(height=220 * len(rows), margin={"t": 40, "l": 70, "r": 20, "b": 40})
    return fig


# App. B strobes (NC→MLC), their code data and the one finish (MLC→NC), as --trace-signals names them
STROBES = (("M", "M31064", "D31048"), ("S", "M31065", "D31050"), ("T", "M31066", "D31052"))
FINISH = "M21016"
HANDSHAKE_SIGNALS = "M_STROBE,S_STROBE,T_STROBE,MST_FINISH,M_CODE,S_CODE,T_CODE"


def handshakes(cols: dict[str, Any]) -> list[dict[str, Any]]:
    """Each strobe's rising edge (commanded) and the first finish after it (answered, None if never)."""
    t = cols["t"]
    fin = cols.get(FINISH)
    fin_up = np.flatnonzero(np.diff(np.asarray(fin, dtype=np.int8), prepend=0) > 0) if fin is not None else []
    out = []
    for kind, strobe, data in STROBES:
        if strobe not in cols:
            continue
        for i in np.flatnonzero(np.diff(np.asarray(cols[strobe], dtype=np.int8), prepend=0) > 0):
            later = [j for j in fin_up if j >= i]
            code = cols[data][i] if data in cols else None
            # the strobe's row may still carry the previous block's line: take the block it waits in
            span = cols["line"][i:(later[0] + 1) if later else i + 1]
            line = next((int(x) for x in span if x), int(cols["line"][i]))
            out.append({"kind": kind, "code": f"{kind}{int(code)}" if code is not None else kind,
                        "t": float(t[i]), "line": line,
                        "answered": float(t[later[0]]) if later else None})
    return sorted(out, key=lambda h: h["t"])


def handshake_lane(fig: Any, cols: dict[str, Any], row: int) -> None:
    """Event lane: a bar from each M/S/T strobe to the MLC's finish (red and open-ended if none)."""
    events = handshakes(cols)
    if not events and STROBES[0][1] not in cols:
        fig.add_annotation(text=f"run with --trace-signals {HANDSHAKE_SIGNALS} for this lane", showarrow=False,
                           xref="x domain", yref="y domain", x=0.5, y=0.5, row=row, col=1)
    end = float(cols["t"][-1]) if len(cols["t"]) else 0.0
    for kind, color in (("M", "#1f77b4"), ("S", "#2ca02c"), ("T", "#9467bd")):
        xs, ys, text = [], [], []
        for h in (e for e in events if e["kind"] == kind):
            stop = h["answered"] if h["answered"] is not None else end
            what = (f"answered after {(h['answered'] - h['t']) * 1000:.0f} ms" if h["answered"] is not None
                    else "never answered")
            xs += [h["t"], stop, None]
            ys += [kind, kind, None]
            where = f" line {h['line']}" if h["line"] else ""  # the trace's line is the moving block's
            text += [f"{h['code']}{where}: strobe", f"{h['code']}: {what}", None]
        if xs:
            fig.add_scatter(x=xs, y=ys, text=text, hoverinfo="text+x", mode="lines+markers", name=f"{kind} handshake",
                            line={"color": color, "width": 6}, marker={"size": 8}, row=row, col=1)
    unanswered = [h for h in events if h["answered"] is None]
    if unanswered:
        fig.add_scatter(x=[h["t"] for h in unanswered], y=[h["kind"] for h in unanswered], mode="markers",
                        name="no MLC finish", marker={"color": "red", "size": 12, "symbol": "x"},
                        text=[h["code"] for h in unanswered], row=row, col=1)
    fig.update_yaxes(title_text="strobe → finish", categoryorder="array", categoryarray=["T", "S", "M"],
                     row=row, col=1)


def path_figure(tf: TraceFile, plane: tuple[str, str]) -> Any:
    """Commanded path and the actual one with its deviation magnified ×MAGNIFY along the normal."""
    import plotly.graph_objects as go

    h, v = plane
    cols = tf.arrays()
    k = _step(len(cols["t"]))
    ch, cv = cols[f"{h}_cmd"][::k], cols[f"{v}_cmd"][::k]
    ah, av = cols[f"{h}_act"][::k], cols[f"{v}_act"][::k]
    mh, mv = ch + (ah - ch) * MAGNIFY, cv + (av - cv) * MAGNIFY
    fig = go.Figure()
    fig.add_scatter(x=ch, y=cv, mode="lines", name="commanded")
    fig.add_scatter(x=mh, y=mv, mode="lines", name=f"actual, deviation ×{MAGNIFY:g}", line={"dash": "dot"})
    fig.update_layout(title=f"Path {h}{v}: contour error magnified ×{MAGNIFY:g}", height=600,
                      xaxis_title=f"{h} (mm)", yaxis_title=f"{v} (mm)")
    fig.update_yaxes(scaleanchor="x", scaleratio=1)
    return fig


def write_html_report(tf: TraceFile, path: Path, plane: tuple[str, str] | None, title: str | None = None,
                      summary: str = "") -> Path:
    """One file, Plotly JS embedded (include_plotlyjs=True): it opens without a network."""
    from hil.circular_test import format_circular, full_circles

    head = title_of(tf, title)
    if plane is not None:
        circles = format_circular(full_circles(tf.arrays(), plane))
        summary = f"{summary}\n{circles}" if circles else summary
    parts = [time_figure(tf).to_html(full_html=False, include_plotlyjs=True, div_id="time")]
    if plane is not None:
        parts.append(path_figure(tf, plane).to_html(full_html=False, include_plotlyjs=False, div_id="path"))
    page = ("<!doctype html><html><head><meta charset='utf-8'>"
            f"<title>{html.escape(head)}</title><style>body{{font-family:sans-serif;margin:1em 2em}}"
            "pre{background:#f4f4f4;padding:1em}</style></head><body>"
            f"<h1>{html.escape(head)}</h1><pre>{html.escape(summary)}</pre>" + "\n".join(parts) + "</body></html>")
    tmp = path.with_suffix(".tmp")
    tmp.write_text(page, encoding="utf-8")
    tmp.replace(path)  # never a half-written report
    return path
