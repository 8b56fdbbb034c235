"""The software ESC in-process: frames in, frames out, no network (no root needed)."""

from __future__ import annotations

import struct

import pytest

from hil.bench import default_lathe
from hil.commands.sim import build_chain
from virtual_bus.ethercat import registers as E
from virtual_bus.ethercat.coe import ABORT_NO_OBJECT, ABORT_READ_ONLY, ABORT_STATE, COE_SDO_INFO
from virtual_bus.ethercat.device import load_device
from virtual_bus.ethercat.faults import parse_fault
from virtual_bus.ethercat.sii import build_sii, crc8


def frame(*datagrams: tuple[int, int, int, bytes]) -> bytes:
    body = b""
    for k, (cmd, adp, ado, data) in enumerate(datagrams):
        more = 0x8000 if k < len(datagrams) - 1 else 0
        body += struct.pack("<BBHHHH", cmd, k, adp, ado, len(data) | more, 0) + data + b"\x00\x00"
    eth = b"\xff" * 6 + b"\x01" * 6 + b"\x88\xa4"
    return eth + struct.pack("<H", len(body) | 0x1000) + body


def answers(raw: bytes) -> list[tuple[int, bytes, int]]:
    """(ADP, data, WKC) of every datagram in an answered frame."""
    out, pos = [], 16
    while True:
        cmd, _i, adp, ado, ln, _irq = struct.unpack_from("<BBHHHH", raw, pos)
        n = ln & 0x7FF
        data = raw[pos + 10:pos + 10 + n]
        wkc = struct.unpack_from("<H", raw, pos + 10 + n)[0]
        out.append((adp, data, wkc))
        pos += 12 + n
        if not ln & 0x8000:
            return out


def send(chain, *dgs):
    raw, _ = chain.process(frame(*dgs))
    assert raw is not None
    return answers(raw)


@pytest.fixture
def chain():
    return build_chain(default_lathe(), io=1)  # X, Z, S1 drives + one DIO


def address(chain):
    for k in range(len(chain.slaves)):
        send(chain, (E.APWR, (-k) & 0xFFFF, E.R_STATION, struct.pack("<H", 0x1001 + k)))


def mailbox(chain, station: int, payload: bytes, s: int = 0) -> list[bytes]:
    """Send a CoE payload through SM0 and collect the responses from SM1."""
    esc = chain.slaves[s]
    out_sm, in_sm = esc.device.mailbox_out, esc.device.mailbox_in
    msg = struct.pack("<HHBB", len(payload), 0, 0, 0x13) + payload
    (_, _, wkc), = send(chain, (E.FPWR, station, out_sm.start, msg.ljust(out_sm.size, b"\x00")))
    assert wkc == 1
    got = []
    while True:
        (_, st, _), = send(chain, (E.FPRD, station, 0x080D, b"\x00"))
        if not st[0] & 0x08:
            return got
        (_, data, wkc), = send(chain, (E.FPRD, station, in_sm.start, bytes(in_sm.size)))
        assert wkc == 1
        n = struct.unpack_from("<H", data)[0]
        got.append(data[6:6 + n])


def to_preop(chain, station=0x1001, s=0):
    d = chain.slaves[s].device
    sm = b"".join(struct.pack("<HHBBBB", x.start, x.size, x.control, 0, 1, 0) for x in d.sms[:2])
    send(chain, (E.FPWR, station, E.R_SM, sm))
    send(chain, (E.FPWR, station, E.R_AL_CONTROL, struct.pack("<H", E.PREOP)))
    assert chain.slaves[s].al_state == E.PREOP


def test_broadcast_and_auto_increment_working_counters(chain):
    (adp, data, wkc), = send(chain, (E.BRD, 0, 0x0000, b"\x00\x00"))
    assert wkc == 4 and adp == 4 and data[0] == 0x11  # every slave answers, ADP counts up
    (adp, _, wkc), = send(chain, (E.APRD, 0xFFFE, E.R_AL_STATUS, b"\x00\x00"))
    assert wkc == 1 and adp == 2  # only the third slave is addressed
    address(chain)
    assert [s.station for s in chain.slaves] == [0x1001, 0x1002, 0x1003, 0x1004]
    (_, data, wkc), = send(chain, (E.FPRD, 0x1003, E.R_STATION, b"\x00\x00"))
    assert (wkc, struct.unpack("<H", data)[0]) == (1, 0x1003)
    (_, _, wkc), = send(chain, (E.FPRD, 0x7777, E.R_STATION, b"\x00\x00"))
    assert wkc == 0
    (_, _, wkc), = send(chain, (E.BWR, 0, 0x0200, b"\x00\x00"))
    assert wkc == 4
    # FPRW swaps: old value comes back, new value is stored, WKC 3
    (_, data, wkc), = send(chain, (E.FPRW, 0x1002, 0x0200, b"\x34\x12"))
    assert wkc == 3 and data == b"\x00\x00" and chain.slaves[1].u16(0x0200) == 0x1234
    # read-only registers keep their value
    send(chain, (E.BWR, 0, E.R_AL_STATUS, b"\x08\x00"))
    assert all(s.al_state == E.INIT for s in chain.slaves)


