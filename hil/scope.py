"""The live scope of `hil run --scope`: a page on 127.0.0.1 that streams chosen trace columns while
the run goes, like TwinCAT Scope or halscope on a real bench.

The cyclic path pays only for what the trace already does: `ScopeTap` sits where the runner writes
its trace rows and appends a reference to each row to a bounded deque (one O(1) append, no lock, no
copy). The HTTP server runs in its own daemon threads; every `PUSH_S` it takes the rows newer than
what that browser already has (`deque.copy()` is atomic under the GIL), picks the chosen columns,
thins them to at most `MAX_PUSH` points and sends them as one Server-Sent Event. The page is served
by this server with Plotly's JavaScript from the installed plotly package: it needs no network.

After the run the page stays up until every connected browser has had the last rows, or for
`linger` seconds when none is connected (Ctrl-C leaves at once): a short lock-step run can still be
watched from its first row, since the ring keeps the newest `RING_ROWS` rows; `--scope-wait` holds
the run until a browser has the page open."""

from __future__ import annotations

import json
import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Callable, Sequence

from hil.stop_signals import SignalStop
from hil.trace import TraceWriter, axes_of, spindles_of

RING_ROWS = 60_000  # newest rows kept for a browser that connects late (60 s of 1 ms cycles)
PUSH_S = 0.1  # one event per browser every 100 ms: 10 updates a second, as a scope redraws
MAX_PUSH = 500  # rows per event at most; more are thinned (every k-th row) for drawing only


def default_columns(columns: Sequence[str]) -> list[str]:
    """Axis command/actual position and following error, spindle commanded/actual rpm."""
    out = [f"{a}_{k}" for a in axes_of(columns) for k in ("cmd", "act", "ferr")]
    out += [f"{s}_rpm_{k}" for s in spindles_of(columns) for k in ("cmd", "act")]
    return [c for c in out if c in columns]


def choose_columns(spec: str | None, columns: Sequence[str]) -> list[str]:
    """`--scope-columns X_cmd,Z_ferr`: names of trace columns; ValueError names the unknown ones."""
    if not spec:
        return default_columns(columns)
    chosen = [c.strip() for c in spec.split(",") if c.strip()]
    unknown = [c for c in chosen if c not in columns]
    if unknown or not chosen:
        raise ValueError(f"--scope-columns: unknown column(s) {', '.join(unknown) or '(none given)'}; "
                         f"this run's trace has {', '.join(c for c in columns if c not in ('t', 'cycle'))}")
    return chosen


def group_of(column: str) -> tuple[str, float]:
    """Plot a column belongs to and the factor to its unit there."""
    if column.endswith("_ferr"):
        return "following error (µm)", 1000.0
    if "_rpm_" in column:
        return "spindle (rpm)", 1.0
    if column.endswith(("_cmd", "_act")):
        return "position (mm)", 1.0
    return column, 1.0


class ScopeTap:
    """A TraceWriter that passes every row on to the real trace (if any) and keeps a reference to
    it in a ring for the scope's server thread."""

    def __init__(self, inner: TraceWriter | None, columns: list[str]) -> None:
        self.inner = inner
        self.columns = columns
        self.ring: deque[tuple[int, Sequence[Any]]] = deque(maxlen=RING_ROWS)
        self.n = 0  # rows written so far
        self.ended = False

    def write(self, row: Sequence[float | int | str]) -> None:
        if self.inner is not None:
            self.inner.write(row)
        self.n += 1
        self.ring.append((self.n, row))  # the runner builds a new list every cycle: no copy needed

    def close(self, end: dict[str, Any] | None = None) -> None:
        if self.inner is not None:
            self.inner.close(end)
        self.ended = True

    def discard(self) -> None:
        if self.inner is not None:
            self.inner.discard()
        self.ended = True

    def newer_than(self, seq: int) -> list[tuple[int, Sequence[Any]]]:
        """Rows after `seq`, oldest first (called from the server thread)."""
        rows = self.ring.copy()
        if not rows or rows[-1][0] <= seq:
            return []
        start = max(0, len(rows) - (rows[-1][0] - seq))
        return list(rows)[start:]


