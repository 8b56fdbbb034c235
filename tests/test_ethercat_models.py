"""Delta drive models on the EtherCAT bench (issue 23): the packaged multi-device ESI-like file agrees with
fieldbus.devices, a bench picks A3-E / B3-E / A2-E per axis or points a drive at a vendor ESI file, and
hil's master maps Delta's 0x1602/0x1A02 entry by entry (complete access only on request, with a
fallback when the drive refuses it)."""

from __future__ import annotations

import re
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

from fieldbus.devices import MODELS
from fieldbus.ethercat.link import EthercatLink
from fieldbus.ethercat.pdo_mapping import mapping_sdos
from fieldbus.pdo import ASDA_E
from virtual_bus.ethercat.device import load_device, parse_devices
from virtual_bus.ethercat.veth import SimProcess, can_create

ROOT = Path(__file__).resolve().parents[1]
PACKAGED = Path(str(resources.files("virtual_bus.ethercat") / "devices" / "delta_asda_e.xml"))


def test_packaged_file_holds_three_devices_equal_to_the_catalogue():
    devices = parse_devices(PACKAGED)
    assert [(d.vendor_id, d.product_code, d.revision) for d in devices] == \
        [(m.vendor_id, m.product_code, m.revision) for m in MODELS.values()]
    for key, m in MODELS.items():
        d = load_device(key)
        assert d.product_code == m.product_code and d.name == m.type_name
        for index, entries in m.rx_sets.items() | m.tx_sets.items():
            obj = d.objects[index]
            assert obj.max_sub == m.max_entries
            words = [obj.entries[k].value for k in range(1, obj.entries[0].value + 1)]
            assert words == [i << 16 | s << 8 | b for i, s, b in entries]
        for direction in "RT":
            flagged = {(i, e.sub) for i, o in d.objects.items() for e in o.entries.values() if e.pdo == direction}
            assert flagged == m.mappable(direction)
        assert d.objects[0x1C12].entries[1].value == m.default_rx and d.objects[0x1C13].entries[1].value == m.default_tx


def x_a3e_and_z(z: str) -> str:
    """A sim bench: X an A3-E named by model, Z as the TOML lines `z` say."""
    return 'bus = "sim"\n[[axes]]\nname = "X"\ndrive = { model = "asda-a3-e" }\n[[axes]]\nname = "Z"\n' + z


def test_resolution_follows_the_named_model(tmp_path):
    """A bench that names a model and no counts_per_rev converts with the model's default resolution (A3-E/B3-E
    24-bit: 16 777 216, A2-E: 1 280 000, decisions E11/E17); an explicit counts_per_rev wins; a bench naming no
    model keeps the generic 1 280 000. The master's conversion uses it: X10 on a 10 mm lead is one motor rev."""
    from fieldbus.link import SimLink
    from hil.bench_file import parse_bench
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from nc.program import parse_program

    bench = parse_bench(x_a3e_and_z('''counts_per_rev = 100000
drive = { model = "asda-b3-e" }
[[spindles]]
drive = { model = "asda-a2-e" }
'''))
    assert [a.scaling.counts_per_rev for a in bench.axes] == [16_777_216, 100_000]
    assert bench.spindles[0].scaling.counts_per_rev == 1_280_000
    assert parse_bench('[[axes]]\nname = "X"\n').axes[0].scaling.counts_per_rev == 1_280_000
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    result = runner.run_program(parse_program("G00 U20. W10.\nM30\n"))  # lathe: U on the diameter
    assert result.ok
    assert abs(runner.tx[0].position_actual - 16_777_216) <= 2 and abs(runner.tx[1].position_actual - 100_000) <= 2


def test_drive_defaults_in_counts_follow_the_resolution():
    """The sim drive's defaults held in counts (CSV ramp, quick-stop deceleration 0x6085, following-error
    window 0x6065) are the same physics at any resolution: on a 24-bit A3-E they are 16 777 216 / 1 280 000
    times the generic figures, so S1000 still takes the same 0.43 s to reach (decisions E17). A value the
    bench gives is taken as written."""
    from hil.bench_file import parse_bench
    from virtual_bus.drive import DriveParams

    bench = parse_bench(x_a3e_and_z('drive = { model = "asda-a3-e", csv_accel = 1.0e7 }\n'))
    generic, k = DriveParams(), 16_777_216 / 1_280_000
    x, z = bench.axes[0].drive, bench.axes[1].drive
    assert x.csv_accel == pytest.approx(generic.csv_accel * k) and z.csv_accel == 1.0e7
    assert x.quick_stop_decel == pytest.approx(generic.quick_stop_decel * k)
    assert x.following_error_window == int(generic.following_error_window * k)
    # rev/s² of the CSV ramp equal the generic drive's: 1000 rpm in the same time
    assert x.csv_accel / 16_777_216 == pytest.approx(generic.csv_accel / 1_280_000)


