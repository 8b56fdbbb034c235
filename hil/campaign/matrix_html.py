"""The campaign's pass/fail matrix as one self-contained HTML page: programs down, benches and
variants across, a cell per case coloured by status, linking to the case's report where its trace
was kept. `hil campaign` writes it as DIR/summary.html; `hil campaign diff --html` marks changes."""

from __future__ import annotations

import html
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from hil.campaign.results import report_dir

COLOURS = {"completed": "#c8f0c8", "alarm": "#f6c2c2", "check_failed": "#f9e0a8", "not_triggered": "#f0e6c8",
           "worker_lost": "#d9d9d9", "timeout": "#e3c8f0"}


def variant(row: dict[str, Any]) -> str:
    parts = [row["bus"]] if row.get("bus") != "sim" else []
    parts += [f"F{row['override']:g}%"] if row.get("override") != 100.0 else []
    parts += [f"G0 {row['rapid_override']:g}%"] if row.get("rapid_override", 100.0) != 100.0 else []
    parts += [f"S{row['spindle_override']:g}%"] if row.get("spindle_override", 100.0) != 100.0 else []
    parts += [row["params"]] if row.get("params") else []
    parts += [f"fault {row['fault']}"] if row.get("fault") not in (None, "none") else []
    return ", ".join(parts) or "nominal"


def matrix_page(title: str, rows: list[dict[str, Any]], out_dir: Path,
                changed: Iterable[tuple] = (), key=None) -> str:
    """`changed`: keys (as `key(row)` gives them) of cases a diff flagged; they get a red border."""
    changed = set(changed)
    programs = sorted({r["program"] for r in rows})
    columns = sorted({(r["bench"], variant(r)) for r in rows})
    cell = {(r["program"], r["bench"], variant(r)): r for r in rows}
    counts = {s: sum(r["status"] == s for r in rows) for s in COLOURS}
    head = "".join(f"<th>{html.escape(b)}<br><small>{html.escape(v)}</small></th>" for b, v in columns)
    body = []
    for p in programs:
        tds = []
        for b, v in columns:
            r = cell.get((p, b, v))
            if r is None:
                tds.append("<td></td>")
                continue
            text = r["status"].replace("_", " ")
            if r.get("alarm"):
                text += f"<br>{html.escape(r['alarm'])}" + (f" line {r['alarm_line']}" if r.get("alarm_line") else "")
            elif r.get("checks_failed"):
                text += f"<br><small>{html.escape(r['checks_failed'])}</small>"
            if r.get("program_time_s") is not None:
                text += f"<br><small>{r['program_time_s']:.3f} s</small>"
            report = report_dir(r) / "index.html" if r.get("trace") else None
            if report is not None and (out_dir / report).exists():
                text = f'<a href="{html.escape(report.as_posix())}">{text}</a>'
            border = "border:3px solid #c00;" if key is not None and key(r) in changed else ""
            tds.append(f'<td style="background:{COLOURS.get(r["status"], "#fff")};{border}" '
                       f'title="{html.escape(r.get("message") or "")}">{text}</td>')
        body.append(f"<tr><th>{html.escape(p)}</th>{''.join(tds)}</tr>")
    legend = "  ".join(f'<span style="background:{c};padding:2px 6px">{s.replace("_", " ")} {counts[s]}</span>'
                       for s, c in COLOURS.items())
    return f"""<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif}} table{{border-collapse:collapse}} td,th{{border:1px solid #999;padding:4px 8px;
text-align:center;font-size:13px}} th{{background:#f0f0f0}}</style></head><body>
<h1>{html.escape(title)}</h1><p>{len(rows)} cases. {legend}</p>
<table><tr><th>program</th>{head}</tr>{''.join(body)}</table></body></html>"""
