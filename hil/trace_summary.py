"""Trace summaries and slices, streamed batch by batch so hours-long traces need little memory."""

from __future__ import annotations

import json

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from hil.clock import TimingStats
from hil.trace import axes_of, check_target, is_parquet, spindles_of
from hil.trace_read import TraceFile


@dataclass
class Bound:
    """A slice bound: a time in seconds or a program line."""

    time: float | None = None
    line: int | None = None

    @classmethod
    def parse(cls, text: str) -> "Bound":
        t = text.strip()
        try:
            if t[:1] in "Ll" or t.lower().startswith("line:"):
                b = cls(line=int(t.split(":", 1)[1] if ":" in t else t[1:]))
            else:
                b = cls(time=float(t[:-1] if t.endswith("s") else t))
            if (b.line is not None and b.line < 0) or (b.time is not None and not 0.0 <= b.time < math.inf):
                raise ValueError
            return b
        except ValueError:
            raise ValueError(f"bad bound {text!r}: a time in seconds >= 0 (1.5, 1.5s) or a line (L12, line:12)") from None


def slice_mask(batch: pa.RecordBatch, lo: Bound | None, hi: Bound | None, state: dict) -> pa.Array:
    """Rows from the first reaching `lo` to the last before passing `hi` (a line bound ends when a
    later line starts). `state` carries whether the slice has started/ended across batches."""
    n = batch.num_rows
    t = batch.column("t").to_numpy()
    line = batch.column("line").to_numpy()
    keep = np.ones(n, dtype=bool)
    if lo is not None:
        started = state.get("started", False)
        hit = t >= lo.time if lo.time is not None else line >= lo.line
        on = np.logical_or.accumulate(hit) | started
        state["started"] = bool(on[-1]) if n else started
        keep &= on
    if hi is not None:
        ended = state.get("ended", False)
        past = t > hi.time if hi.time is not None else line > hi.line
        off = np.logical_or.accumulate(past) | ended
        state["ended"] = bool(off[-1]) if n else ended
        keep &= ~off
    return pa.array(keep)


def _bound_text(b: Bound) -> str:
    return f"L{b.line}" if b.line is not None else f"{b.time:g} s"


def check_bounds(lo: Bound | None, hi: Bound | None) -> None:
    """--from after --to (both times or both lines) selects nothing: a usage error, not an empty file
    (decisions B53)."""
    if lo is None or hi is None:
        return
    if (lo.time is not None and hi.time is not None and lo.time > hi.time) or \
            (lo.line is not None and hi.line is not None and lo.line > hi.line):
        raise ValueError(f"--from {_bound_text(lo)} lies after --to {_bound_text(hi)}: the slice is empty")


def empty_slice(tf: TraceFile, lo: Bound | None, hi: Bound | None) -> ValueError:
    """The error for bounds that select no row of a trace that has rows: it names what the trace
    holds, so the user can pick bounds inside it (decisions B53)."""
    whole = summarise(tf)
    asked = " ".join(f"{k} {_bound_text(b)}" for k, b in (("--from", lo), ("--to", hi)) if b is not None)
    if whole.rows == 0:
        return ValueError(f"{tf.path}: empty trace")
    lines = sorted(whole.lines)
    held = f"t {whole.t0:.3f} … {whole.t1:.3f} s" + (f", lines {lines[0]} … {lines[-1]}" if lines else "")
    return ValueError(f"{tf.path}: {asked} selects no rows (the trace holds {held})")


@dataclass
class Summary:
    rows: int = 0
    t0: float | None = None
    t1: float | None = None
    lines: set[int] = field(default_factory=set)
    alarms: list[tuple[int, float, int, str]] = field(default_factory=list)  # cycle, t, line, codes
    events: list[tuple[int, float, int, str]] = field(default_factory=list)  # `hil run --at` actions, same
    ferr: dict[str, tuple[float, float, int]] = field(default_factory=dict)  # max |ferr|, t, line
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)  # actual min, max
    rpm: dict[str, float] = field(default_factory=dict)
    jitter: TimingStats = field(default_factory=TimingStats)
    period: float | None = None


