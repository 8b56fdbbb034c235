"""Write tests/data/esi/Delta_ASDA-E_etg2000.xml: the packaged Delta devices in the form of a vendor ESI file
(ETG.2000). Run `python tests/data/esi/make_etg2000.py` from the repository root after the packaged
description changes; test_ethercat_models.py::test_an_etg2000_vendor_file_equals_the_packaged_devices fails
until then."""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from xml.sax.saxutils import escape
from fieldbus.devices import MODELS  # noqa: E402
from virtual_bus.ethercat.device import load_device, OBJ_VAR, VISIBLE_STRING  # noqa: E402

NAMES = {0x0001: "BOOL", 0x0002: "SINT", 0x0003: "INT", 0x0004: "DINT", 0x0005: "USINT", 0x0006: "UINT", 0x0007: "UDINT"}

def tname(e):
    return f"STRING({e.bits // 8})" if e.dtype == VISIBLE_STRING else NAMES[e.dtype]

def hexdata(e):
    if isinstance(e.value, bytes):
        return e.value.hex().upper()
    n = max(1, (e.bits + 7) // 8)
    return int(e.value).to_bytes(n, "little", signed=e.signed and int(e.value) < 0).hex().upper()

def flags(e, indent):
    pdo = f"<PdoMapping>{e.pdo}</PdoMapping>" if e.pdo else ""
    return f"<Flags><Access>{e.access}</Access>{pdo}</Flags>"

out = ['<?xml version="1.0" encoding="utf-8"?>',
 '<!-- Test fixture: the three Delta ASDA-E drives deltahil packages (virtual_bus/ethercat/devices/delta_asda_e.xml),',
 '     written in the form a vendor ESI file uses, per ETG.2000 (EtherCAT Slave Information Specification):',
 '     one <EtherCATInfo> with <Vendor>, <Descriptions><Groups>/<Devices>/<Modules>; each <Device> with <Type>',
 '     (ProductCode, RevisionNo), <Name>, <GroupType>, <Fmmu>, <Sm>, <RxPdo>/<TxPdo> (Sm, Index, Entry), <Mailbox><CoE>,',
 '     <Dc><OpMode>, <Eeprom>, and <Profile><Dictionary> with <DataTypes> (records as DataType with SubItems,',
 '     arrays with ArrayInfo) and <Objects> whose <Type> names a base type or a DataType, defaults as',
 '     little-endian hex in <Info><DefaultData>, access and PDO mapping in <Flags>. A <Modules> section',
 '     (ETG.2000: modules for modular devices, ModuleIdent) and a device <Slots> element are included, as a',
 '     vendor file may have them; a drive without modules ignores them. Generated from the packaged',
 '     file by tests/data/esi/make_etg2000.py; tests/test_ethercat_models.py::test_an_etg2000_vendor_file_equals_the_packaged_devices checks the two',
 '     readers agree object by object. -->',
 '<EtherCATInfo Version="1.6">',
 '  <Vendor><Id>#x000001DD</Id><Name>Delta Electronics, Inc.</Name></Vendor>',
 '  <Descriptions>',
 '    <Groups><Group><Type>ASDA</Type><Name>Delta AC Servo Drives</Name></Group></Groups>',
 '    <Devices>']
for key, m in MODELS.items():
    d = load_device(key)
    out.append(f'      <Device Physics="YY">')
    out.append(f'        <Type ProductCode="#x{d.product_code:08X}" RevisionNo="#x{d.revision:08X}">{escape(m.type_name.split(" CoE")[0])}</Type>')
    out.append(f'        <Name>{escape(d.name)}</Name><GroupType>{d.group}</GroupType>')
    out += [f'        <Fmmu>{f}</Fmmu>' for f in d.fmmus]
    out += [f'        <Sm StartAddress="#x{s.start:04X}" DefaultSize="{s.size}" ControlByte="#x{s.control:02X}" Enable="{s.enable}">{s.kind}</Sm>' for s in d.sms]
    for tag, pdos in (("RxPdo", d.rx_pdos), ("TxPdo", d.tx_pdos)):
        for p in pdos:
            sm = f' Sm="{p.sm}"' if p.sm != 0xFF else ""
            out.append(f'        <{tag}{sm}><Index>#x{p.index:04X}</Index><Name>{escape(p.name)}</Name>')
            for e in p.entries:
                out.append(f'          <Entry><Index>#x{e.index:04X}</Index><SubIndex>{e.sub}</SubIndex><BitLen>{e.bits}</BitLen></Entry>')
            out.append(f'        </{tag}>')
    ca = "1" if d.coe_complete_access else "0"
    out.append(f'        <Mailbox><CoE SdoInfo="{int(d.coe_sdo_info)}" PdoAssign="1" PdoConfig="1" CompleteAccess="{ca}"/></Mailbox>')
    if d.assign_activate:
        out.append(f'        <Dc><OpMode><Name>DC</Name><Desc>DC-Synchron</Desc><AssignActivate>#x{d.assign_activate:04X}</AssignActivate>'
                   f'<CycleTimeSync0 Min="{d.sync0_min}" Max="{d.sync0_max}" Step="{d.sync0_step}">0</CycleTimeSync0></OpMode></Dc>')
    out.append(f'        <Slots><Slot MinInstances="0" MaxInstances="0"><Name>none</Name></Slot></Slots>')
    out.append(f'        <Eeprom><ByteSize>{d.eeprom_bytes}</ByteSize><ConfigData>{d.config_data.hex().upper()}</ConfigData></Eeprom>')
    out.append('        <Profile><Dictionary>')
    types, objs = [], []
    for index in sorted(d.objects):
        o = d.objects[index]
        if o.code == OBJ_VAR:
            e = o.entries[0]
            objs.append(f'          <Object><Index>#x{index:04X}</Index><Name>{escape(o.name)}</Name><Type>{tname(e)}</Type><BitSize>{e.bits}</BitSize>'
                        f'<Info><DefaultData>{hexdata(e)}</DefaultData></Info>{flags(e, "")}</Object>')
            continue
        dt = f"DT{index:04X}"
        bits = sum(max(8, e.bits) for e in o.entries.values())
        t = [f'          <DataType><Name>{dt}</Name><BitSize>{bits}</BitSize>']
        infos = []
        for sub in sorted(o.entries):
            e = o.entries[sub]
            t.append(f'            <SubItem><SubIdx>{sub}</SubIdx><Name>{escape(e.name)}</Name><Type>{tname(e)}</Type><BitSize>{e.bits}</BitSize>{flags(e, "")}</SubItem>')
            infos.append(f'<SubItem><Name>{escape(e.name)}</Name><Info><DefaultData>{hexdata(e)}</DefaultData></Info></SubItem>')
        t.append('          </DataType>')
        types += t
        objs.append(f'          <Object><Index>#x{index:04X}</Index><Name>{escape(o.name)}</Name><Type>{dt}</Type><BitSize>{bits}</BitSize>'
                    f'<Info>{"".join(infos)}</Info><Flags><Access>ro</Access></Flags></Object>')
    out.append('         <DataTypes>'); out += types; out.append('         </DataTypes>')
    out.append('         <Objects>'); out += objs; out.append('         </Objects>')
    out.append('        </Dictionary></Profile>')
    out.append('      </Device>')
out += ['    </Devices>',
        '    <Modules>',
        '      <Module><Type ModuleIdent="#x00006011">ASDA-E-OPT</Type><Name>Option module (no process data)</Name></Module>',
        '    </Modules>',
        '  </Descriptions>',
        '</EtherCATInfo>', '']
open(ROOT / "tests" / "data" / "esi" / "Delta_ASDA-E_etg2000.xml", "w").write("\n".join(out))
