"""`hil campaign diff BASE NEW`: what changed between two campaigns' results.

Cases are matched on their key (program, bench, bus, overrides, params, fault), not on their input
hash, so a changed bench or program is compared with its earlier self. A regression is a case that
passed and no longer does, an alarm that changed, or program time or an error that grew beyond
its tolerance; improvements and new or missing cases are listed but do not fail the diff.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq

from hil.campaign.results import KEY_COLUMNS


@dataclass
class Tolerances:
    time: float = 0.01  # relative change of program time
    error: float = 0.005  # absolute change of a following or contour error, mm
    share: float = 0.02  # absolute change of a peak v/a/j share of its limit


@dataclass
class Change:
    key: dict[str, Any]
    what: str
    base: Any
    new: Any
    regression: bool

    def line(self) -> str:
        k = self.key
        case = f"{k['program']} on {k['bench']}"
        variant = [f"bus {k['bus']}"] if k["bus"] != "sim" else []
        variant += [f"{n.replace('_', ' ')} {k[n]:g} %" for n in ("override", "rapid_override", "spindle_override")
                    if k.get(n) not in (None, 100.0)]
        variant += [k["params"]] if k.get("params") else []
        variant += [f"fault {k['fault']}"] if k.get("fault") not in (None, "none") else []
        mark = "REGRESSION" if self.regression else "changed   "
        return f"{mark}  {case}{' (' + ', '.join(variant) + ')' if variant else ''}: {self.what} {_fmt(self.base)} → {_fmt(self.new)}"


@dataclass
class Diff:
    changes: list[Change] = field(default_factory=list)
    added: list[dict[str, Any]] = field(default_factory=list)
    missing: list[dict[str, Any]] = field(default_factory=list)
    compared: int = 0

    @property
    def regressions(self) -> list[Change]:
        return [c for c in self.changes if c.regression]


def _fmt(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _key(row: dict[str, Any]) -> tuple:
    return tuple(row.get(k) for k in KEY_COLUMNS)


def load_rows(path: str | Path) -> list[dict[str, Any]]:
    p = Path(path)
    if p.is_dir():
        p = p / "results.parquet"
    table = pq.read_table(p)
    missing = [c for c in (*KEY_COLUMNS, "status") if c not in table.column_names]
    if missing:
        raise ValueError(f"no {', '.join(missing)} column{'s' if len(missing) > 1 else ''}")
    return table.to_pylist()


def diff(base: list[dict[str, Any]], new: list[dict[str, Any]], tol: Tolerances) -> Diff:
    b = {_key(r): r for r in base}
    n = {_key(r): r for r in new}
    out = Diff()
    out.added = [n[k] for k in n if k not in b]
    out.missing = [b[k] for k in b if k not in n]
    for k in (k for k in n if k in b):
        out.compared += 1
        key = dict(zip(KEY_COLUMNS, k))
        old, cur = b[k], n[k]
        if old["status"] != cur["status"]:
            worse = old["status"] == "completed"
            out.changes.append(Change(key, "status", _status(old), _status(cur), worse))
        elif old.get("alarm") != cur.get("alarm"):
            out.changes.append(Change(key, "alarm", _status(old), _status(cur), True))
        t0, t1 = old.get("program_time_s"), cur.get("program_time_s")
        if _num(t0) and _num(t1) and abs(t1 - t0) > tol.time * max(abs(t0), 1e-9):
            out.changes.append(Change(key, "program time (s)", t0, t1, t1 > t0))
        for col in sorted(set(old) | set(cur)):
            limit = tol.error if col.startswith(("max_ferr_", "max_contour")) else \
                tol.share if col.startswith("peak_") else None
            if limit is None:
                continue
            v0, v1 = old.get(col), cur.get(col)
            if _num(v0) and _num(v1) and abs(v1 - v0) > limit:
                out.changes.append(Change(key, col, v0, v1, v1 > v0))
    return out


def _num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _status(row: dict[str, Any]) -> str:
    if row.get("alarm"):
        return f"{row['status']} {row['alarm']}" + (f" line {row['alarm_line']}" if row.get("alarm_line") else "")
    if row.get("checks_failed"):
        return f"{row['status']} ({row['checks_failed']})"
    return str(row["status"])
