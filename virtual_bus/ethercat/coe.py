"""CoE (CANopen over EtherCAT, ETG.1000.6) server of a virtual slave: the object dictionary,
SDO upload/download (expedited, normal and segmented, complete access), SDO information,
abort codes and emergencies. Works on CoE payloads; the mailbox framing lives in `esc.py`."""

from __future__ import annotations

import copy
import struct
from collections.abc import Callable
from dataclasses import dataclass

from virtual_bus.ethercat.device import OBJ_VAR, VISIBLE_STRING, Device, OdEntry, OdObject

COE_EMERGENCY, COE_SDO_REQ, COE_SDO_RESP, COE_SDO_INFO = 1, 2, 3, 8

ABORT_TOGGLE = 0x05030000
ABORT_UNSUPPORTED_ACCESS = 0x06010000
ABORT_COMMAND = 0x05040001
ABORT_WRITE_ONLY = 0x06010001
ABORT_READ_ONLY = 0x06010002
ABORT_SI0_NOT_ZERO = 0x06010003
ABORT_NO_OBJECT = 0x06020000
ABORT_NOT_MAPPABLE = 0x06040041
ABORT_PDO_LENGTH = 0x06040042
ABORT_TYPE_LENGTH = 0x06070010
ABORT_NO_SUBINDEX = 0x06090011
ABORT_VALUE_RANGE = 0x06090030
ABORT_VALUE_TOO_LOW = 0x06090032
ABORT_GENERAL = 0x08000000
ABORT_STATE = 0x08000022

# ETG.1000.6 object access bits for SDO information
ACCESS_RO, ACCESS_RW, ACCESS_RXPDO, ACCESS_TXPDO = 0x0007, 0x003F, 0x0040, 0x0080
PREOP = 2


class SdoAbort(Exception):
    def __init__(self, code: int) -> None:
        self.code = code
        super().__init__(f"SDO abort 0x{code:08X}")


@dataclass
class _Segmented:
    index: int
    sub: int
    complete: bool
    data: bytearray
    toggle: int = 0
    upload: bool = True
    size: int = 0


