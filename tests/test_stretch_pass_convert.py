"""A stretch over the NC's steps converts its filtered rows to the drives' target counts itself (hil/stretch_pass.py
`Pass._convert`, a drive check's new rows at once; decision bench B165 measured a mill's row-at-a-time variant and
dropped it). The counts must be the ones the stepped cycle writes to 0x607A (`AxisScaling.to_counts` of the position
less the axis origin): rounded half to even, reversed axes negative, for every axis count."""

from __future__ import annotations

import pytest

from fieldbus.units import AxisScaling
from hil.stretch_pass import Pass

SCALES = [AxisScaling(counts_per_rev=2560, lead=10.0), AxisScaling(counts_per_rev=1_280_000, lead=5.0),
          AxisScaling(counts_per_rev=1_280_000, lead=10.0, direction=-1)]
ORIGIN = [0.0, 12.5, -3.25]
# exact ties at 256 counts a mm (0.5, 1.5, -2.5 counts: half to even), and plain positions
ROWS = [[0.5 / 256, 0.0, 0.0], [1.5 / 256, 12.5 + 1e-6, -3.25], [-2.5 / 256, -40.123456, 100.000049],
        [123.456789, 7.0, -0.0000004], [-0.0, 12.5, -3.25]]


def _pass(n_axes: int, rows: list[list[float]]) -> Pass:
    ps = object.__new__(Pass)  # (only what _convert reads: the rows, the targets so far and each axis's scaling)
    ps.out_rows = [r[:n_axes] for r in rows]
    ps.converted = 0
    ps.targets = [[7] for _ in range(n_axes)]  # (the drive's target before the stretch)
    ps.to_counts = [(sc._cpu, ORIGIN[i]) for i, sc in enumerate(SCALES[:n_axes])]
    return ps


@pytest.mark.parametrize("n_axes", [1, 2, 3])
def test_targets_are_the_stepped_cycles_counts(n_axes: int) -> None:
    ps = _pass(n_axes, ROWS)
    ps._convert()  # the first drive check: two rows
    ps.converted, kept = 2, ps.out_rows
    ps.targets = [t[:3] for t in ps.targets]
    ps._convert()  # the rest at the next check
    for i in range(n_axes):
        want = [7] + [SCALES[i].to_counts(r[i] - ORIGIN[i]) for r in ROWS]
        assert ps.targets[i] == want
    assert ps.converted == len(kept)


def test_ties_round_to_even() -> None:
    ps = _pass(3, ROWS[:3])
    ps._convert()
    assert ps.targets[0] == [7, 0, 2, -2]  # 0.5, 1.5 and -2.5 counts
