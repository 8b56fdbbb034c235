"""The SII EEPROM image of a slave, generated from its device description (ETG.2010 layout:
identity words, mailbox words, then categories: strings, general, FMMU, SyncManager, PDOs)."""

from __future__ import annotations

import struct

from virtual_bus.ethercat.device import FMMU_TYPES, SM_TYPES, TYPES, Device

CAT_STRINGS, CAT_GENERAL, CAT_FMMU, CAT_SM, CAT_TXPDO, CAT_RXPDO, CAT_DC, CAT_END = 10, 30, 40, 41, 50, 51, 60, 0xFFFF
MBX_COE = 0x0004
COE_SDO, COE_SDO_INFO, COE_PDO_ASSIGN, COE_PDO_CONFIG, COE_COMPLETE_ACCESS = 0x01, 0x02, 0x04, 0x08, 0x20


def crc8(data: bytes) -> int:
    """The SII configuration-area checksum: CRC-8, polynomial x^8+x^2+x+1, seed 0xFF."""
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


class _Strings:
    def __init__(self) -> None:
        self.items: list[bytes] = []

    def index(self, s: str) -> int:
        b = s.encode("latin-1", "replace")[:255]
        if b not in self.items:
            self.items.append(b)
        return self.items.index(b) + 1


def _category(kind: int, data: bytes) -> bytes:
    if len(data) % 2:
        data += b"\x00"
    return struct.pack("<HH", kind, len(data) // 2) + data


def build_sii(dev: Device) -> bytes:
    strings = _Strings()
    name_idx = strings.index(dev.name)
    group_idx = strings.index(dev.group)
    type_idx = strings.index(dev.type_name)
    coe = COE_SDO | COE_PDO_ASSIGN | COE_PDO_CONFIG
    coe |= COE_SDO_INFO if dev.coe_sdo_info else 0
    coe |= COE_COMPLETE_ACCESS if dev.coe_complete_access else 0
    # group, image, order, name, reserved, CoE, FoE, EoE, SoE, DS402, sysman, flags, ebus current, ...
    general = struct.pack("<BBBBBBBBBBBBhBBHH12x", group_idx, 0, type_idx, name_idx, 0, coe, 0, 0, 0,
                          1 if dev.kind == "drive" else 0, 0, 0, 0, group_idx, 0, 0x0011, 0)
    fmmu = bytes(FMMU_TYPES[f] for f in dev.fmmus)
    sm = b"".join(struct.pack("<HHBBBB", s.start, s.size, s.control, 0, s.enable, SM_TYPES[s.kind]) for s in dev.sms)

    def pdo_cat(pdos) -> bytes:
        out = b""
        for p in pdos:
            out += struct.pack("<HBBBBH", p.index, len(p.entries), p.sm, 0, strings.index(p.name), 0)
            for e in p.entries:
                obj = dev.objects.get(e.index)
                entry = obj.entries.get(e.sub) if obj else None
                dtype = entry.dtype if entry else TYPES["UDINT"][0]
                nidx = strings.index(entry.name if obj and obj.code == 7 else (obj.name if obj else "")) if obj else 0
                out += struct.pack("<HBBBBH", e.index, e.sub, nidx, dtype, e.bits, 0)
        return out

    tx, rx = pdo_cat(dev.tx_pdos), pdo_cat(dev.rx_pdos)
    # ETG.2010 DC category: one op mode (cycle time 0 = the master's, shifts 0, AssignActivate, names)
    dc = struct.pack("<IIIhHhBB4x", 0, 0, 0, 0, dev.assign_activate, 0, strings.index("DC"),
                     strings.index("DC synchron (SYNC0)")) if dev.assign_activate else b""
    text = bytes([len(strings.items)]) + b"".join(bytes([len(s)]) + s for s in strings.items)

    head = bytearray(128)
    cfg = dev.config_data[:14].ljust(14, b"\x00")
    head[0:14] = cfg
    head[14] = crc8(cfg)
    struct.pack_into("<IIII", head, 0x08 * 2, dev.vendor_id, dev.product_code, dev.revision, dev.serial)
    mo, mi = dev.mailbox_out, dev.mailbox_in
    struct.pack_into("<HHHHH", head, 0x18 * 2, mo.start, mo.size, mi.start, mi.size, MBX_COE)
    struct.pack_into("<HH", head, 0x3E * 2, dev.eeprom_bytes * 8 // 1024 - 1, 1)
    body = (_category(CAT_STRINGS, text) + _category(CAT_GENERAL, general) + _category(CAT_FMMU, fmmu)
            + _category(CAT_SM, sm) + _category(CAT_TXPDO, tx) + _category(CAT_RXPDO, rx)
            + (_category(CAT_DC, dc) if dc else b"") + struct.pack("<H", CAT_END))
    image = bytes(head) + body
    if len(image) > dev.eeprom_bytes:
        raise ValueError(f"{dev.name}: SII image of {len(image)} bytes exceeds the {dev.eeprom_bytes}-byte EEPROM")
    return image.ljust(dev.eeprom_bytes, b"\xff")


def set_alias(sii: bytearray, alias: int) -> None:
    """Write the configured station alias (SII word 4, ETG.1000.6) and the config area's checksum (word 7)."""
    struct.pack_into("<H", sii, 8, alias)
    sii[14] = crc8(bytes(sii[:14]))