def test_asda_e_fits_every_model():
    """hil's default layout stays within each model's limits: 8 entries, mappable objects only. On the A3-E and
    B3-E it is the ESI's own 0x1602/0x1A02 contents (LCEC's sets; the drive's predefined set as is, only
    assigned), on the A2-E a remap of its 0x1602/0x1A02."""
    for key in ("asda-a3-e", "asda-b3-e"):
        m = MODELS[key]
        assert [(e.index, e.subindex, e.bits) for e in ASDA_E.rx] == list(m.rx_sets[ASDA_E.rx_index])
        assert [(e.index, e.subindex, e.bits) for e in ASDA_E.tx] == list(m.tx_sets[ASDA_E.tx_index])
    for m in MODELS.values():
        assert len(ASDA_E.rx) <= m.max_entries and len(ASDA_E.tx) <= m.max_entries
        assert {(e.index, e.subindex) for e in ASDA_E.rx} <= m.mappable("R")
        assert {(e.index, e.subindex) for e in ASDA_E.tx} <= m.mappable("T")


def test_master_maps_entry_by_entry():
    """As LinuxCNC (IgH) does: assignment off, count 0, entries, count, PDO assigned, assignment on."""
    sdos = mapping_sdos(ASDA_E)
    rx = [(i, s) for i, s, _ in sdos if i in (0x1C12, 0x1602)]
    assert rx[:2] == [(0x1C12, 0), (0x1602, 0)]
    assert rx[2:8] == [(0x1602, k) for k in range(1, 7)]
    assert rx[8:] == [(0x1602, 0), (0x1C12, 1), (0x1C12, 0)]
    assert all(len(d) in (1, 2, 4) for _, _, d in sdos)  # no complete-access blocks


def hil(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hil.cli", *args], capture_output=True, text=True, cwd=ROOT,
                          timeout=180)


def test_bench_refuses_an_unknown_model_and_a_missing_esi(tmp_path):
    bench = tmp_path / "b.toml"
    bench.write_text('[[axes]]\nname = "X"\ndrive = { model = "asda-z9" }\n'
                     '[[axes]]\nname = "Z"\ndrive = { model = "asda-b3-e", esi = "nowhere.xml" }\n')
    r = hil("run", str(ROOT / "examples" / "lathe_demo.nc"), "--bench", str(bench))
    assert r.returncode == 2
    assert "axes[0].drive.model" in r.stderr and "asda-a3-e, asda-b3-e, asda-a2-e" in r.stderr
    assert "axes[1].drive.esi" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_mixed_models_and_a_vendor_esi_without_complete_access(tmp_path):
    """X an A3-E, Z a B3-E built from a copy of the ESI that says CompleteAccess="0", S1 an A2-E. The
    bench asks for complete access; the B3-E refuses it (0x06010000) and is mapped entry by entry; the
    demo program completes and `hil scan` names each model."""
    esi = tmp_path / "vendor.xml"
    esi.write_text(PACKAGED.read_text().replace('CompleteAccess="1"', 'CompleteAccess="0"'))
    bench = tmp_path / "mixed.toml"
    bench.write_text(f'''
bus = "sim"
[params]
ethercat_complete_access = 1
[[axes]]
name = "X"
lead = 5.0
start = 60.0
drive = {{ model = "asda-a3-e" }}
[[axes]]
name = "Z"
lead = 10.0
start = 100.0
drive = {{ model = "asda-b3-e", esi = "{esi}" }}
[[spindles]]
name = "S1"
drive = {{ model = "asda-a2-e" }}
''')
    with SimProcess("--bench", str(bench), tag="m") as sim:
        scan = hil("scan", "--bus", f"ethercat:{sim.iface}")
        assert scan.returncode == 0, scan.stderr
        rows = scan.stdout.splitlines()
        assert [re.search(r"product 0x([0-9A-F]{8})", row).group(1) for row in rows] == \
            ["00006010", "00006080", "10305070"]
        assert "ASDA-B3-E CoE Drive" in rows[1] and "ASDA-A2-E CoE Drive" in rows[2]
        # the model's default resolution and units beside each drive (decisions E17)
        assert "[asda-a3-e: 16777216 counts/rev, velocity 0.1 rpm" in rows[0]
        assert "[asda-a2-e: 1280000 counts/rev" in rows[2]
        link = EthercatLink(sim.iface, names=["X", "Z", "S1"], complete_access=True)
        link.open()
        try:
            refused = [e for e in link.stats.events if "complete access refused" in e]
            assert len(refused) == 1 and refused[0].startswith("Z:") and "0x06010000" in refused[0]
            assert [i.state for i in link.infos] == ["OP"] * 3
        finally:
            link.close()
        r = hil("run", str(ROOT / "examples" / "lathe_demo.nc"), "--bench", str(bench),
                "--bus", f"ethercat:{sim.iface}")
        assert r.returncode == 0, r.stdout + r.stderr
        assert "result         completed" in r.stdout


