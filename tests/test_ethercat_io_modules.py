"""R1-EC stations built from modules (`modules = ["DI32", "DO8"]` in an [[io]] table): the generated
ESI-like description, object dictionary and SII agree; the bench file reports bad module lists per
field; on EtherCAT (a veth pair in a netns the test creates and removes, root only) and on SimLink the
modules' points map to X/Y devices in module order, in lock-step simulated time."""

from __future__ import annotations

import struct
from types import SimpleNamespace

import pytest

from fieldbus.ethercat.link import EthercatLink
from fieldbus.link import BusError
from hil.bench_file import BenchFileError, parse_bench
from hil.commands.sim import build_chain
from hil.scripting import Machine
from hil.session import make_link
from mlc.machine import Mlc
from virtual_bus.ethercat.coe import ObjectDictionary
from virtual_bus.ethercat.device import load_device
from virtual_bus.ethercat.r1ec import MODULES, esi_xml, r1ec_device
from virtual_bus.ethercat.sii import build_sii
from virtual_bus.ethercat.veth import ForkedLine, can_create

AXES = '[[axes]]\nname = "X"\nstart = 10.0\n[[spindles]]\nname = "S1"\n'
# A: 32 inputs X0–X31, 8 outputs Y0–Y7. B: DO16 Y16–Y31, DI8 X32–X39, DI16 X40–X55. C: inputs only, X64–X71.
STATIONS = ('[[io]]\nname = "A"\nmodules = ["DI32", "DO8"]\n'
            '[[io]]\nname = "B"\nmodules = ["DO16", "DI8", "di16"]\n'
            '[[io]]\nname = "C"\nmodules = ["DI8"]\n')
ROOT_REASON = can_create()


