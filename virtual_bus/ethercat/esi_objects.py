"""Objects as a vendor's ESI file writes them (ETG.2000): a `<Type>` that names a base type or a
`<DataType>` of the dictionary (records with `<SubItem>`s, arrays with `<ArrayInfo>`), defaults as
little-endian hex in `<Info><DefaultData>`, access and PDO mapping under `<Flags>`. The packaged
ESI-like files use the shorter inline form `device._object` reads; both give the same `OdObject`."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from virtual_bus.ethercat.device import (OBJ_ARRAY, OBJ_RECORD, OBJ_VAR, TYPES, VISIBLE_STRING, OdEntry, OdObject,
                                         PdoDef, _int, _text)


def is_esi_object(el: ET.Element) -> bool:
    return el.find("Flags") is not None or el.find("BitSize") is not None


def _hex_default(info: ET.Element | None) -> bytes | None:
    text = _text(info, "DefaultData") if info is not None else ""
    if text:
        try:
            return bytes.fromhex(text)
        except ValueError:
            return None
    value = _text(info, "DefaultValue") if info is not None else ""
    return _int(value).to_bytes(8, "little", signed=_int(value) < 0) if value else None


def _make(sub: int, name: str, tname: str, bits: int, access: str, pdo: str, raw: bytes | None) -> OdEntry:
    if tname.startswith("STRING") or tname == "VISIBLE_STRING":
        n = max(1, bits // 8)
        return OdEntry(sub, name, VISIBLE_STRING, 8 * n, False, access, pdo, (raw or b"")[:n].ljust(n, b" "))
    code, tbits, signed = TYPES.get(tname, (0x0007, bits or 32, False))
    bits = bits or tbits
    value = int.from_bytes((raw or b"\x00")[: max(1, (bits + 7) // 8)], "little", signed=signed)
    return OdEntry(sub, name, code, bits, signed, access, pdo, value)


def esi_object(el: ET.Element, datatypes: dict[str, ET.Element], pdos: dict[int, PdoDef]) -> OdObject:
    index, name, tname = _int(_text(el, "Index")), _text(el, "Name"), _text(el, "Type")
    access, pdo = _text(el, "Flags/Access", "ro"), _text(el, "Flags/PdoMapping")
    dt = datatypes.get(tname)
    if dt is None:  # a base type: one variable
        entry = _make(0, name, tname, _int(_text(el, "BitSize")), access, pdo, _hex_default(el.find("Info")))
        return OdObject(index, name, OBJ_VAR, {0: entry})
    defaults = {_text(s, "Name"): _hex_default(s.find("Info")) for s in el.findall("Info/SubItem")}
    obj = OdObject(index, name, OBJ_RECORD)
    for s in dt.findall("SubItem"):
        sname, stype = _text(s, "Name"), _text(s, "Type")
        sacc, spdo = _text(s, "Flags/Access", access), _text(s, "Flags/PdoMapping")
        arr = datatypes.get(stype)
        if arr is not None and arr.find("ArrayInfo") is not None:  # Beckhoff style: one SubItem holds the array
            obj.code = OBJ_ARRAY
            first, n = _int(_text(arr, "ArrayInfo/LBound"), 1), _int(_text(arr, "ArrayInfo/Elements"))
            base = _text(arr, "BaseType")
            bits = _int(_text(arr, "BitSize")) // max(n, 1)
            for k in range(first, first + n):
                key = f"SubIndex {k:03d}"
                obj.entries[k] = _make(k, key, base, bits, sacc, spdo, defaults.get(key))
            continue
        sub = _int(_text(s, "SubIdx"), len(obj.entries))
        obj.entries[sub] = _make(sub, sname, stype, _int(_text(s, "BitSize")), sacc, spdo, defaults.get(sname))
    if 0 not in obj.entries:
        obj.entries[0] = OdEntry(0, "Number of entries", 0x0005, 8, False, "ro", "", max(obj.entries, default=0))
    p = pdos.get(index)
    if p is not None:  # a PDO mapping object: its default entries are the ESI's <RxPdo>/<TxPdo>
        obj.entries[0].value = len(p.entries)
        for k, e in enumerate(p.entries, 1):
            if k in obj.entries:
                obj.entries[k].value = e.index << 16 | e.sub << 8 | e.bits
    return obj