class ObjectDictionary:
    """The slave's objects, with the PDO-mapping rules a CiA 402 drive enforces."""

    def __init__(self, device: Device, state: Callable[[], int] = lambda: PREOP) -> None:
        self.objects: dict[int, OdObject] = copy.deepcopy(device.objects)
        self.complete_access = device.coe_complete_access  # the ESI's <CoE CompleteAccess="1">
        self.state = state
        self.before_read: Callable[[int], None] = lambda index: None
        # the application's check of a value before it is stored (raises SdoAbort to refuse it)
        self.before_write: Callable[[int, int, int | bytes], None] = lambda index, sub, value: None
        self.after_write: Callable[[int, int], None] = lambda index, sub: None

    def entry(self, index: int, sub: int) -> OdEntry:
        obj = self.objects.get(index)
        if obj is None:
            raise SdoAbort(ABORT_NO_OBJECT)
        e = obj.entries.get(sub)
        if e is None:
            raise SdoAbort(ABORT_NO_SUBINDEX)
        return e

    def value(self, index: int, sub: int = 0) -> int:
        v = self.entry(index, sub).value
        return v if isinstance(v, int) else 0

    def set(self, index: int, sub: int, value: int) -> None:
        """Slave-side update (process data, live values); no access checks."""
        self.objects[index].entries[sub].value = value

    # ---- SDO semantics ------------------------------------------------------------------
    def read(self, index: int, sub: int, complete: bool = False) -> bytes:
        if complete and not self.complete_access:
            raise SdoAbort(ABORT_UNSUPPORTED_ACCESS)
        self.before_read(index)
        e = self.entry(index, sub)
        if not complete:
            return e.encode()
        obj = self.objects[index]
        if obj.code == OBJ_VAR:
            return e.encode()
        n = obj.entries[0].value if isinstance(obj.entries[0].value, int) else 0
        # Complete access carries subindex 0 padded to 16 bits (ETG.1000.6 5.6.2.1.1).
        out = struct.pack("<BB", n, 0) if sub == 0 else b""
        for s in range(1, int(n) + 1):
            out += obj.entries[s].encode()
        return out

    def write(self, index: int, sub: int, data: bytes, complete: bool = False, exact: bool = True) -> None:
        """`exact`: the request gave its data size (expedited with the size indicator, normal,
        segmented); a size other than the entry's is then refused (0x06070010), as CiA 301 says."""
        if complete and not self.complete_access:
            raise SdoAbort(ABORT_UNSUPPORTED_ACCESS)
        obj = self.objects.get(index)
        if obj is None:
            raise SdoAbort(ABORT_NO_OBJECT)
        if complete and obj.code != OBJ_VAR:
            pos = 0
            count = None
            if sub == 0:
                count = data[0]
                pos = 2
            subs = range(1, (count if count is not None else obj.max_sub) + 1)
            if count is not None:
                self._write_entry(index, 0, bytes([0]))  # SI0 to 0 first, as a mapping change must
            for s in subs:
                e = self.entry(index, s)
                n = max(1, (e.bits + 7) // 8)
                if pos + n > len(data):
                    raise SdoAbort(ABORT_TYPE_LENGTH)
                self._write_entry(index, s, data[pos:pos + n])
                pos += n
            if count is not None:
                self._write_entry(index, 0, bytes([count]))
            return
        self._write_entry(index, sub, data, exact)

    def _write_entry(self, index: int, sub: int, data: bytes, exact: bool = True) -> None:
        e = self.entry(index, sub)
        if not e.writable:
            raise SdoAbort(ABORT_READ_ONLY)
        n = max(1, (e.bits + 7) // 8)
        if e.dtype != VISIBLE_STRING and (len(data) < n or (exact and len(data) != n)):
            raise SdoAbort(ABORT_TYPE_LENGTH)
        value = e.decode(data)
        if 0x1600 <= index <= 0x1BFF or index in (0x1C12, 0x1C13):
            self._check_mapping(index, sub, value)
        if index in (0x1C32, 0x1C33) and sub == 2 and value and 5 in self.objects[index].entries \
                and value < self.value(index, 5):
            raise SdoAbort(ABORT_VALUE_TOO_LOW)  # below the minimum cycle time the device gives in :05
        self.before_write(index, sub, value)
        e.value = value
        self.after_write(index, sub)

    def _check_mapping(self, index: int, sub: int, value) -> None:
        if self.state() != PREOP:
            raise SdoAbort(ABORT_STATE)
        obj = self.objects[index]
        si0 = obj.entries[0].value
        if sub != 0:
            if si0:
                raise SdoAbort(ABORT_SI0_NOT_ZERO)
            if index in (0x1C12, 0x1C13):
                base = 0x1600 if index == 0x1C12 else 0x1A00
                if value and not (base <= value < base + 0x200 and value in self.objects):
                    raise SdoAbort(ABORT_VALUE_RANGE)
                return
            if value == 0:
                return
            mi, ms, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
            want = "R" if index < 0x1A00 else "T"
            target = self.objects.get(mi)
            entry = target.entries.get(ms) if target else None
            if entry is None or want not in entry.pdo:  # "R", "T", or both ("RT") in a vendor ESI
                raise SdoAbort(ABORT_NOT_MAPPABLE)
            if entry.bits != bits:
                raise SdoAbort(ABORT_TYPE_LENGTH)
            return
        if value > obj.max_sub:
            # more entries than the PDO holds: CiA 301 / ETG.1000.6 "exceeds PDO length"
            raise SdoAbort(ABORT_PDO_LENGTH if 0x1600 <= index <= 0x1BFF else ABORT_VALUE_RANGE)
        if 0x1600 <= index <= 0x1BFF:
            total = sum(obj.entries[s].value & 0xFF for s in range(1, value + 1))
            if total > 8 * 64:
                raise SdoAbort(ABORT_PDO_LENGTH)

    # ---- process data layout ------------------------------------------------------------
    def mapping(self, assign: int) -> list[tuple[int, int, int]]:
        """(index, subindex, bits) of every entry the PDO assignment object maps, in order."""
        out: list[tuple[int, int, int]] = []
        a = self.objects[assign]
        for s in range(1, self.value(assign, 0) + 1):
            pdo = a.entries[s].value
            if not pdo or pdo not in self.objects:
                continue
            for k in range(1, self.value(pdo, 0) + 1):
                v = self.value(pdo, k)
                out.append((v >> 16, (v >> 8) & 0xFF, v & 0xFF))
        return out

    def access_bits(self, e: OdEntry) -> int:
        bits = ACCESS_RW if e.writable else ACCESS_RO
        if "R" in e.pdo:
            bits |= ACCESS_RXPDO
        if "T" in e.pdo:
            bits |= ACCESS_TXPDO
        return bits


class CoeServer:
    """Answers CoE requests (payload after the mailbox header) with CoE responses."""

    def __init__(self, od: ObjectDictionary, mailbox_size: int) -> None:
        self.od = od
        self.mbx = mailbox_size
        self._seg: _Segmented | None = None
        self.emergencies: list[bytes] = []

    def handle(self, payload: bytes) -> list[bytes]:
        if len(payload) < 2:
            return []
        service = payload[1] >> 4
        if service == COE_SDO_REQ:
            return [self._sdo(payload)]
        if service == COE_SDO_INFO:
            return self._info(payload)
        return []

    def emergency(self, code: int, register: int, data: bytes = b"") -> bytes:
        return struct.pack("<HHB5s", COE_EMERGENCY << 12, code, register, data[:5].ljust(5, b"\x00"))

    # ---- SDO ----------------------------------------------------------------------------
    def _sdo(self, p: bytes) -> bytes:
        cmd = p[2]
        ccs = cmd >> 5
        index, sub = struct.unpack_from("<HB", p, 3) if len(p) >= 6 else (0, 0)
        try:
            if ccs == 2:  # initiate upload
                return self._upload(index, sub, bool(cmd & 0x10))
            if ccs == 3:  # upload segment
                return self._upload_segment(cmd)
            if ccs == 1:  # initiate download
                return self._download(p, cmd, index, sub)
            if ccs == 0:  # download segment
                return self._download_segment(p, cmd)
            if ccs == 4:  # abort from the master
                self._seg = None
                return b""
            raise SdoAbort(ABORT_COMMAND)
        except SdoAbort as exc:
            if self._seg is not None and ccs in (0, 3):
                index, sub = self._seg.index, self._seg.sub
            self._seg = None
            return struct.pack("<HBHBI", COE_SDO_REQ << 12, 0x80, index, sub, exc.code)

    def _resp(self, cmd: int, index: int, sub: int, data: bytes) -> bytes:
        return struct.pack("<HBHB", COE_SDO_RESP << 12, cmd, index, sub) + data

    def _upload(self, index: int, sub: int, complete: bool) -> bytes:
        data = self.od.read(index, sub, complete)
        flag = 0x10 if complete else 0
        if len(data) <= 4 and not complete:
            return self._resp(0x43 | ((4 - len(data)) << 2), index, sub, data.ljust(4, b"\x00"))
        room = self.mbx - 16
        first, rest = data[:room], data[room:]
        if rest:
            self._seg = _Segmented(index, sub, complete, bytearray(rest))
        return self._resp(0x41 | flag, index, sub, struct.pack("<I", len(data)) + first)

    def _upload_segment(self, cmd: int) -> bytes:
        seg = self._seg
        if seg is None or not seg.upload:
            raise SdoAbort(ABORT_COMMAND)
        toggle = cmd & 0x10
        if toggle != seg.toggle:
            raise SdoAbort(ABORT_TOGGLE)
        seg.toggle ^= 0x10
        room = self.mbx - 9
        chunk, seg.data = bytes(seg.data[:room]), seg.data[room:]
        last = 0 if seg.data else 1
        if last:
            self._seg = None
        unused = max(0, 7 - len(chunk))
        return struct.pack("<HB", COE_SDO_RESP << 12, toggle | (unused << 1) | last) + chunk.ljust(7, b"\x00")

    def _download(self, p: bytes, cmd: int, index: int, sub: int) -> bytes:
        complete = bool(cmd & 0x10)
        if cmd & 0x02:  # expedited
            n = 4 - ((cmd >> 2) & 3) if cmd & 0x01 else 4
            self.od.write(index, sub, p[6:6 + n], complete, exact=bool(cmd & 0x01))
            return self._resp(0x60, index, sub, b"\x00" * 4)
        size = struct.unpack_from("<I", p, 6)[0]
        data = p[10:10 + size]
        if len(data) >= size:
            self.od.write(index, sub, data, complete)
        else:
            self._seg = _Segmented(index, sub, complete, bytearray(data), upload=False, size=size)
        return self._resp(0x60, index, sub, b"\x00" * 4)

    def _download_segment(self, p: bytes, cmd: int) -> bytes:
        seg = self._seg
        if seg is None or seg.upload:
            raise SdoAbort(ABORT_COMMAND)
        toggle = cmd & 0x10
        if toggle != seg.toggle:
            raise SdoAbort(ABORT_TOGGLE)
        seg.toggle ^= 0x10
        body = p[3:]
        n = len(body) - ((cmd >> 1) & 7) if len(body) <= 7 else len(body)
        seg.data += body[:n]
        if cmd & 0x01:
            self._seg = None
            self.od.write(seg.index, seg.sub, bytes(seg.data[:seg.size]), seg.complete)
        return struct.pack("<HB", COE_SDO_RESP << 12, 0x20 | toggle) + b"\x00" * 7

    # ---- SDO information ----------------------------------------------------------------
    def _info(self, p: bytes) -> list[bytes]:
        op = p[2] & 0x7F
        try:
            if op == 0x01:
                return self._od_list(struct.unpack_from("<H", p, 6)[0])
            if op == 0x03:
                return [self._obj_desc(struct.unpack_from("<H", p, 6)[0])]
            if op == 0x05:
                index, sub, _ = struct.unpack_from("<HBB", p, 6)
                return [self._entry_desc(index, sub)]
            raise SdoAbort(ABORT_COMMAND)
        except SdoAbort as exc:
            return [struct.pack("<HBBHI", COE_SDO_INFO << 12, 0x07, 0, 0, exc.code)]

    def _info_frames(self, op: int, body: bytes) -> list[bytes]:
        room = self.mbx - 12
        parts = [body[i:i + room] for i in range(0, len(body), room)] or [b""]
        out = []
        for k, part in enumerate(parts):
            left = len(parts) - 1 - k
            out.append(struct.pack("<HBBH", COE_SDO_INFO << 12, op | (0x80 if left else 0), 0, left) + part)
        return out

    def _od_list(self, list_type: int) -> list[bytes]:
        objs = sorted(self.od.objects)
        lists = {
            1: objs,
            2: [i for i in objs if any("R" in e.pdo for e in self.od.objects[i].entries.values())],
            3: [i for i in objs if any("T" in e.pdo for e in self.od.objects[i].entries.values())],
            4: [], 5: [],
        }
        if list_type == 0:
            body = struct.pack("<H", 0) + b"".join(struct.pack("<H", len(lists[k])) for k in range(1, 6))
        elif list_type in lists:
            body = struct.pack("<H", list_type) + b"".join(struct.pack("<H", i) for i in lists[list_type])
        else:
            raise SdoAbort(ABORT_VALUE_RANGE)
        return self._info_frames(0x02, body)

    def _obj_desc(self, index: int) -> bytes:
        obj = self.od.objects.get(index)
        if obj is None:
            raise SdoAbort(ABORT_NO_OBJECT)
        dtype = obj.entries[0].dtype if obj.code == OBJ_VAR else obj.entries[max(obj.entries)].dtype
        body = struct.pack("<HHBB", index, dtype, obj.max_sub, obj.code) + obj.name.encode()
        return self._info_frames(0x04, body)[0]

    def _entry_desc(self, index: int, sub: int) -> bytes:
        e = self.od.entry(index, sub)
        body = struct.pack("<HBBHHH", index, sub, 0, e.dtype, e.bits, self.od.access_bits(e)) + e.name.encode()
        return self._info_frames(0x06, body)[0]