def sii_sm_lengths(image: bytes) -> dict[int, int]:
    """SM type → length from the SyncManager category of an SII image."""
    pos = 128
    while True:
        kind, words = struct.unpack_from("<HH", image, pos)
        if kind in (0xFFFF, 0):
            return {}
        if kind == 41:
            return {image[pos + 4 + 8 * k + 7]: struct.unpack_from("<H", image, pos + 4 + 8 * k + 2)[0]
                    for k in range(words * 2 // 8)}
        pos += 4 + 2 * words


# ---- the generated description ---------------------------------------------------------------
def test_default_station_is_the_packaged_16_16_description():
    assert build_sii(r1ec_device()) == build_sii(load_device("r1-ec-dio"))
    assert load_device("r1-ec-dio").name == "R1-EC DIO 16/16"


def test_module_station_dictionary_pdos_and_sii_agree():
    dev = r1ec_device(["DI16", "DO16", "DI8", "DO32"])
    od = ObjectDictionary(dev, state=lambda: 2)
    assert od.mapping(0x1C13) == [(0x6000, 1, 16), (0x6010, 1, 8)]  # inputs in module order: 24 bits
    assert od.mapping(0x1C12) == [(0x7000, 1, 16), (0x7010, 1, 32)]  # outputs: 48 bits
    assert [p.index for p in dev.tx_pdos] == [0x1A00, 0x1A01] and [p.index for p in dev.rx_pdos] == [0x1600, 0x1601]
    assert [od.value(0xF050, k) for k in range(1, 5)] == [MODULES[m].ident for m in ("DI16", "DO16", "DI8", "DO32")]
    assert od.objects[0x7010].entries[1].bits == 32 and od.objects[0x6010].entries[1].bits == 8
    sii = build_sii(dev)
    assert sii_sm_lengths(sii) == {1: 128, 2: 128, 3: 0, 4: 0}  # process-data SMs sized from the mapping
    assert b"R1-EC DI16+DO16+DI8+DO32" in sii
    with pytest.raises(ValueError):
        esi_xml([])


# ---- the bench file ---------------------------------------------------------------------------
def test_modules_set_the_points_and_the_x_y_blocks_in_order():
    b = parse_bench(AXES + STATIONS)
    assert [(s.map.name, s.modules, s.map.x, s.map.inputs, s.map.y, s.map.outputs) for s in b.io] == [
        ("A", ("DI32", "DO8"), 0, 32, 0, 8), ("B", ("DO16", "DI8", "DI16"), 32, 24, 16, 16),
        ("C", ("DI8",), 64, 8, 32, 0)]
    assert parse_bench(AXES + "[[io]]\n").io[0].modules == ()  # no modules: the default DI16 + DO16 station


def test_bad_module_lists_are_reported_per_field():
    text = AXES + ('[[io]]\nmodules = ["DI16", "DI12", 7]\n'
                   '[[io]]\nmodules = ["DI32", "DI32", "DI8"]\n'
                   '[[io]]\nmodules = ["DI16", "DO8"]\ninputs = 32\n'
                   '[[io]]\nmodules = []\n'
                   '[[io]]\nmodules = ["DO32"]\ny = 1000\n')
    with pytest.raises(BenchFileError) as err:
        parse_bench(text)
    msgs = err.value.errors
    assert "io[0].modules[1]: unknown module 'DI12' (R1-EC modules: DI8, DI16, DI32, DO8, DO16, DO32)" in msgs
    assert "io[0].modules[2]: unknown module 7 (R1-EC modules: DI8, DI16, DI32, DO8, DO16, DO32)" in msgs
    assert "io[1].modules: 72 inputs / 0 outputs: a station has at most 64 of each" in msgs
    assert "io[2].inputs: 32, but modules DI16 + DO8 have 16" in msgs
    assert any(m.startswith("io[3].modules: must be a non-empty list") for m in msgs)
    assert "io: EIO-505: Y1000–Y1031 runs past Y1023" in msgs
    with pytest.raises(BenchFileError) as err:  # a bad list leaves the span unknown: no range error on top
        parse_bench(AXES + '[[io]]\nmodules = ["DI12", "DO16"]\nx = 1020\n')
    assert err.value.errors == ["io[0].modules[0]: unknown module 'DI12' (R1-EC modules: DI8, DI16, DI32, DO8, "
                                "DO16, DO32)"]


def test_overlapping_module_station_exits_2_without_traceback(hil, program, tmp_path):
    bench = tmp_path / "b.toml"
    bench.write_text(AXES + '[[io]]\nmodules = ["DI32"]\n[[io]]\nmodules = ["DI8", "DO8"]\nx = 24\n')
    r = hil("run", program("M30\n"), "--bench", bench)
    assert r.code == 2 and "io: EIO-502: X24–X31 overlaps EIO-501 (X0–X31)" in r.err, r.err
    assert "Traceback" not in r.err
    bench.write_text(AXES + '[[io]]\nmodules = ["AI4"]\n')
    r = hil("run", program("M30\n"), "--bench", bench)
    assert r.code == 2 and "io[0].modules[0]: unknown module 'AI4'" in r.err and "Traceback" not in r.err


# ---- X/Y mapping in module order: SimLink and EtherCAT -----------------------------------------
def loop_program(log: list):
    """Y0–Y7 (A's DO8) = X24–X31 (A's top byte); Y16–Y31 (B's DO16) = X40–X55 (B's DI16); log X per scan."""

    def scan(mlc):
        log.append((mlc.scan_count, [mlc.x(n) for n in (0, 31, 32, 39, 40, 55, 64, 71)]))
        for k in range(8):
            mlc.y(k, mlc.x(24 + k))
        for k in range(16):
            mlc.y(16 + k, mlc.x(40 + k))
    return SimpleNamespace(scan=scan)


def make_machine(bench, link, log):
    mlc = Mlc(loop_program(log), axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config())
    return Machine(bench, mlc, link)


def test_simlink_module_station_maps_inputs_and_outputs_in_module_order():
    log: list = []
    bench = parse_bench(AXES + STATIONS)
    m = make_machine(bench, make_link(bench), log)
    m.power_up()
    a, b, c = m.link.io_devices
    m.cycle(2)
    a.inputs = 1 << 31 | 1 << 26 | 1  # A's DI32 points 0, 26, 31
    b.inputs = 1 << 23 | 1 << 8 | 1 << 7 | 1 << 0  # B: DI8 points 0 and 7, DI16 points 0 and 15 (bits 8, 23)
    c.inputs = 0x81
    n = len(log)
    m.cycle(1)
    assert log[n][1] == [True] * 8  # X0, X31 (A), X32, X39, X40, X55 (B), X64, X71 (C) in the same cycle
    assert a.outputs == 1 << 7 | 1 << 2  # Y2 = X26, Y7 = X31 (A's DO8)
    assert b.outputs == 1 << 15 | 1  # Y16 = X40, Y31 = X55 (B's DI16 points 0 and 15)
    m.close()


@pytest.mark.skipif(ROOT_REASON is not None, reason=ROOT_REASON or "")
def test_ethercat_module_stations_map_x_and_y_in_module_order_in_lock_step():
    log: list = []
    bench = parse_bench(AXES + STATIONS)
    chain = build_chain(bench)
    assert [s.name for s in chain.slaves] == ["X", "S1", "A", "B", "C"]
    with ForkedLine(chain, "iom") as line:
        link = EthercatLink.for_bench(bench, line.iface)
        m = make_machine(bench, link, log)
        m.power_up()
        m.cycle(3)
        assert [link.io_bits(k) for k in range(3)] == [(32, 8), (24, 16), (8, 0)]  # SM lengths from the modules
        assert (m.get("M30032"), m.get("M30033"), m.get("M30034"), m.get("M30000")) == (1, 1, 1, 1)
        line.set_inputs(0, 1 << 31 | 1 << 26 | 1)
        line.set_inputs(1, 1 << 23 | 1 << 8 | 1 << 7 | 1 << 0)
        line.set_inputs(2, 0x81)
        n = len(log)
        m.cycle(1)
        assert log[n][1] == [True] * 8  # the scan of that very cycle (lock-step: inputs of frame N)
        assert line.outputs(0) == 0 and line.outputs(1) == 0  # Y written in that scan: on the next frame
        m.cycle(1)
        assert line.outputs(0) == 1 << 7 | 1 << 2  # Y2 (X26), Y7 (X31) → A's DO8 bits 2 and 7 (0x7000:1)
        assert line.outputs(1) == 1 << 15 | 1 << 0  # Y16 (X40) and Y31 (X55) → B's DO16 (0x7000:1)
        line.set_inputs(0, 0)
        m.cycle(2)
        assert line.outputs(0) == 0 and m.get("X31") == 0 and m.get("X71") == 1
        m.close()


@pytest.mark.skipif(ROOT_REASON is not None, reason=ROOT_REASON or "")
@pytest.mark.parametrize("modules, message", [
    ('["DO16", "DI16"]', "EIO-501 (EIO node 501) is set up as DO16 + DI16; the slave reports DI16 + DO16"),
    ('["DI32", "DO8"]', "EIO-501 (EIO node 501) needs 32 inputs / 8 outputs; EtherCAT has 16 inputs / 16 outputs"),
])
def test_a_station_built_otherwise_than_the_bench_says_raises_0x142e(modules, message):
    """The line carries the default DI16 + DO16 station; the master's bench declares other modules:
    the same size in another order (found by the slave's 0xF050 list), or other sizes."""
    chain = build_chain(parse_bench(AXES + "[[io]]\n"))
    bench = parse_bench(AXES + f"[[io]]\nmodules = {modules}\n")
    with ForkedLine(chain, "iox") as line:
        m = make_machine(bench, EthercatLink.for_bench(bench, line.iface), [])
        with pytest.raises(BusError) as err:
            m.power_up()
            m.cycle(2)
        m.close()
    assert err.value.alarm.code == 0x142E and message in err.value.alarm.message, err.value.alarm.message


@pytest.mark.skipif(ROOT_REASON is not None, reason=ROOT_REASON or "")
def test_a_station_with_no_slave_at_its_port_raises_0x142f():
    """App. A 0x142F 'The corresponding port number for the remote module (EIO) connection was not found': the
    line carries one I/O station, the bench declares two; the second (EIO node 502, the 2nd I/O slave in
    connection order) has no slave at its port."""
    chain = build_chain(parse_bench(AXES + "[[io]]\n"))
    bench = parse_bench(AXES + '[[io]]\n[[io]]\nname = "panel"\n')
    with ForkedLine(chain, "iop") as line:
        m = make_machine(bench, EthercatLink.for_bench(bench, line.iface), [])
        with pytest.raises(BusError) as err:
            m.power_up()
            m.cycle(2)
        m.close()
    alarm = err.value.alarm
    assert alarm.code == 0x142F, alarm.message
    assert "panel (EIO node 502) not found: only 1 I/O slaves on the line" in alarm.message


@pytest.mark.skipif(ROOT_REASON is not None, reason=ROOT_REASON or "")
def test_hil_sim_serves_the_bench_stations_and_hil_scan_names_their_modules(hil, tmp_path):
    from virtual_bus.ethercat.veth import SimProcess

    bench = tmp_path / "io.toml"
    bench.write_text(AXES + STATIONS)
    with SimProcess("--bench", str(bench), tag="ios") as sim:
        r = hil("scan", "--bus", f"ethercat:{sim.iface}")
    assert r.code == 0, r.err
    rows = r.out.splitlines()[2:]  # after the two drives: each station's name and module list (0x1008, 0xF050)
    assert [row.split("io", 1)[1].strip() for row in rows] == [
        "R1-EC DI32+DO8  [DI32+DO8]", "R1-EC DO16+DI8+DI16  [DO16+DI8+DI16]", "R1-EC DI8  [DI8]"], r.out


def test_module_idents_outside_the_catalogue_are_judged_by_size_only():
    """A real R1-EC lists Delta's own module idents in 0xF050, which this project cannot name: the
    station is then accepted if its image holds the declared points, refused (0x142E) if not."""
    from fieldbus.ethercat.io import EthercatIoPort

    class Line:  # the two EthercatLink calls the port makes after bring-up
        master, io = object(), [object()]

        def __init__(self, bits, modules):
            self.bits, self.modules = bits, modules

        def io_bits(self, k):
            return self.bits

        def io_modules(self, k):
            return self.modules

    declared = ("DI16", "DO16")
    EthercatIoPort(Line((16, 16), ["0x00C80210", "0x00C80310"]), 0, "A", 16, 16, declared)._check()
    for line in (Line((16, 16), ["DO16", "DI16"]), Line((8, 16), ["0x00C80210", "0x00C80310"])):
        with pytest.raises(BusError) as err:
            EthercatIoPort(line, 0, "A", 16, 16, declared)._check()
        assert err.value.alarm.code == 0x142E
