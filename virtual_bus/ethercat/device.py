"""ESI-like device descriptions: identity, SyncManagers, default PDOs, DC and the CoE object
dictionary, read from one XML file. The SII image (`sii.py`) and the object dictionary
(`coe.py`) are both built from a `Device`, so they always agree."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from fieldbus.devices import MODELS

# CoE basic data types: name -> (CoE data type code, bits, signed)
TYPES: dict[str, tuple[int, int, bool]] = {
    "BOOL": (0x0001, 1, False), "SINT": (0x0002, 8, True), "INT": (0x0003, 16, True),
    "DINT": (0x0004, 32, True), "USINT": (0x0005, 8, False), "UINT": (0x0006, 16, False),
    "UDINT": (0x0007, 32, False),
}
VISIBLE_STRING = 0x0009
OBJ_VAR, OBJ_ARRAY, OBJ_RECORD = 7, 8, 9

SM_TYPES = {"MBoxOut": 1, "MBoxIn": 2, "Outputs": 3, "Inputs": 4}
FMMU_TYPES = {"Outputs": 1, "Inputs": 2, "MBoxState": 3}


def _int(text: str | None, default: int = 0) -> int:
    if text is None or not text.strip():
        return default
    t = text.strip()
    return int(t[2:], 16) if t.startswith("#x") else int(t, 0)


@dataclass
class OdEntry:
    sub: int
    name: str
    dtype: int
    bits: int
    signed: bool = False
    access: str = "ro"
    pdo: str = ""  # "R" RxPDO-mappable, "T" TxPDO-mappable
    value: int | bytes = 0

    @property
    def writable(self) -> bool:
        return "w" in self.access

    def encode(self) -> bytes:
        if isinstance(self.value, bytes):
            return self.value
        n = max(1, (self.bits + 7) // 8)
        return int(self.value).to_bytes(n, "little", signed=self.signed and int(self.value) < 0)

    def decode(self, data: bytes) -> int | bytes:
        if self.dtype == VISIBLE_STRING:
            return bytes(data)
        return int.from_bytes(data[: max(1, (self.bits + 7) // 8)], "little", signed=self.signed)


@dataclass
class OdObject:
    index: int
    name: str
    code: int  # OBJ_VAR / OBJ_ARRAY / OBJ_RECORD
    entries: dict[int, OdEntry] = field(default_factory=dict)

    @property
    def max_sub(self) -> int:
        return max(self.entries)


@dataclass(frozen=True)
class PdoEntryDef:
    index: int
    sub: int
    bits: int


@dataclass(frozen=True)
class PdoDef:
    index: int
    sm: int
    name: str
    entries: tuple[PdoEntryDef, ...]


@dataclass(frozen=True)
class SmDef:
    start: int
    size: int
    control: int
    enable: int
    kind: str  # MBoxOut / MBoxIn / Outputs / Inputs


@dataclass
class Device:
    vendor_id: int
    vendor_name: str
    product_code: int
    revision: int
    serial: int
    type_name: str
    name: str
    group: str
    kind: str  # "drive" or "io"
    fmmus: list[str]
    sms: list[SmDef]
    rx_pdos: list[PdoDef]
    tx_pdos: list[PdoDef]
    coe_sdo_info: bool
    coe_complete_access: bool
    assign_activate: int  # 0 = no DC; 0x0300 = SYNC0
    sync0_min: int = 0  # ns
    sync0_max: int = 0
    sync0_step: int = 0
    eeprom_bytes: int = 2048
    config_data: bytes = b""
    objects: dict[int, OdObject] = field(default_factory=dict)

    @property
    def mailbox_out(self) -> SmDef:
        return self.sms[0]

    @property
    def mailbox_in(self) -> SmDef:
        return self.sms[1]

    def sm_of(self, kind: str) -> int:
        return next(i for i, s in enumerate(self.sms) if s.kind == kind)


def _text(el: ET.Element, tag: str, default: str = "") -> str:
    child = el.find(tag)
    return child.text.strip() if child is not None and child.text else default


def _entry(sub: int, name: str, tname: str, access: str, pdo: str, default: str | None) -> OdEntry:
    m = re.fullmatch(r"STRING\((\d+)\)", tname)
    if m:
        n = int(m.group(1))
        raw = (default or "").encode()[:n].ljust(n, b" ")
        return OdEntry(sub, name, VISIBLE_STRING, 8 * n, False, access, pdo, raw)
    code, bits, signed = TYPES[tname]
    return OdEntry(sub, name, code, bits, signed, access, pdo, _int(default))


def _object(el: ET.Element, pdos: dict[int, PdoDef]) -> OdObject:
    index = _int(_text(el, "Index"))
    name = _text(el, "Name")
    tname = _text(el, "Type")
    access = _text(el, "Access", "ro")
    pdo = _text(el, "PdoMapping")
    default = _text(el, "Default")
    if tname == "RECORD":
        obj = OdObject(index, name, OBJ_RECORD)
        subs = el.findall("SubItem")
        # <SubIdx> numbers a record with gaps (0x1C32: 1-6, 9, 11, 12, 32); without it, 1, 2, 3, ...
        numbers = [_int(_text(s, "SubIdx"), i) for i, s in enumerate(subs, start=1)]
        obj.entries[0] = OdEntry(0, "Number of entries", 0x0005, 8, False, "ro", "", max(numbers, default=0))
        for i, s in zip(numbers, subs):
            obj.entries[i] = _entry(i, _text(s, "Name"), _text(s, "Type"), _text(s, "Access", "ro"),
                                    _text(s, "PdoMapping"), _text(s, "Default"))
        return obj
    m = re.fullmatch(r"(ARRAY|PDOMAP)\((?:(\w+),)?(\d+)\)", tname)
    if m:
        kind, elem, n = m.group(1), m.group(2) or "UDINT", int(m.group(3))
        obj = OdObject(index, name, OBJ_ARRAY)
        if kind == "PDOMAP":
            p = pdos.get(index)
            values = [e.index << 16 | e.sub << 8 | e.bits for e in p.entries] if p else []
        else:
            values = [_int(v) for v in default.split(",")] if default else []
        obj.entries[0] = OdEntry(0, "Number of entries", 0x0005, 8, False, access, "", len(values))
        for i in range(1, n + 1):
            obj.entries[i] = _entry(i, f"Subindex {i:03d}", elem, access, pdo,
                                    str(values[i - 1]) if i <= len(values) else "0")
        return obj
    obj = OdObject(index, name, OBJ_VAR)
    obj.entries[0] = _entry(0, name, tname, access, pdo, default)
    return obj


def _pdo(el: ET.Element) -> PdoDef:
    entries = tuple(PdoEntryDef(_int(_text(e, "Index")), _int(_text(e, "SubIndex")), _int(_text(e, "BitLen")))
                    for e in el.findall("Entry"))
    # A PDO without Sm="n" is not assigned at power-on (ESI); the SII marks it 0xFF.
    return PdoDef(_int(_text(el, "Index")), _int(el.get("Sm"), 0xFF), _text(el, "Name"), entries)


def parse_devices(source: str | Path) -> list[Device]:
    """Every device of an ESI-like file (a vendor's file describes several)."""
    root = ET.parse(source).getroot()
    vendor = root.find("Vendor")
    devs = root.findall("Descriptions/Devices/Device")
    if vendor is None or not devs:
        raise ValueError(f"{source}: not an ESI-like description (no Vendor or Device)")
    return [_device(vendor, dev) for dev in devs]


def parse_device(source: str | Path, product_code: int | None = None) -> Device:
    """The device of `product_code` in the file, or its first device."""
    devices = parse_devices(source)
    if product_code is None:
        return devices[0]
    for d in devices:
        if d.product_code == product_code:
            return d
    raise ValueError(f"{source}: no device with product code 0x{product_code:08X} "
                     f"(it has {', '.join(f'0x{d.product_code:08X}' for d in devices)})")


def _device(vendor: ET.Element, dev: ET.Element) -> Device:
    t = dev.find("Type")
    assert t is not None
    rx = [_pdo(e) for e in dev.findall("RxPdo")]
    tx = [_pdo(e) for e in dev.findall("TxPdo")]
    pdos = {p.index: p for p in rx + tx}
    coe = dev.find("Mailbox/CoE")
    opmode = dev.find("Dc/OpMode")
    cyc = opmode.find("CycleTimeSync0") if opmode is not None else None
    device = Device(
        vendor_id=_int(_text(vendor, "Id")), vendor_name=_text(vendor, "Name"),
        product_code=_int(t.get("ProductCode")), revision=_int(t.get("RevisionNo")), serial=_int(t.get("SerialNo")),
        type_name=(t.text or "").strip(), name=_text(dev, "Name"), group=_text(dev, "GroupType"),
        kind=dev.get("Kind", "drive"),
        fmmus=[(f.text or "").strip() for f in dev.findall("Fmmu")],
        sms=[SmDef(_int(s.get("StartAddress")), _int(s.get("DefaultSize")), _int(s.get("ControlByte")),
                   _int(s.get("Enable"), 1), (s.text or "").strip()) for s in dev.findall("Sm")],
        rx_pdos=rx, tx_pdos=tx,
        coe_sdo_info=coe is not None and coe.get("SdoInfo") == "1",
        coe_complete_access=coe is not None and coe.get("CompleteAccess") == "1",
        assign_activate=_int(_text(opmode, "AssignActivate")) if opmode is not None else 0,
        sync0_min=_int(cyc.get("Min")) if cyc is not None else 0,
        sync0_max=_int(cyc.get("Max")) if cyc is not None else 0,
        sync0_step=_int(cyc.get("Step")) if cyc is not None else 0,
        eeprom_bytes=_int(_text(dev, "Eeprom/ByteSize"), 2048),
        config_data=bytes.fromhex(_text(dev, "Eeprom/ConfigData", "")),
    )
    from virtual_bus.ethercat.esi_objects import esi_object, is_esi_object  # it builds on this module

    datatypes = {_text(t, "Name"): t for t in dev.findall("Profile/Dictionary/DataTypes/DataType")}
    for o in dev.findall("Profile/Dictionary/Objects/Object"):
        obj = esi_object(o, datatypes, pdos) if is_esi_object(o) else _object(o, pdos)
        device.objects[obj.index] = obj
    return device


# short name -> (packaged file, product code or None for the file's first device)
DEVICE_FILES: dict[str, tuple[str, int | None]] = {
    **{key: ("delta_asda_e.xml", m.product_code) for key, m in MODELS.items()},
    "r1-ec-dio": ("r1_ec_dio.xml", None),
}


def load_device(name: str, product_code: int | None = None) -> Device:
    """A packaged description by short name (asda-a3-e, asda-b3-e, asda-a2-e, r1-ec-dio), or an ESI(-like)
    file by path, then the device of `product_code` in it (default: its first)."""
    if name in DEVICE_FILES:
        fname, code = DEVICE_FILES[name]
        with resources.as_file(resources.files("virtual_bus.ethercat") / "devices" / fname) as p:
            return parse_device(p, code)
    return parse_device(name, product_code)