# A vendor's ESI as ETG.2000 writes it: <DataTypes>, <Type> naming them, <Flags>, <Info><DefaultData> in
# little-endian hex, a Beckhoff-style mapping array, two devices in one file, and a <Modules> section.
VENDOR_ESI = """<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x1DD</Id><Name>Delta Electronics, Inc.</Name></Vendor>
<Descriptions><Groups><Group><Type>ASDA</Type><Name>Servo</Name></Group></Groups><Devices>
 <Device Physics="YY"><Type ProductCode="#x00006099" RevisionNo="#x1">Other</Type><Name>Other drive</Name>
  <Sm StartAddress="#x1000" DefaultSize="128" ControlByte="#x26" Enable="1">MBoxOut</Sm>
  <Sm StartAddress="#x1080" DefaultSize="128" ControlByte="#x22" Enable="1">MBoxIn</Sm></Device>
 <Device Physics="YY"><Type ProductCode="#x00006010" RevisionNo="#x00030000">ASDA-A3-E</Type>
  <Name>ASDA-A3-E CoE Drive</Name><GroupType>ASDA</GroupType>
  <Fmmu>Outputs</Fmmu><Fmmu>Inputs</Fmmu><Fmmu>MBoxState</Fmmu>
  <Sm StartAddress="#x1000" DefaultSize="256" ControlByte="#x26" Enable="1">MBoxOut</Sm>
  <Sm StartAddress="#x1200" DefaultSize="256" ControlByte="#x22" Enable="1">MBoxIn</Sm>
  <Sm StartAddress="#x1400" ControlByte="#x64" Enable="1">Outputs</Sm>
  <Sm StartAddress="#x1600" ControlByte="#x20" Enable="1">Inputs</Sm>
  <RxPdo Sm="2"><Index>#x1600</Index><Name>RxPDO 1</Name>
   <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><Name>Controlword</Name><DataType>UINT</DataType></Entry></RxPdo>
  <TxPdo Sm="3"><Index>#x1A00</Index><Name>TxPDO 1</Name>
   <Entry><Index>#x6041</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><Name>Statusword</Name><DataType>UINT</DataType></Entry></TxPdo>
  <Mailbox><CoE SdoInfo="1" PdoAssign="1" PdoConfig="1"/></Mailbox>
  <Profile><Dictionary>
   <DataTypes>
    <DataType><Name>DT1018</Name><BitSize>144</BitSize>
     <SubItem><SubIdx>0</SubIdx><Name>Number of entries</Name><Type>USINT</Type><BitSize>8</BitSize><Flags><Access>ro</Access></Flags></SubItem>
     <SubItem><SubIdx>1</SubIdx><Name>Vendor ID</Name><Type>UDINT</Type><BitSize>32</BitSize><Flags><Access>ro</Access></Flags></SubItem>
     <SubItem><SubIdx>2</SubIdx><Name>Product code</Name><Type>UDINT</Type><BitSize>32</BitSize><Flags><Access>ro</Access></Flags></SubItem></DataType>
    <DataType><Name>DT1600ARR</Name><BaseType>UDINT</BaseType><BitSize>256</BitSize><ArrayInfo><LBound>1</LBound><Elements>8</Elements></ArrayInfo></DataType>
    <DataType><Name>DT1600</Name><BitSize>272</BitSize>
     <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><Flags><Access>rw</Access></Flags></SubItem>
     <SubItem><Name>Elements</Name><Type>DT1600ARR</Type><BitSize>256</BitSize><Flags><Access>rw</Access></Flags></SubItem></DataType>
   </DataTypes>
   <Objects>
    <Object><Index>#x1000</Index><Name>Device type</Name><Type>UDINT</Type><BitSize>32</BitSize>
     <Info><DefaultData>92010200</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x1018</Index><Name>Identity</Name><Type>DT1018</Type><BitSize>144</BitSize>
     <Info><SubItem><Name>Number of entries</Name><Info><DefaultData>02</DefaultData></Info></SubItem>
      <SubItem><Name>Vendor ID</Name><Info><DefaultData>DD010000</DefaultData></Info></SubItem>
      <SubItem><Name>Product code</Name><Info><DefaultData>10600000</DefaultData></Info></SubItem></Info>
     <Flags><Access>ro</Access></Flags></Object>
    <Object><Index>#x1600</Index><Name>RxPDO 1</Name><Type>DT1600</Type><BitSize>272</BitSize><Flags><Access>rw</Access></Flags></Object>
    <Object><Index>#x6040</Index><Name>Controlword</Name><Type>UINT</Type><BitSize>16</BitSize>
     <Info><DefaultData>0000</DefaultData></Info><Flags><Access>rw</Access><PdoMapping>R</PdoMapping></Flags></Object>
    <Object><Index>#x6041</Index><Name>Statusword</Name><Type>UINT</Type><BitSize>16</BitSize>
     <Flags><Access>ro</Access><PdoMapping>RT</PdoMapping></Flags></Object>
   </Objects></Dictionary></Profile>
 </Device></Devices></Descriptions>
<Modules><Module><Type ModuleIdent="#x1">Unused</Type><Name>not a drive</Name></Module></Modules>
</EtherCATInfo>
"""


def test_a_vendor_esi_file_loads(tmp_path):
    """ETG.2000 object form (DataTypes, Flags, DefaultData), several devices in one file, a Modules
    section: the device of the model's product code is taken, with its objects and defaults."""
    from virtual_bus.ethercat.coe import ObjectDictionary
    from virtual_bus.ethercat.sii import build_sii

    path = tmp_path / "Delta_vendor.xml"
    path.write_text(VENDOR_ESI)
    assert [d.product_code for d in parse_devices(path)] == [0x6099, 0x6010]
    dev = load_device(str(path), MODELS["asda-a3-e"].product_code)
    assert dev.name == "ASDA-A3-E CoE Drive" and not dev.coe_complete_access
    od = ObjectDictionary(dev)
    assert od.value(0x1000) == 0x00020192 and od.value(0x1018, 1) == 0x1DD and od.value(0x1018, 2) == 0x6010
    assert od.objects[0x1600].max_sub == 8 and od.value(0x1600, 0) == 1 and od.value(0x1600, 1) == 0x60400010
    assert od.entry(0x6040, 0).pdo == "R" and "T" in od.entry(0x6041, 0).pdo
    assert build_sii(dev)[0x08 * 2 + 4:0x08 * 2 + 8] == (0x6010).to_bytes(4, "little")
    with pytest.raises(ValueError, match="no device with product code 0x00006080"):
        load_device(str(path), 0x6080)


ETG2000_FILE = ROOT / "tests" / "data" / "esi" / "Delta_ASDA-E_etg2000.xml"


def test_an_etg2000_vendor_file_equals_the_packaged_devices():
    """A vendor-form file (ETG.2000: <DataTypes>, typed <Objects> with <Info><DefaultData> and <Flags>, <RxPdo>/
    <TxPdo>, <Dc>, <Eeprom>, <Slots>, and a <Modules> section) holding all three Delta drives: the reader picks
    each by product code and gives the same object dictionary, entry by entry (value, size, type, access, PDO
    mapping), and the same SII image as the packaged description; a virtual drive built from it starts with
    the file's profile-mode defaults."""
    from virtual_bus.drive import Cia402Drive
    from virtual_bus.ethercat.app import DriveApp
    from virtual_bus.ethercat.coe import ObjectDictionary
    from virtual_bus.ethercat.sii import build_sii

    devices = parse_devices(ETG2000_FILE)
    assert [(d.vendor_id, d.product_code, d.revision) for d in devices] == \
        [(m.vendor_id, m.product_code, m.revision) for m in MODELS.values()]
    for key, m in MODELS.items():
        ours, theirs = load_device(key), load_device(str(ETG2000_FILE), m.product_code)
        assert set(theirs.objects) == set(ours.objects)
        for index, obj in ours.objects.items():
            for sub, e in obj.entries.items():
                f = theirs.objects[index].entries[sub]
                assert (f.value, f.bits, f.dtype, f.signed, f.access, f.pdo) == \
                    (e.value, e.bits, e.dtype, e.signed, e.access, e.pdo), (key, hex(index), sub)
        assert build_sii(theirs) == build_sii(ours)
        app = DriveApp(Cia402Drive())
        app.attach(ObjectDictionary(theirs))
        assert app.drive.modes.objects.homing_speed_switch == theirs.objects[0x6099].entries[1].value == 1000
        assert theirs.objects[0x6502].entries[0].value == 0x3A5


