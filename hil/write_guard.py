"""A trace that cannot be written ends the run under control (bench decision B97).

A full disk, a file system gone read-only, an I/O error: the trace's write raises OSError in the middle of a cycle
(a CSV row's buffered flush, a Parquet part handed back by its writer thread). Left alone it ended the run as an NC
internal error with the drives' quick stop, and every later cycle of the stop wrote and raised again, so the stop
itself broke off and a half-written CSV was left looking complete. Guarded, the first failure raises deltahil's
alarm 0xDE04 once (the channel stops along the path, as for any alarm), later rows are dropped, and at the end the
partial trace is removed — nothing half-written is left; the summary says why.

The trace object stays what it is (the bulk path knows a Parquet trace by its type, B85): its `write`,
`write_columns` and `close` are wrapped on the instance.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any


class TraceGuard:
    def __init__(self, trace: Any, fail: Callable[[OSError], None]) -> None:
        self.trace = trace
        self.fail = fail
        self.failed: OSError | None = None
        path = getattr(trace, "path", None)
        self._files = [Path(path), Path(f"{path}.meta.json"), Path(f"{path}.meta.json.part")] if path else []
        self._before = {p: _stamp(p) for p in self._files}  # an earlier run's files there are not ours to remove
        cls = type(trace)
        self._write = cls.write.__get__(trace)
        self._close = cls.close.__get__(trace)
        trace.write = self.write
        trace.close = self.close
        if hasattr(cls, "write_columns"):
            self._write_columns = cls.write_columns.__get__(trace)
            trace.write_columns = self.write_columns

    def write(self, row: Any) -> None:
        if self.failed is None:
            try:
                self._write(row)
            except OSError as exc:
                self._failed(exc)

    def write_columns(self, cols: Any, n: int) -> None:
        if self.failed is None:
            try:
                self._write_columns(cols, n)
            except OSError as exc:
                self._failed(exc)

    def close(self, end: dict[str, Any] | None = None) -> None:
        if self.failed is None:
            try:
                self._close(end)
                return
            except OSError as exc:  # the last rows or the end record did not fit
                self._failed(exc)
        self._remove()

    def _failed(self, exc: OSError) -> None:
        self.failed = exc
        self.fail(exc)

    def _remove(self) -> None:
        try:
            self.trace.discard()  # its .part (CSV) or parts folder (Parquet)
        except OSError:
            pass
        for p in self._files:  # what this run renamed into place before the failure (a CSV's rows, its record)
            if _stamp(p) != self._before[p]:
                try:
                    p.unlink()
                except OSError:
                    pass


def _stamp(p: Path) -> tuple[int, int] | None:
    try:
        st = os.stat(p)
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns
