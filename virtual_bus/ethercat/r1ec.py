"""The ESI-like description of an R1-EC remote I/O station built from its module list.

A Delta R1-EC station is a coupler plus digital I/O modules (8, 16 or 32 points each), exposed to
the master as ONE slave. The description follows the modular device profile's numbering, counted per
direction so the default 16/16 station keeps its objects (docs/decisions/ethercat.md, E10):

  i-th input module   data 0x6000 + 0x10·i (sub 1: USINT/UINT/UDINT), TxPDO 0x1A00 + i
  j-th output module  data 0x7000 + 0x10·j, RxPDO 0x1600 + j
  0x1C13 / 0x1C12     every TxPDO / RxPDO in module order, 0xF050 the module ident list

so the process image holds the modules' points in module order: input bit p of the image is the
station's X(x + p), output bit p its Y(y + p). The SII (`sii.py`) and the object dictionary
(`coe.py`) are both made from the `Device` this XML parses into, so SM lengths always agree.
"""

from __future__ import annotations

import io
from collections.abc import Sequence

from fieldbus.ethercat.r1ec_modules import DEFAULT_MODULES, MODULES, Module, points, split
from virtual_bus.ethercat.device import Device, parse_device

__all__ = ["DEFAULT_MODULES", "MODULES", "Module", "esi_xml", "points", "r1ec_device", "split", "title"]

PRODUCT_CODE = 0x00005601
_STATION_BYTES_MAX = 128  # the SM2/SM3 windows (0x1100 / 0x1180) hold 128 bytes each


def title(modules: Sequence[str]) -> str:
    """Device name: "R1-EC DIO 16/16" for the default, the module list otherwise."""
    if tuple(modules) == DEFAULT_MODULES:
        return "R1-EC DIO 16/16"
    return "R1-EC " + "+".join(modules)