def test_sii_image_matches_the_device_description():
    dev = load_device("asda-a3-e")
    sii = build_sii(dev)
    vendor, product, revision = struct.unpack_from("<III", sii, 0x08 * 2)
    assert (vendor, product, revision) == (0x1DD, 0x6010, 0x30000)
    assert sii[14] == crc8(sii[:14])
    assert struct.unpack_from("<HHHHH", sii, 0x18 * 2) == (0x1000, 256, 0x1200, 256, 0x0004)
    # the first category is the strings, whose first string is the device name
    assert struct.unpack_from("<H", sii, 0x80)[0] == 10
    assert sii[0x86:0x86 + sii[0x85]] == dev.name.encode()


def test_eeprom_read_through_registers(chain):
    address(chain)
    send(chain, (E.FPWR, 0x1001, E.R_EEP_CTRL, struct.pack("<HI", 0x0100, 0x0A)))
    (_, status, _), = send(chain, (E.FPRD, 0x1001, E.R_EEP_CTRL, b"\x00\x00"))
    assert not struct.unpack("<H", status)[0] & 0x8000
    (_, data, _), = send(chain, (E.FPRD, 0x1001, E.R_EEP_DATA, bytes(8)))
    assert struct.unpack_from("<I", data)[0] == 0x6010  # product code word 0x0A


def test_al_state_machine_refuses_invalid_changes(chain):
    address(chain)
    send(chain, (E.FPWR, 0x1001, E.R_AL_CONTROL, struct.pack("<H", E.OP)))
    (_, st, _), = send(chain, (E.FPRD, 0x1001, E.R_AL_STATUS, bytes(6)))
    assert st[0] == E.INIT | E.AL_ERROR and struct.unpack_from("<H", st, 4)[0] == 0x0011
    # PRE-OP without mailbox SyncManagers: invalid mailbox configuration
    send(chain, (E.FPWR, 0x1001, E.R_AL_CONTROL, struct.pack("<H", E.PREOP | 0x10)))
    assert chain.slaves[0].al_code == 0x0016
    send(chain, (E.FPWR, 0x1001, E.R_AL_CONTROL, struct.pack("<H", E.INIT | 0x10)))
    to_preop(chain)
    # SAFE-OP with an output SM that does not match the mapping (12 bytes): 0x001D
    send(chain, (E.FPWR, 0x1001, E.R_SM + 16, struct.pack("<HHBBBB", 0x1400, 5, 0x64, 0, 1, 0)))
    send(chain, (E.FPWR, 0x1001, E.R_AL_CONTROL, struct.pack("<H", E.SAFEOP)))
    assert chain.slaves[0].al_state == E.PREOP and chain.slaves[0].al_code == 0x001D


