"""The SDO writes that give a CoE slave its PDO mapping and assignment (0x1600/0x1A00, 0x1C12/0x1C13)."""

from __future__ import annotations

import struct

from fieldbus.pdo import PdoLayout


def mapping_sdos(layout: PdoLayout) -> list[tuple[int, int, bytes]]:
    """The SDO writes (index, subindex, data) that configure `layout` entry by entry, as LinuxCNC
    (IgH) does and every CoE slave takes (ETG.1000.6 5.6.7.4.9): assignment off, mapping count 0,
    each entry, the count, then the PDO assigned and the assignment on."""
    out = []
    for assign, pdo, entries in ((0x1C12, layout.rx_index, layout.rx), (0x1C13, layout.tx_index, layout.tx)):
        out.append((assign, 0, b"\x00"))
        out.append((pdo, 0, b"\x00"))
        out += [(pdo, k, struct.pack("<I", e.index << 16 | e.subindex << 8 | e.bits)) for k, e in enumerate(entries, 1)]
        out.append((pdo, 0, bytes([len(entries)])))
        out.append((assign, 1, struct.pack("<H", pdo)))
        out.append((assign, 0, b"\x01"))
    return out


def mapping_sdos_complete(layout: PdoLayout) -> list[tuple[int, int, bytes]]:
    """The same configuration in three complete-access writes per direction (faster on a line of many
    drives); a drive that refuses complete access gets `mapping_sdos` instead."""
    out = []
    for assign, pdo, entries in ((0x1C12, layout.rx_index, layout.rx), (0x1C13, layout.tx_index, layout.tx)):
        words = [e.index << 16 | e.subindex << 8 | e.bits for e in entries]
        out.append((assign, 0, struct.pack("<BxH", 0, 0)))
        out.append((pdo, 0, struct.pack("<Bx" + "I" * len(words), len(words), *words)))
        out.append((assign, 0, struct.pack("<BxH", 1, pdo)))
    return out