def summarise(tf: TraceFile, lo: Bound | None = None, hi: Bound | None = None) -> Summary:
    s = Summary()
    axes, spindles = axes_of(tf.columns), spindles_of(tf.columns)
    state: dict = {}
    for batch in tf.batches():
        if lo is not None or hi is not None:
            batch = batch.filter(slice_mask(batch, lo, hi, state))
        if batch.num_rows == 0:
            continue
        cols = {n: batch.column(n) for n in batch.schema.names}
        t = cols["t"].to_numpy()
        line = cols["line"].to_numpy()
        s.rows += batch.num_rows
        s.t0 = float(t[0]) if s.t0 is None else s.t0
        s.t1 = float(t[-1])
        s.lines.update(int(x) for x in np.unique(line) if x)
        s.alarms += _marked_rows(cols, "alarm", t, line)
        s.events += _marked_rows(cols, "event", t, line)  # hil/run_events.py: what the MLC saw in that scan
        for a in axes:
            if f"{a}_ferr" not in cols or f"{a}_act" not in cols:
                continue
            f = np.abs(cols[f"{a}_ferr"].to_numpy())
            i = int(np.argmax(f))
            if a not in s.ferr or f[i] > s.ferr[a][0]:
                s.ferr[a] = (float(f[i]), float(t[i]), int(line[i]))
            act = cols[f"{a}_act"].to_numpy()
            lo_, hi_ = s.ranges.get(a, (np.inf, -np.inf))
            s.ranges[a] = (min(lo_, float(act.min())), max(hi_, float(act.max())))
        for sp in [sp for sp in spindles if f"{sp}_rpm_act" in cols]:
            s.rpm[sp] = max(s.rpm.get(sp, 0.0), float(np.max(np.abs(cols[f"{sp}_rpm_act"].to_numpy()))))
        if "period" in cols:
            per = cols["period"].to_numpy()
            if s.period is None:
                s.period = round(float(np.median(per)), 7)
            s.jitter.add_many(per - s.period)
    return s


def _marked_rows(cols: dict, name: str, t: np.ndarray, line: np.ndarray) -> list[tuple[int, float, int, str]]:
    """(cycle, t, line, text) of the rows whose string column `name` is not empty (none without it)."""
    if name not in cols:
        return []
    texts = cols[name].to_pylist()
    cyc = cols["cycle"].to_numpy() if "cycle" in cols else np.arange(len(texts))
    return [(int(cyc[i]), float(t[i]), int(line[i]), x) for i, x in enumerate(texts) if x]


def end_note(meta: dict) -> str | None:
    """How the traced run ended, when not at its program's end (the trace's end record, decision B87), else None."""
    end = meta.get("end") if isinstance(meta, dict) else None
    if not isinstance(end, dict) or end.get("reason") in (None, "completed"):
        return None
    reason = str(end["reason"])
    what = {"alarm": "by an alarm", "aborted": "aborted (a reset flushed the program)",
            "interrupted": "interrupted (the trace was cut)"}.get(reason, f"by {reason}")
    alarm = end.get("alarm")
    if alarm:
        what += f" {alarm}" + (f" at line {end['alarm_line']}" if end.get("alarm_line") else "")
    when = f" at t={float(end['t']):.3f} s (cycle {end.get('cycle')})" if end.get("t") is not None else ""
    return f"run ended {what}{when}, before its program's end"