def test_coe_sdo_expedited_segmented_complete_access_and_aborts(chain):
    address(chain)
    to_preop(chain)

    def upload(index, sub, ca=False):
        return mailbox(chain, 0x1001, struct.pack("<HBHBI", 0x2000, 0x40 | (0x10 if ca else 0), index, sub, 0))

    (r,) = upload(0x1018, 2)
    assert r[2] == 0x43 and struct.unpack_from("<I", r, 6)[0] == 0x6010  # expedited, 4 bytes
    (r,) = upload(0x1008, 0)  # 19 bytes: normal transfer with the size
    assert r[2] & 0x03 == 0x01 and struct.unpack_from("<I", r, 6)[0] == 19 and r[10:29] == b"ASDA-A3-E CoE Drive"
    (r,) = upload(0x1600, 0, ca=True)  # complete access: SI0 padded to 16 bits, then 32-bit entries
    n = struct.unpack_from("<I", r, 6)[0]
    # the A3-E ESI's 1st RxPDO: 6040 607A 60FF 60B8 (12 bytes out, the drive's default image)
    assert n == 2 + 4 * 4 and r[10] == 4 and struct.unpack_from("<I", r, 12)[0] == 0x60400010
    (r,) = upload(0x2345, 0)
    assert r[2] == 0x80 and struct.unpack_from("<I", r, 6)[0] == ABORT_NO_OBJECT
    # download to a read-only object aborts; mapping changes only in PRE-OP
    (r,) = mailbox(chain, 0x1001, struct.pack("<HBHBI", 0x2000, 0x2B, 0x6041, 0, 5))
    assert struct.unpack_from("<I", r, 6)[0] == ABORT_READ_ONLY
    # segmented download of a 3-entry mapping (complete access, 14 bytes) then read it back
    data = struct.pack("<BxIII", 3, 0x60400010, 0x607A0020, 0x60FF0020)
    (r,) = mailbox(chain, 0x1001, struct.pack("<HBHBI", 0x2000, 0x31, 0x1601, 0, len(data)) + data)
    assert r[2] == 0x60
    assert chain.slaves[0].od.mapping(0x1C12) == [(0x6040, 0, 16), (0x607A, 0, 32), (0x60FF, 0, 32), (0x60B8, 0, 16)]
    assert chain.slaves[0].od.value(0x1601, 3) == 0x60FF0020
    chain.slaves[0].mem[E.R_AL_STATUS] = E.SAFEOP
    (r,) = mailbox(chain, 0x1001, struct.pack("<HBHBI", 0x2000, 0x2F, 0x1600, 0, 0))  # 1 byte to SI0
    assert struct.unpack_from("<I", r, 6)[0] == ABORT_STATE


def test_sdo_information_lists_objects_and_describes_entries(chain):
    address(chain)
    to_preop(chain)
    frames = mailbox(chain, 0x1001, struct.pack("<HBBHH", COE_SDO_INFO << 12, 0x01, 0, 0, 1))
    indices = b"".join(f[8:] if k == 0 else f[6:] for k, f in enumerate(frames))
    listed = set(struct.unpack(f"<{len(indices) // 2}H", indices))
    assert {0x1000, 0x1018, 0x6040, 0x6064, 0x1C12} <= listed
    (r,) = mailbox(chain, 0x1001, struct.pack("<HBBHHBB", COE_SDO_INFO << 12, 0x05, 0, 0, 0x6064, 0, 0))
    index, sub, _, dtype, bits, access = struct.unpack_from("<HBBHHH", r, 6)
    assert (index, dtype, bits) == (0x6064, 0x0004, 32) and access & 0x80 and r[16:] == b"Position actual value"


def test_emergency_reaches_the_mailbox(chain):
    address(chain)
    to_preop(chain)
    chain.slaves[0].emergency(0xFF09, 0x81, b"\x09")
    (_, st, _), = send(chain, (E.FPRD, 0x1001, 0x080D, b"\x00"))
    assert st[0] & 0x08
    (_, data, _), = send(chain, (E.FPRD, 0x1001, 0x1200, bytes(256)))
    assert data[7] >> 4 == 1 and struct.unpack_from("<H", data, 8)[0] == 0xFF09


def test_dc_receive_times_and_system_time(chain):
    address(chain)
    send(chain, (E.BWR, 0, E.R_DC_RECV, bytes(4)))
    t = [struct.unpack("<II", send(chain, (E.FPRD, 0x1001 + k, E.R_DC_RECV, bytes(8)))[0][1]) for k in range(4)]
    loops = [p1 - p0 for p0, p1 in t[:-1]]
    assert loops == sorted(loops, reverse=True) and loops[-1] > 0 and t[-1][1] == 0  # last slave: port 1 open
    # offset moves the system time; FRMW: reference (first) slave reads, others follow
    send(chain, (E.FPWR, 0x1002, E.R_DC_OFFSET, struct.pack("<Q", 10**15)))
    (_, ref, wkc), = send(chain, (E.FRMW, 0x1001, E.R_DC_SYSTIME, bytes(8)))
    assert wkc == 4 and struct.unpack("<Q", ref)[0] > 0
    assert chain.slaves[1].u32(E.R_DC_DIFF) & 0x7FFFFFFF > 0


def test_fault_specs_parse_and_reject_garbage():
    f = parse_fault("leave:1@500+20")
    assert (f.kind, f.slave, f.at, f.back) == ("leave", 1, 500, 20) and f.active(510) and not f.active(520)
    assert parse_fault("alerr:2@10").arg == 0x001A
    assert parse_fault("late@5x3:40").arg == 40.0
    with pytest.raises(ValueError):
        parse_fault("explode@3")
