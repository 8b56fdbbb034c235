"""Per-cycle trace, written row by row so memory stays flat on long runs."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import IO, Protocol, Sequence


class TraceWriter(Protocol):
    columns: list[str]

    def write(self, row: Sequence[float | int | str]) -> None: ...

    def close(self) -> None: ...


def trace_columns(axes: Sequence[str], spindles: Sequence[str]) -> list[str]:
    cols = ["t", "line"]
    for a in axes:
        cols += [f"{a}_cmd", f"{a}_act", f"{a}_vel", f"{a}_torque", f"{a}_ferr", f"{a}_sw"]
    for s in spindles:
        cols += [f"{s}_rpm_cmd", f"{s}_rpm_act", f"{s}_torque", f"{s}_sw"]
    return cols


class CsvTrace:
    def __init__(self, path: str | Path, columns: list[str]) -> None:
        self.path = Path(path)
        self.columns = columns
        # Written to a side file and renamed on close, so a failed run never leaves half a trace
        # that looks complete.
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = self.path.with_name(self.path.name + ".part")
        self._fh: IO[str] = open(self._tmp, "w", newline="")
        self._w = csv.writer(self._fh)
        self._w.writerow(columns)

    def write(self, row: Sequence[float | int | str]) -> None:
        self._w.writerow(row)

    def close(self) -> None:
        if not self._fh.closed:
            self._fh.close()
            self._tmp.replace(self.path)