def _num(v: Any, f: float) -> float | None:
    try:
        x = float(v) * f
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None  # JSON has no NaN


@dataclass
class Scope:
    """`hil run --scope`: start() before the run, attach() once the trace columns are known,
    linger() after the run's summary is printed, close() at the end."""

    spec: str | None = None
    linger_s: float = 30.0
    port: int = 0
    wait: bool = False  # --scope-wait: hil.run holds the run for a browser once its inputs are checked
    tap: ScopeTap | None = None
    chosen: list[str] = field(default_factory=list)
    _server: ThreadingHTTPServer | None = None
    _clients: int = 0
    _delivered_end: int = 0
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def start(self) -> str:
        """Bind 127.0.0.1 on a free port (or `port`) and serve from a daemon thread; the URL."""
        scope = self

        class Handler(_Handler):
            owner = scope

        self._server = ThreadingHTTPServer(("127.0.0.1", self.port), Handler)
        self._server.daemon_threads = True
        threading.Thread(target=self._server.serve_forever, name="hil-scope", daemon=True).start()
        return self.url

    @property
    def url(self) -> str:
        assert self._server is not None
        return f"http://127.0.0.1:{self._server.server_address[1]}/"

    def attach(self, trace: TraceWriter | None, columns: list[str]) -> ScopeTap:
        """Wrap the run's trace writer; ValueError for unknown --scope-columns."""
        self.chosen = choose_columns(self.spec, columns)
        self.tap = ScopeTap(trace, columns)
        return self.tap

    def wait_for_browser(self, out: Any, stopped: Callable[[], str | None] = lambda: None) -> None:
        """`--scope-wait`: hold the run until a page is open, so it is watched from its first row. `stopped`: the
        signal that asked the run to stop meanwhile (hil.stop_signals), which ends the command as it would end
        it outside a run (SIGINT: interrupted; SIGTERM/SIGHUP: stopped by it, 128 + n)."""
        print(f"scope: waiting for a browser at {self.url} before the run starts (Ctrl-C to stop)",
              file=out, flush=True)
        while True:
            with self._lock:
                if self._clients:
                    return
            name = stopped()
            if name is not None:
                raise KeyboardInterrupt(name) if name == "SIGINT" else SignalStop(name)
            time.sleep(0.05)

    def linger(self, out: Any) -> None:
        """Keep the page up until connected browsers have the last rows, else for linger_s."""
        if self.tap is None or self._server is None:
            return
        self.tap.ended = True
        deadline = time.monotonic() + self.linger_s
        told = False
        try:
            while time.monotonic() < deadline:
                with self._lock:
                    clients, done = self._clients, self._delivered_end
                if done and clients == 0:
                    return  # every browser that watched has had the end
                if not told:
                    print(f"scope: run ended; the page stays at {self.url} for up to {self.linger_s:g} s "
                          "or until the browser has the last rows (Ctrl-C leaves now)", file=out, flush=True)
                    told = True
                time.sleep(PUSH_S)
        except KeyboardInterrupt:
            return

    def close(self) -> None:
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
            self._server = None

    # ---- what the server thread sends --------------------------------------------------------
    def header(self) -> dict[str, Any]:
        tap = self.tap
        cols = self.chosen
        return {"columns": cols, "groups": [group_of(c)[0] for c in cols]} if tap else {"columns": []}

    def batch(self, rows: list[tuple[int, Sequence[Any]]]) -> dict[str, Any]:
        assert self.tap is not None
        k = max(1, math.ceil(len(rows) / MAX_PUSH))
        pick = rows[::k]
        if pick[-1] is not rows[-1]:
            pick.append(rows[-1])  # the newest row always reaches the page
        idx = {c: i for i, c in enumerate(self.tap.columns)}
        ti = idx["t"]
        out: dict[str, Any] = {"t": [_num(r[ti], 1.0) for _, r in pick], "line": pick[-1][1][idx["line"]],
                               "y": [[_num(r[idx[c]], group_of(c)[1]) for _, r in pick] for c in self.chosen]}
        return out