def format_summary(tf: TraceFile, s: Summary) -> str:
    out = [f"trace          {tf.path}  ({tf.kind}, {len(tf.columns)} columns)"]
    if s.rows == 0:
        return "\n".join(out + ["rows           0"])
    out.append(f"rows           {s.rows}  (t {s.t0:.3f} … {s.t1:.3f} s)")
    if s.period:
        j = s.jitter
        out.append(f"cycle          {s.period * 1e3:g} ms; jitter p50 {j.percentile(50) * 1e6:.1f} µs  "
                   f"p99 {j.percentile(99) * 1e6:.1f} µs  p99.9 {j.percentile(99.9) * 1e6:.1f} µs  "
                   f"max {j.max * 1e6:.1f} µs")
    lines = sorted(s.lines)
    out.append(f"program lines  {len(lines)}" + (f" ({lines[0]} … {lines[-1]})" if lines else ""))
    for a, (v, t, ln) in s.ferr.items():
        lo, hi = s.ranges[a]
        out.append(f"axis {a:<9} range {lo:.4f} … {hi:.4f}; max following error {v:.4f} at t={t:.3f} s line {ln}")
    for sp, rpm in s.rpm.items():
        out.append(f"spindle {sp:<6} max {rpm:.1f} rpm")
    extra = [c for c in tf.columns if c not in _standard(tf.columns)]
    if extra:
        out.append(f"signals        {', '.join(extra)}")
    out.append(f"alarms         {len(s.alarms) or 'none'}")
    for cyc, t, ln, codes in s.alarms[:20]:
        out.append(f"  {codes} at cycle {cyc} (t={t:.3f} s), line {ln}")
    if "event" in tf.columns:
        out.append(f"events         {len(s.events) or 'none'}")
        for cyc, t, ln, text in s.events[:20]:
            out.append(f"  {text} at cycle {cyc} (t={t:.3f} s), line {ln}")
    note = end_note(tf.meta)
    if note:
        out.append(f"end            {note}")
    return "\n".join(out)


def _standard(columns: list[str]) -> set[str]:
    from hil.trace import trace_columns

    return set(trace_columns(axes_of(columns), spindles_of(columns)))


EXPORT_SUFFIXES = (".parquet", ".pq", ".csv", ".feather", ".arrow", ".mf4")


def export(tf: TraceFile, out: str | Path, lo: Bound | None = None, hi: Bound | None = None,
           columns: list[str] | None = None) -> int:
    """Write the slice (and columns) in the format the output's suffix names — Parquet (.parquet,
    .pq), CSV, Arrow IPC (.feather, .arrow) or MDF4 (.mf4, through asammdf, with each column's
    unit) — and return its rows; ValueError for any other suffix, before anything is written."""
    check_target(out)
    suffix = Path(out).suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise ValueError(f"{out}: cannot write {suffix or 'a file without a suffix'}; "
                         f"choose {', '.join(EXPORT_SUFFIXES)}")
    check_bounds(lo, hi)
    if columns:
        missing = [c for c in columns if c not in tf.columns]
        if missing:
            raise ValueError(f"no column {', '.join(missing)} in {tf.path}")
    need = None if not columns else list(dict.fromkeys(["t", "line"] + columns))
    state: dict = {}
    writer = None
    rows = 0
    tmp = Path(str(out) + ".part")
    if suffix == ".mf4":
        return _export_mdf(tf, out, tmp, lo, hi, columns, need)
    record, units = _record(tf)
    try:
        for batch in tf.batches(need):
            if lo is not None or hi is not None:
                batch = batch.filter(slice_mask(batch, lo, hi, state))
            if columns:
                batch = batch.select(columns)
            if writer is None:
                schema = batch.schema if suffix == ".csv" else _with_record(batch.schema, record, units)
                writer = _writer(suffix, tmp, schema)
            if batch.num_rows:
                writer.write_batch(batch) if hasattr(writer, "write_batch") else writer.write(batch)
                rows += batch.num_rows
    except BaseException:  # a damaged input leaves no half export behind
        if writer is not None:
            writer.close()
        tmp.unlink(missing_ok=True)
        raise
    if writer is None:
        raise ValueError(f"{tf.path}: empty trace")
    writer.close()
    if rows == 0 and (lo is not None or hi is not None):
        tmp.unlink(missing_ok=True)  # no file of headers only: the bounds missed the trace
        raise empty_slice(tf, lo, hi)
    tmp.replace(out)
    if suffix == ".csv":
        _csv_record(out, record, units)
    return rows


