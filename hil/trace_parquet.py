"""Parquet traces through pyarrow: rows are buffered and written one row group at a time, so a
run of hours keeps at most one row group in memory and a crash loses at most that much."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from hil.trace import INT_COLUMNS

ROW_GROUP = 50_000  # rows per row group: ~50 s at 1 ms, a few MB in memory


def _type_of(name: str, value: float | int | str) -> pa.DataType:
    if name in INT_COLUMNS or name.endswith("_sw"):
        return pa.int64()
    if isinstance(value, str):
        return pa.string()
    if isinstance(value, (bool, int)):
        return pa.int64()
    return pa.float64()


class ParquetTrace:
    def __init__(self, path: str | Path, columns: list[str], row_group: int = ROW_GROUP) -> None:
        self.path = Path(path)
        self.columns = columns
        self.row_group = row_group
        self._tmp = self.path.with_name(self.path.name + ".part")
        self._tmp.touch()  # fail now, not at the first flush, if the place is not writable
        self._rows: list[Sequence[float | int | str]] = []
        self._schema: pa.Schema | None = None
        self._writer: pq.ParquetWriter | None = None
        self._closed = False

    def write(self, row: Sequence[float | int | str]) -> None:
        self._rows.append(tuple(row))
        if len(self._rows) >= self.row_group:
            self._flush()

    def _flush(self) -> None:
        if not self._rows:
            return
        if self._schema is None:
            first = self._rows[0]
            self._schema = pa.schema([(c, _type_of(c, v)) for c, v in zip(self.columns, first)])
            self._writer = pq.ParquetWriter(self._tmp, self._schema, compression="zstd")
        cols = list(zip(*self._rows))
        arrays = [pa.array(col, type=f.type) for col, f in zip(cols, self._schema)]
        assert self._writer is not None
        self._writer.write_table(pa.Table.from_arrays(arrays, schema=self._schema))
        self._rows.clear()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._flush()
        if self._writer is None:  # no rows at all: still a valid file with the columns
            self._schema = pa.schema([(c, pa.float64()) for c in self.columns])
            self._writer = pq.ParquetWriter(self._tmp, self._schema)
        self._writer.close()
        self._tmp.replace(self.path)
