"""NC-side homing against the simulated home switch (0x60FD bit 2), through the `hil script` Machine."""

from __future__ import annotations

import dataclasses

import pytest

from hil.bench import default_lathe
from hil.scripting import Machine

SWITCH_MM = 40.0  # machine position (before homing) of the X home switch edge; X starts at 60 mm


def _machine(start: float) -> tuple[Machine, int]:
    bench = default_lathe()
    x = bench.axes[0]
    cpu = x.scaling.counts_per_unit
    edge = int(round(SWITCH_MM * cpu))
    bench.axes[0] = dataclasses.replace(x, start=start, drive=dataclasses.replace(x.drive, home_switch=edge))
    m = Machine(bench)
    m.power_up()
    return m, edge


@pytest.mark.parametrize("start", [60.0, 25.0])  # off the switch, and on it (leaves it first)
def test_home_sets_machine_origin_at_the_switch_edge(start):
    m, edge = _machine(start)
    m.home("X")
    r = m.runner
    sc = r.scales[0]
    # The switch edge (drive counts `edge`) is now machine position 0 (the home position) within a count.
    assert abs(sc.to_units(edge) + r.origin[0]) <= 1.0 / sc.counts_per_unit
    assert m.command("X") == pytest.approx(0.0, abs=1e-9)
    assert m.get("M31320") == 1 and m.get("M31336") == 1  # homed, home done
    m.settle("X")
    assert abs(r.tx[0].position_actual - edge) <= 2  # ends standing on the edge