class _Handler(BaseHTTPRequestHandler):
    owner: Scope

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - no access log on the run's stderr
        pass

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        if self.path in ("/", "/index.html"):
            self._send(200, "text/html; charset=utf-8", PAGE.encode())
        elif self.path == "/plotly.js":
            from plotly.offline import get_plotlyjs

            self._send(200, "application/javascript", get_plotlyjs().encode())
        elif self.path == "/stream":
            self._stream()
        else:
            self._send(404, "text/plain", b"not found")

    def _send(self, code: int, ctype: str, body: bytes) -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def _event(self, kind: str, data: Any) -> None:
        self.wfile.write(f"event: {kind}\ndata: {json.dumps(data)}\n\n".encode())
        self.wfile.flush()

    def _stream(self) -> None:
        """Server-Sent Events: `header` once, `rows` every PUSH_S while there are new ones, `end`."""
        scope = self.owner
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-cache")
        self.end_headers()
        with scope._lock:
            scope._clients += 1
        try:
            while scope.tap is None:  # the page opened before the run's columns were known
                time.sleep(PUSH_S)
            self._event("header", scope.header())
            seq = 0
            while True:
                ended = scope.tap.ended
                rows = scope.tap.newer_than(seq)
                if rows:
                    seq = rows[-1][0]
                    self._event("rows", scope.batch(rows))
                elif ended:
                    self._event("end", {"rows": seq})
                    with scope._lock:
                        scope._delivered_end += 1
                    return
                time.sleep(PUSH_S)
        except (BrokenPipeError, ConnectionResetError):
            return  # the browser went away
        finally:
            with scope._lock:
                scope._clients -= 1


PAGE = """<!doctype html><html><head><meta charset="utf-8"><title>hil scope</title><link rel="icon" href="data:,">
<script src="/plotly.js"></script>
<style>body{font-family:sans-serif;margin:.5em 1em}#status{color:#555}</style></head><body>
<h2>hil scope <span id="status">connecting…</span></h2><div id="scope" style="height:85vh"></div>
<script>
const KEEP = 20000;  // points per trace kept on the page
let groups = [], total = 0, src = null, pend = null, last = null, ended = false;
// the stream opens after the page's load event: an event stream still open would hold 'load' back
window.addEventListener('load', () => {
src = new EventSource('/stream');
src.addEventListener('header', ev => {
  const h = JSON.parse(ev.data);
  groups = [...new Set(h.groups)];
  const data = h.columns.map((c, i) => {
    const g = groups.indexOf(h.groups[i]) + 1;
    return {x: [], y: [], name: c, mode: 'lines', type: 'scatter', xaxis: 'x', yaxis: g === 1 ? 'y' : 'y' + g};
  });
  const layout = {grid: {rows: groups.length, columns: 1, pattern: 'coupled'}, showlegend: true,
                  margin: {t: 20, l: 70, r: 20, b: 40}, xaxis: {title: {text: 'time (s)'}}};
  groups.forEach((g, i) => { layout['yaxis' + (i ? i + 1 : '')] = {title: {text: g}}; });
  Plotly.newPlot('scope', data, layout, {responsive: true});
});
src.addEventListener('rows', ev => {
  const b = JSON.parse(ev.data);
  if (!pend) pend = {t: [], y: b.y.map(() => [])};
  pend.t.push(...b.t); b.y.forEach((y, i) => pend.y[i].push(...y));
  last = b;
});
src.addEventListener('end', ev => { ended = true; src.close(); });
// draw at most 4 times a second, whatever the stream's rate: the page stays responsive
setInterval(() => {
  if (pend) {
    const n = pend.y.length;
    Plotly.extendTraces('scope', {x: Array(n).fill(pend.t), y: pend.y}, [...Array(n).keys()], KEEP);
    total += pend.t.length; pend = null;
  }
  if (last) document.getElementById('status').textContent =
    `${ended ? 'run ended' : 'running'} · t=${last.t[last.t.length - 1].toFixed(3)} s · line ${last.line} · ${total} rows`;
}, 250);
});
</script></body></html>"""
