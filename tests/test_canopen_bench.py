"""CANopen settings a bench file carries: the bus bitrate (`canopen_bitrate`, used by the bus budget
and handed to python-can adapters that set it) and per-drive / per-station device files
(`canopen_eds`, relative to the bench file, checked when the file is read). And the budget counts
the remote I/O stations' frames and heartbeats, not only the drives'."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldbus.canopen.budget import BusBudgetError, frame_bits
from fieldbus.canopen.link import CanopenLink, connect_args
from fieldbus.canopen.objects import ASDA_B3_EDS, DIO_EDS
from hil.bench_file import BenchFileError, load_bench_file, parse_bench
from hil.session import make_link
from tests.conftest import ROOT

DEMO = ROOT / "examples" / "lathe_demo.nc"

LATHE = """
bus = "canopen:virtual"
cycle_ms = {cycle}
{top}
[[axes]]
name = "X"
lead = 5.0
start = 60.0
{x}
[[axes]]
name = "Z"
start = 100.0
{z}
[[spindles]]
name = "S1"
{s}
"""


def lathe(cycle: float = 4.0, top: str = "", x: str = "", z: str = "", s: str = "", io: str = "") -> str:
    return LATHE.format(cycle=cycle, top=top, x=x, z=z, s=s) + io


def station(node: int, inputs: int, outputs: int, extra: str = "") -> str:
    return f"[[io]]\ncanopen_node = {node}\ninputs = {inputs}\noutputs = {outputs}\n{extra}\n"


# ---- bitrate ---------------------------------------------------------------------------------
def test_bench_bitrate_sets_the_budget_and_is_refused_when_not_a_cia301_rate():
    fast = CanopenLink.for_bench(parse_bench(lathe()), "socketcan", "vcan0")
    half = CanopenLink.for_bench(parse_bench(lathe(top="canopen_bitrate = 500000")), "socketcan", "vcan0")
    assert (fast.budget.bitrate, half.budget.bitrate) == (1_000_000, 500_000)
    assert half.budget.bits_per_s == fast.budget.bits_per_s  # same frames, half the wire
    assert half.budget.load == pytest.approx(2 * fast.budget.load)
    assert fast.budget_note is None and "of 500 kbit/s" in half.budget_note and "above 70%" in half.budget_note
    with pytest.raises(BusBudgetError, match=r"175\.3 % of 250 kbit/s"):
        CanopenLink.for_bench(parse_bench(lathe(top="canopen_bitrate = 250000")), "socketcan", "vcan0")
    with pytest.raises(BenchFileError) as exc:
        parse_bench(lathe(top="canopen_bitrate = 300000"))
    assert exc.value.errors == ["canopen_bitrate: must be one of 10000, 20000, 50000, 125000, 250000, 500000, "
                                "800000, 1000000, got 300000"]


def test_hil_run_refuses_a_bench_whose_bitrate_cannot_carry_it_with_exit_2(hil, tmp_path):
    bench = tmp_path / "slow.toml"
    bench.write_text(lathe(top="canopen_bitrate = 250000"))
    res = hil("run", DEMO, "--bench", bench, "--bus", "canopen:socketcan:vcan0")
    assert res.code == 2, res.out + res.err
    assert "of 250 kbit/s" in res.err and "exceeds the bus" in res.err and "Traceback" not in res.err
    bench.write_text(lathe(top='canopen_bitrate = "fast"'))
    res = hil("run", DEMO, "--bench", bench)
    assert res.code == 2 and "canopen_bitrate: must be an integer, got 'fast'" in res.err


def test_bitrate_goes_to_python_can_adapters_that_set_it_and_not_to_socketcan():
    assert connect_args("pcan", "PCAN_USBBUS1", 500_000) == {"interface": "pcan", "channel": "PCAN_USBBUS1",
                                                             "bitrate": 500_000}
    # socketcan's bit timing belongs to the kernel (ip link), udp_multicast has none
    assert "bitrate" not in connect_args("socketcan", "can0", 500_000)
    assert "bitrate" not in connect_args("udp_multicast", "239.74.163.2", 500_000)


# ---- EDS per drive / per station ------------------------------------------------------------------
def _custom_eds(folder: Path, product: int, source: Path = ASDA_B3_EDS, name: str = "asda_variant.eds") -> Path:
    """A shipped EDS with another product code (0x1018:2), as a vendor's variant would be."""
    folder.mkdir(parents=True, exist_ok=True)
    text = source.read_text(encoding="utf-8")
    head, sep, rest = text.partition("[1018sub2]")
    assert sep, "the shipped EDS has an identity object"
    block, nxt, tail = rest.partition("\n[")
    lines = [f"DefaultValue=0x{product:08X}" if ln.startswith("DefaultValue=") else ln for ln in block.split("\n")]
    path = folder / name
    path.write_text(head + sep + "\n".join(lines) + nxt + tail, encoding="utf-8")
    return path


