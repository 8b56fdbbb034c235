"""App. A 0x1416 'The slave address does not match. The slave address is different from the system address
setting. Please confirm the slave address or reset.' on the veth bench: a bench drive's `drive.alias` names the
EtherCAT station alias (SII word 4) its slave must carry; `hil sim ethercat` gives its slaves the aliases of the
bench it serves."""

from __future__ import annotations

import pytest

from fieldbus.ethercat.link import EthercatLink
from hil.bench_file import load_bench_file
from hil.runner import BenchRunner
from nc.program import parse_program
from virtual_bus.ethercat.veth import SimProcess, can_create

REASON = can_create()
pytestmark = pytest.mark.skipif(REASON is not None, reason=REASON or "")

BENCH = """
name = "alias"
cycle_ms = 1.0
[[axes]]
name = "X"
drive = {{ alias = 11 }}
[[axes]]
name = "Z"
drive = {{ alias = {z} }}
"""
PROGRAM = "G00 U2. W-3.\nM30\n"


def _run(tmp_path, served: int, expected: int):
    served_path, run_path = tmp_path / "served.toml", tmp_path / "run.toml"
    served_path.write_text(BENCH.format(z=served))
    run_path.write_text(BENCH.format(z=expected))
    bench = load_bench_file(run_path)
    with SimProcess("--bench", str(served_path), tag="al") as sim:
        link = EthercatLink.for_bench(bench, sim.iface)
        return BenchRunner(bench, link).run_program(parse_program(PROGRAM))


def test_0x1416_the_z_slave_carries_another_station_alias(tmp_path):
    """The line's Z drive has alias 12, the bench expects 13: the bring-up stops with 0x1416 on Z before any drive
    is enabled; nothing moves."""
    result = _run(tmp_path, served=12, expected=13)
    assert [(a.code, a.axis) for a in result.alarms] == [(0x1416, "Z")]
    assert "station alias 12, the bench expects 13" in result.alarms[0].message
    assert not result.finished and result.enable_cycles == 0


def test_matching_station_aliases_run_the_program(tmp_path):
    result = _run(tmp_path, served=12, expected=12)
    assert result.alarms == [] and result.finished
    assert result.final["Z"] == pytest.approx(-3.0, abs=1e-3)