def _record(tf: TraceFile) -> tuple[dict, dict[str, str]]:
    """The run's record (provenance, bench, program, end) and the columns' units an export carries on (bench
    B81): a converted trace is judged, reported and exported again as the one it came from."""
    meta = {k: v for k, v in tf.meta.items() if k != "units"}
    return meta, tf.units()


def _with_record(schema, record: dict, units: dict[str, str]):
    """Parquet / Arrow IPC: the record in the schema's `deltahil` metadata, each unit in its field's."""
    from hil.trace_parquet import META_KEY

    fields = [f if f.metadata or f.name not in units else f.with_metadata({"unit": units[f.name]}) for f in schema]
    meta = dict(schema.metadata or {})
    if record and META_KEY not in meta:
        meta[META_KEY] = json.dumps(record, allow_nan=False, default=str).encode()
    return pa.schema(fields, metadata=meta or None)


def _csv_record(out: str | Path, record: dict, units: dict[str, str]) -> None:
    """CSV: the record in the side file `hil run` writes (never an older file's left beside the export)."""
    from hil.trace import csv_meta_path

    side = csv_meta_path(out)
    if not record and not units:
        side.unlink(missing_ok=True)
        return
    tmp = side.with_name(side.name + ".part")
    tmp.write_text(json.dumps({**record, **({"units": units} if units else {})}, default=str))
    tmp.replace(side)


def _writer(suffix: str, tmp: Path, schema):
    if suffix in (".parquet", ".pq"):
        return pq.ParquetWriter(tmp, schema, compression="zstd")
    if suffix in (".feather", ".arrow"):  # Feather v2 is the Arrow IPC file format
        import pyarrow as pa

        return pa.ipc.new_file(str(tmp), schema)
    return pacsv.CSVWriter(tmp, schema)


def _export_mdf(tf: TraceFile, out: str | Path, tmp: Path, lo, hi, columns, need) -> int:
    """MDF4 for CANape and asammdf users: one channel per column against the trace's time, with
    its unit; the alarm column as text."""
    try:
        from asammdf import MDF, Signal
    except ImportError:
        raise ValueError("writing .mf4 needs asammdf: pip install 'deltahil[mdf]'") from None
    import numpy as np
    import pyarrow as pa

    table = tf.table(need)
    if lo is not None or hi is not None:
        table = table.filter(slice_mask(table, lo, hi, {}))
    if table.num_rows == 0:
        raise empty_slice(tf, lo, hi) if lo is not None or hi is not None else ValueError(f"{tf.path}: empty trace")
    units = tf.units()
    t = table.column("t").to_numpy()
    signals = []
    for name in (columns or table.column_names):
        if name == "t":
            continue
        col = table.column(name)
        extra = {}
        if pa.types.is_string(col.type):
            samples = np.array([(v or "").encode() for v in col.to_pylist()], dtype="S32")
            extra["encoding"] = "utf-8"
        else:
            samples = col.to_numpy()
        signals.append(Signal(samples=samples, timestamps=t, name=name, unit=units.get(name, ""), **extra))
    mdf = MDF(version="4.10")
    meta = tf.meta
    mdf.append(signals, comment=f"deltahil trace of {meta.get('program', tf.path.name)}"
               + (f" on bench {meta['bench']['name']}" if "bench" in meta else ""))
    tmp = Path(out).with_name(f".{Path(out).stem}.part.mf4")  # asammdf adds .mf4 to any other suffix
    try:
        saved = Path(mdf.save(str(tmp), overwrite=True))
        mdf.close()
        saved.replace(out)
    finally:
        tmp.unlink(missing_ok=True)
    return table.num_rows


__all__ = ["Bound", "Summary", "export", "format_summary", "summarise"]