def esi_xml(modules: Sequence[str] = DEFAULT_MODULES) -> str:
    """The ESI-like XML of a station with these modules (the format `device.parse_device` reads)."""
    ins, outs = split(modules)
    if not ins and not outs:
        raise ValueError("an R1-EC station needs at least one module")
    if max(sum(m.points for m in ins), sum(m.points for m in outs)) > 8 * _STATION_BYTES_MAX:
        raise ValueError("an R1-EC station's image exceeds its 128-byte SyncManager window")
    name = title(modules)

    def pdos(tag: str, base_pdo: int, base_obj: int, mods: list[Module], sm: int, what: str) -> list[str]:
        return [f'        <{tag} Sm="{sm}">\n'
                f"          <Index>#x{base_pdo + k:04X}</Index><Name>{what} module {k + 1} ({m.name})</Name>\n"
                f"          <Entry><Index>#x{base_obj + 0x10 * k:04X}</Index><SubIndex>1</SubIndex>"
                f"<BitLen>{m.points}</BitLen></Entry>\n"
                f"        </{tag}>\n" for k, m in enumerate(mods)]

    def obj(index: int, oname: str, otype: str, access: str = "ro", extra: str = "") -> str:
        return (f"            <Object><Index>#x{index:04X}</Index><Name>{oname}</Name><Type>{otype}</Type>"
                f"<Access>{access}</Access>{extra}</Object>\n")

    def assign(base: int, n: int) -> str:
        return ",".join(f"#x{base + k:04X}" for k in range(n))

    objects = [
        obj(0x1000, "Device type", "UDINT", extra="<Default>#x00030191</Default>"),
        obj(0x1001, "Error register", "USINT", extra="<Default>0</Default>"),
        obj(0x1008, "Device name", f"STRING({len(name)})", extra=f"<Default>{name}</Default>"),
        "            <Object><Index>#x1018</Index><Name>Identity</Name><Type>RECORD</Type>\n"
        "              <SubItem><Name>Vendor ID</Name><Type>UDINT</Type><Access>ro</Access><Default>#x000001DD</Default></SubItem>\n"
        f"              <SubItem><Name>Product code</Name><Type>UDINT</Type><Access>ro</Access><Default>#x{PRODUCT_CODE:08X}</Default></SubItem>\n"
        "              <SubItem><Name>Revision number</Name><Type>UDINT</Type><Access>ro</Access><Default>#x00010000</Default></SubItem>\n"
        "              <SubItem><Name>Serial number</Name><Type>UDINT</Type><Access>ro</Access><Default>0</Default></SubItem>\n"
        "            </Object>\n",
    ]
    objects += [obj(0x1600 + k, f"Output module {k + 1} mapping", "PDOMAP(1)") for k in range(len(outs))]
    objects += [obj(0x1A00 + k, f"Input module {k + 1} mapping", "PDOMAP(1)") for k in range(len(ins))]
    objects += [
        obj(0x1C00, "Sync manager type", "ARRAY(USINT,4)", extra="<Default>1,2,3,4</Default>"),
        obj(0x1C12, "RxPDO assign", f"ARRAY(UINT,{max(1, len(outs))})", extra=f"<Default>{assign(0x1600, len(outs))}</Default>"),
        obj(0x1C13, "TxPDO assign", f"ARRAY(UINT,{max(1, len(ins))})", extra=f"<Default>{assign(0x1A00, len(ins))}</Default>"),
    ]
    objects += [obj(0x6000 + 0x10 * k, f"Digital inputs {k + 1}", f"ARRAY({m.ctype},1)",
                    extra="<PdoMapping>T</PdoMapping><Default>0</Default>") for k, m in enumerate(ins)]
    objects += [obj(0x7000 + 0x10 * k, f"Digital outputs {k + 1}", f"ARRAY({m.ctype},1)", "rw",
                    extra="<PdoMapping>R</PdoMapping><Default>0</Default>") for k, m in enumerate(outs)]
    idents = ",".join(f"#x{MODULES[m].ident:08X}" for m in modules)
    objects.append(obj(0xF050, "Detected module ident list", f"ARRAY(UDINT,{len(modules)})",
                       extra=f"<Default>{idents}</Default>"))
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n'
        f"<!-- ESI-like description of a Delta R1-EC class remote I/O station (virtual): coupler with modules\n"
        f"     {', '.join(modules)}, exposed as one slave. Generated by virtual_bus/ethercat/r1ec.py; the product\n"
        "     code and module idents are this project's own (docs/decisions/ethercat.md, E6/E10). -->\n"
        '<EtherCATInfo Version="1.6">\n'
        "  <Vendor><Id>#x000001DD</Id><Name>Delta Electronics, Inc.</Name></Vendor>\n"
        "  <Descriptions>\n"
        "    <Groups><Group><Type>R1-EC</Type><Name>Delta Remote I/O</Name></Group></Groups>\n"
        "    <Devices>\n"
        '      <Device Physics="YY" Kind="io">\n'
        f'        <Type ProductCode="#x{PRODUCT_CODE:08X}" RevisionNo="#x00010000" SerialNo="#x00000000">R1-EC5601</Type>\n'
        f"        <Name>{name}</Name>\n"
        "        <GroupType>R1-EC</GroupType>\n"
        "        <Fmmu>Outputs</Fmmu>\n"
        "        <Fmmu>Inputs</Fmmu>\n"
        "        <Fmmu>MBoxState</Fmmu>\n"
        '        <Sm DefaultSize="128" StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>\n'
        '        <Sm DefaultSize="128" StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>\n'
        '        <Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>\n'
        '        <Sm StartAddress="#x1180" ControlByte="#x20" Enable="1">Inputs</Sm>\n'
        + "".join(pdos("RxPdo", 0x1600, 0x7000, outs, 2, "Output"))
        + "".join(pdos("TxPdo", 0x1A00, 0x6000, ins, 3, "Input"))
        + '        <Mailbox><CoE SdoInfo="1" CompleteAccess="1" PdoAssign="0" PdoConfig="0"/></Mailbox>\n'
        "        <Eeprom><ByteSize>2048</ByteSize><ConfigData>050E03440A000000</ConfigData></Eeprom>\n"
        "        <Profile>\n"
        "          <ProfileNo>401</ProfileNo>\n"
        "          <Dictionary><Objects>\n"
        + "".join(objects)
        + "          </Objects></Dictionary>\n"
        "        </Profile>\n"
        "      </Device>\n"
        "    </Devices>\n"
        "  </Descriptions>\n"
        "</EtherCATInfo>\n"
    )


def r1ec_device(modules: Sequence[str] = DEFAULT_MODULES) -> Device:
    """The parsed description of a station with these modules."""
    return parse_device(io.StringIO(esi_xml(modules)))