def test_hil_sim_ethercat_esi_refuses_a_file_without_the_drives_model(tmp_path):
    """`hil sim ethercat --esi FILE` needs the device of each drive's model in FILE: a file holding only another
    product is refused before anything is served, exit 2, naming the model and the codes the file has."""
    other = tmp_path / "other.xml"
    other.write_text(ETG2000_FILE.read_text().replace("#x00006010", "#x00006011"))  # no A3-E left in it
    r = hil("sim", "ethercat", "--bus", "ethercat:nowhere0", "--esi", str(other))
    assert r.returncode == 2, r.stderr
    assert "asda-a3-e" in r.stderr and "0x00006010" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_hil_sim_ethercat_builds_the_drives_from_a_vendor_esi(tmp_path):
    """`hil sim ethercat --esi FILE` builds the built-in lathe's drives (A3-E) from a vendor's ETG.2000 file:
    the name a master reads from the SII is the file's, and hil runs the demo against them."""
    esi = tmp_path / "vendor.xml"
    esi.write_text(ETG2000_FILE.read_text().replace("<Name>ASDA-A3-E CoE Drive</Name>",
                                                    "<Name>ASDA-A3-E from the vendor file</Name>"))
    with SimProcess("--esi", str(esi), tag="v") as sim:
        scan = hil("scan", "--bus", f"ethercat:{sim.iface}")
        assert scan.returncode == 0, scan.stderr
        rows = scan.stdout.splitlines()
        assert len(rows) == 3 and all("ASDA-A3-E from the vendor file" in row for row in rows), rows
        r = hil("run", str(ROOT / "examples" / "lathe_demo.nc"), "--bus", f"ethercat:{sim.iface}")
        assert r.returncode == 0 and "result         completed" in r.stdout, r.stdout + r.stderr


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_master_maps_over_a_drive_left_remapped():
    """A drive keeps the last mapping written until power-off: a LinuxCNC session before ours left lcec_deasda's
    0x1602 = 6040/60FF and 0x1A02 = 6041/606C/6064/2511 assigned. hil's master maps over it entry by entry, the
    line reaches OP with the ASDA_E image (15 bytes out, 23 in) and the drive's 0x1602/0x1A02 read back as ASDA_E."""
    import struct

    pysoem = pytest.importorskip("pysoem")
    lcec = {0x1602: [0x60400010, 0x60FF0020], 0x1A02: [0x60410010, 0x606C0020, 0x60640020, 0x25110020]}
    with SimProcess(tag="r") as sim:
        m = pysoem.Master()
        m.open(sim.iface)
        try:
            assert m.config_init() == 3
            for s in m.slaves:
                for index, words in lcec.items():
                    s.sdo_write(index, 0, b"\x00")
                    for k, w in enumerate(words, 1):
                        s.sdo_write(index, k, struct.pack("<I", w))
                    s.sdo_write(index, 0, bytes([len(words)]))
                for assign, pdo in ((0x1C12, 0x1602), (0x1C13, 0x1A02)):
                    s.sdo_write(assign, 0, b"\x00")
                    s.sdo_write(assign, 1, struct.pack("<H", pdo))
                    s.sdo_write(assign, 0, b"\x01")
        finally:
            m.close()
        link = EthercatLink(sim.iface, names=["X", "Z", "S1"])
        link.open()
        try:
            assert [i.state for i in link.infos] == ["OP"] * 3
            assert [(len(s.output), len(s.input)) for s in link.drives] == [(ASDA_E.rx_bytes, ASDA_E.tx_bytes)] * 3
            assert (ASDA_E.rx_bytes, ASDA_E.tx_bytes) == (15, 23)
            for pos in range(3):
                for index, entries in ((0x1602, ASDA_E.rx), (0x1A02, ASDA_E.tx)):
                    got = [int.from_bytes(link.sdo_read(pos, index, k), "little") for k in range(len(entries) + 1)]
                    assert got == [len(entries)] + [e.index << 16 | e.subindex << 8 | e.bits for e in entries]
        finally:
            link.close()
