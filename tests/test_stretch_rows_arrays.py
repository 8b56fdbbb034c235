"""A stretch's rows become arrays without numpy's conversion of Python lists value by value (decision bench B165):
the drives' feedback counts for the trace's columns (hil/stretch_bulk.py `_floats`) and the pass's filtered rows
(hil/stretch_pass.py `Pass.samples`). The trace must hold the same doubles, bit for bit, as numpy's conversion made
them: a count beyond 2^53 rounded to the nearest double, and what is not an int within int64 (a float, a huge count)
converted as before (B180: the int64 bytes now made by `struct`, not `array`). The CAM program stretched against stepped, column by column, is tests/test_stretch_cam.py."""

from __future__ import annotations

import numpy as np
import pytest

from hil.stretch_bulk import _floats


@pytest.mark.parametrize("counts", [
    [0, -1, 1_280_000, -2_147_483_648, 2_147_483_647],
    [2**53 + 1, -(2**53) - 3, 2**62 + 12345, -(2**63)],  # rounded to even doubles
    [True, False, 7],  # bools count as 1 and 0
    [1.5, 2, -0.25],  # a float among them: numpy's way
    [2**70, 1],  # beyond int64: numpy's way
    [2**63, -(2**63) - 1, 0],  # just outside int64 either side: numpy's way
    [np.int64(-5), np.int32(7), np.uint8(255)],  # numpy's integers (an index, as an int)
    [np.uint64(2**64 - 1), 3],  # a numpy integer beyond int64: numpy's way
    [],
])
def test_counts_are_numpys_doubles(counts: list) -> None:
    got = _floats(counts)
    want = np.array(counts, dtype=np.float64)
    assert got.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()