def test_drive_eds_is_resolved_next_to_the_bench_file_and_used_by_master_and_simulated_node(tmp_path):
    _custom_eds(tmp_path / "devices", 0x6081)
    bench_file = tmp_path / "bench.toml"
    bench_file.write_text(lathe(z='canopen_eds = "devices/asda_variant.eds"'))
    bench = load_bench_file(bench_file)
    assert bench.axes[1].canopen_eds == str((tmp_path / "devices" / "asda_variant.eds").resolve())
    assert bench.axes[0].canopen_eds == "" and bench.spindles[0].canopen_eds == ""
    link = make_link(bench)
    assert [Path(str(c.eds)).name for c in link.nodes_cfg] == ["delta_asda_b3.eds", "asda_variant.eds",
                                                                "delta_asda_b3.eds"]
    try:
        infos = link.open()  # identity read over SDO from each node's object dictionary
    finally:
        link.close()
    assert [i.product_code for i in infos] == [0x6080, 0x6081, 0x6080]


def test_station_eds_is_used_by_the_simulated_station_on_the_virtual_bus(tmp_path):
    _custom_eds(tmp_path / "devices", 0x0401_0042, DIO_EDS, "dio_variant.eds")
    bench_file = tmp_path / "bench.toml"
    bench_file.write_text(lathe(io=station(64, 16, 16, 'canopen_eds = "devices/dio_variant.eds"')))
    link = make_link(load_bench_file(bench_file))
    try:
        infos = link.open()  # the station's identity is read over SDO from the simulated node
    finally:
        link.close()
    assert [i.product_code for i in infos if i.kind == "io"] == [0x0401_0042]


@pytest.mark.parametrize("where, value, message", [
    ("z", '"devices/none.eds"', "EDS file {tmp}/devices/none.eds not found"),
    ("z", '"garbage.eds"', "EDS file {tmp}/garbage.eds cannot be parsed: File contains no section headers."),
    ("s", f'"{(ROOT / "fieldbus/canopen/eds/delta_dio_401.eds").as_posix()}"',
     "lacks objects 0x60C2:1, 0x60C2:2, 0x1401:1"),
    ("io", '"devices/none.eds"', "EDS file {tmp}/devices/none.eds not found"),
    ("io", f'"{ASDA_B3_EDS.as_posix()}"', "lacks objects 0x6000:1, 0x6000:2, 0x6200:1, 0x6200:2 the master uses"),
])
def test_a_missing_or_unusable_eds_is_a_per_field_error_with_exit_2(hil, tmp_path, where, value, message):
    (tmp_path / "garbage.eds").write_text("garbage\n[[[\n")
    key = f"canopen_eds = {value}"
    text = (lathe(z=key) if where == "z" else lathe(s=key) if where == "s" else
            lathe(io=station(64, 16, 16, key)))
    bench = tmp_path / "bench.toml"
    bench.write_text(text)
    field = {"z": "axes[1].canopen_eds", "s": "spindles[0].canopen_eds", "io": "io[0].canopen_eds"}[where]
    res = hil("run", DEMO, "--bench", bench)
    assert res.code == 2, res.out + res.err
    assert f"{bench}: {field}: " in res.err and message.format(tmp=tmp_path.resolve()) in res.err
    assert "Traceback" not in res.err


# ---- the budget counts the I/O stations ------------------------------------------------------------
def test_budget_counts_each_io_stations_pdos_and_heartbeat():
    drives_only = CanopenLink.for_bench(parse_bench(lathe(cycle=4.0)), "socketcan", "vcan0").budget
    stations = station(64, 16, 16) + station(65, 8, 0) + station(66, 0, 64) + station(67, 20, 8,
                                                                                      'canopen_tpdo = "change"')
    bench = parse_bench(lathe(cycle=4.0, top="canopen_bitrate = 1000000", io=stations))
    link = CanopenLink.for_bench(bench, "socketcan", "vcan0")
    with_io = link.budget
    # 16/16: RPDO 2 B + TPDO 2 B; 8/0: TPDO 1 B; 0/64: RPDO 8 B; 20/8 on change: RPDO 1 B + TPDO 3 B
    # (a change-of-state TPDO is counted once a cycle: the worst case)
    frames = [2, 2, 1, 8, 1, 3]
    assert with_io.frames_per_cycle - drives_only.frames_per_cycle == len(frames) == 6
    assert with_io.bits_per_cycle - drives_only.bits_per_cycle == sum(frame_bits(n) for n in frames) == 500
    # and one 1-byte heartbeat per station every producer period (100 ms on a real wire)
    assert with_io.heartbeat_bits_per_s - drives_only.heartbeat_bits_per_s == pytest.approx(4 * 65 / 0.1)
    assert with_io.load - drives_only.load == pytest.approx((500 / 0.004 + 4 * 65 / 0.1) / 1e6)


def test_io_stations_push_a_bench_that_fitted_over_the_bus_limit():
    """2 ms with three drives is 87 % (a warning); two 64/64 stations add 2 × (135 + 135) bit a cycle,
    +27 %: refused, with the cycle that would fit."""
    two_full = station(64, 64, 64) + station(65, 64, 64)
    fits = CanopenLink.for_bench(parse_bench(lathe(cycle=2.0)), "socketcan", "vcan0")
    assert fits.budget.load == pytest.approx(0.8725 + 3 * 65 / 0.1 / 1e6)
    with pytest.raises(BusBudgetError, match=r"114\.6 % of 1000 kbit/s: 19 frames \(2285 bit worst case\).*at least 2\.29 ms"):
        CanopenLink.for_bench(parse_bench(lathe(cycle=2.0, io=two_full)), "socketcan", "vcan0")
