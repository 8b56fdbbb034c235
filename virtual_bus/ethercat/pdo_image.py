"""A virtual slave's process-data image compiled once per PDO mapping (issue 17): the object
dictionary entries in image order and one `struct.Struct` per direction, so a frame costs one
unpack and one pack instead of an object lookup, an `int.from_bytes` and a `to_bytes` per entry.

The bytes are the ones the entry-by-entry route (`unpack_generic` / `pack_generic`) gives: outputs
read with each entry's signedness, inputs written as the value masked to the entry's width.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass

from fieldbus.pdo import RxPdo, TxPdo

from virtual_bus.ethercat.coe import ObjectDictionary
from virtual_bus.ethercat.device import VISIBLE_STRING, OdEntry

Mapping = list[tuple[int, int, int]]  # (index, subindex, bits) per mapped entry, as ObjectDictionary.mapping
_CODES = {8: "b", 16: "h", 32: "i", 64: "q"}


def unpack_generic(data: bytes | memoryview, mapping: Mapping, od: ObjectDictionary) -> None:
    """Outputs into their objects entry by entry (mappings a `PdoImage` cannot take)."""
    pos = 0
    for index, sub, bits in mapping:
        n = bits // 8
        e = od.objects[index].entries[sub]
        od.set(index, sub, int.from_bytes(data[pos:pos + n], "little", signed=e.signed))
        pos += n


def pack_generic(mapping: Mapping, od: ObjectDictionary) -> bytes:
    out = bytearray()
    for index, sub, bits in mapping:
        n = bits // 8
        v = od.value(index, sub)
        out += (v & ((1 << bits) - 1)).to_bytes(n, "little")
    return bytes(out)


@dataclass(frozen=True, slots=True)
class PdoImage:
    """One direction of a mapping: its entries, their width masks and the two structs."""

    entries: tuple[OdEntry, ...]
    masks: tuple[int, ...]
    reader: struct.Struct  # each entry's signedness: the values int.from_bytes(signed=e.signed) gives
    writer: struct.Struct  # unsigned: the masked values' bytes, as to_bytes writes them

    @classmethod
    def compile(cls, mapping: Mapping, od: ObjectDictionary) -> "PdoImage | None":
        """None when an entry is missing, not byte-wide or not an integer (the generic route then
        decides, and fails, as before)."""
        entries = []
        for index, sub, bits in mapping:
            obj = od.objects.get(index)
            e = obj.entries.get(sub) if obj is not None else None
            if e is None or bits not in _CODES or e.dtype == VISIBLE_STRING or not isinstance(e.value, int):
                return None
            entries.append(e)
        widths = [b for _, _, b in mapping]
        reader = "<" + "".join(_CODES[b] if e.signed else _CODES[b].upper() for e, b in zip(entries, widths))
        return cls(tuple(entries), tuple((1 << b) - 1 for b in widths), struct.Struct(reader),
                   struct.Struct("<" + "".join(_CODES[b].upper() for b in widths)))

    def read(self, data: bytes | memoryview) -> None:
        """The outputs in `data` (bytes or a memoryview of the SM2 area) into their entries."""
        for e, v in zip(self.entries, self.reader.unpack_from(data)):
            e.value = v

    def write(self) -> bytes:
        return self.writer.pack(*[e.value & m for e, m in zip(self.entries, self.masks)])  # type: ignore[operator]  # int entries only (compile)


class Images:
    """The compiled images of the mapping in force; recompiled when the ESC hands over new mapping
    lists (it makes new ones on every SAFE-OP entry)."""

    def __init__(self) -> None:
        self._maps: tuple[object, object] = (None, None)
        self.rx: PdoImage | None = None
        self.tx: PdoImage | None = None

    def get(self, rx_map: Mapping, tx_map: Mapping, od: ObjectDictionary) -> "Images":
        if self._maps[0] is not rx_map or self._maps[1] is not tx_map:
            self.rx, self.tx = PdoImage.compile(rx_map, od), PdoImage.compile(tx_map, od)
            self._maps = (rx_map, tx_map)
        return self

    def unpack(self, data: bytes | memoryview, rx_map: Mapping, od: ObjectDictionary) -> None:
        if self.rx is not None:
            self.rx.read(data)
        else:
            unpack_generic(data, rx_map, od)

    def pack(self, tx_map: Mapping, od: ObjectDictionary) -> bytes:
        return self.tx.write() if self.tx is not None else pack_generic(tx_map, od)


class DriveCodec:
    """A drive's process data in one generated function per direction (issue 17), for `DriveApp`:
    `read_rx(data, mode)` stores the outputs in their entries, as `PdoImage.read` does, and returns the
    `RxPdo` the drive latches (fields the mapping does not carry come from their entries, `mode` where
    the dictionary has no 0x6060); `write_tx(fb)` stores a `TxPdo` in the entries, as `DriveApp._publish`
    does, and returns the input image `PdoImage.write` would pack from them. The dictionary ends up as
    the entry-by-entry route leaves it; only the per-entry loops, lookups and temporaries are gone."""

    def __init__(self, read_rx: Callable[..., RxPdo], write_tx: Callable[[TxPdo], bytes]) -> None:
        self.read_rx, self.write_tx = read_rx, write_tx

    @classmethod
    def compile(cls, rx_map: Mapping, tx_map: Mapping, od: ObjectDictionary, rx_attr: dict[tuple[int, int], str],
                tx_attr: dict[tuple[int, int], str]) -> "DriveCodec | None":
        """None where either image cannot be compiled (`PdoImage.compile`): the generic route decides."""
        rx, tx = PdoImage.compile(rx_map, od), PdoImage.compile(tx_map, od)
        if rx is None or tx is None:
            return None
        scope: dict = {"RxPdo": RxPdo, "_unpack": rx.reader.unpack_from, "_pack": tx.writer.pack}
        # outputs: v<k> is the k-th mapped value, stored in its entry; a field takes the last value mapped to it
        lines = ["def read_rx(data, mode):"]
        names = [f"v{k}" for k in range(len(rx.entries))]
        if names:
            lines.append(f"    {', '.join(names)}{',' if len(names) == 1 else ''} = _unpack(data)")
        fields: dict[str, str] = {}
        for k, ((index, sub, _), e) in enumerate(zip(rx_map, rx.entries)):
            scope[f"e{k}"] = e
            lines.append(f"    e{k}.value = v{k}")
            if (index, sub) in rx_attr:
                fields[rx_attr[(index, sub)]] = f"v{k}"
        for k, ((index, sub), attr) in enumerate(rx_attr.items()):  # not mapped: the entry's value (SDO)
            obj = od.objects.get(index)
            if attr not in fields and obj is not None and sub in obj.entries:
                scope[f"u{k}"] = obj.entries[sub]
                fields[attr] = f"(x if isinstance(x := u{k}.value, int) else 0)"  # ObjectDictionary.value's rule
        fields.setdefault("mode", "mode")
        lines.append("    return RxPdo(" + ", ".join(f"{a}={x}" for a, x in fields.items()) + ")")
        # inputs: every TxPdo field the dictionary has goes to its entry; the mapped ones are packed masked
        lines.append("def write_tx(fb):")
        published: dict[tuple[int, int], str] = {}
        for k, ((index, sub), attr) in enumerate(tx_attr.items()):
            obj = od.objects.get(index)
            if obj is not None and sub in obj.entries:
                scope[f"t{k}"] = obj.entries[sub]
                lines.append(f"    w{k} = t{k}.value = fb.{attr}")
                published[(index, sub)] = f"w{k}"
        packed = []
        for k, ((index, sub, _), e, mask) in enumerate(zip(tx_map, tx.entries, tx.masks)):
            scope[f"p{k}"] = e
            packed.append(f"{published.get((index, sub), f'p{k}.value')} & {mask:#x}")
        lines.append(f"    return _pack({', '.join(packed)})")
        exec(compile("\n".join(lines) + "\n", "<drive codec>", "exec"), scope)
        return cls(scope["read_rx"], scope["write_tx"])
