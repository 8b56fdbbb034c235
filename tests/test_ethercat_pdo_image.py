"""The virtual slaves' compiled process data (issue 17): one struct per direction and a copy plan per
logical datagram, equal to the entry-by-entry route and following the master's FMMU changes.
In-process, no network (no root needed)."""

from __future__ import annotations

import random
import struct

from hil.bench import default_lathe
from hil.commands.sim import build_chain
from virtual_bus.ethercat import registers as E
from virtual_bus.ethercat.pdo_image import PdoImage, pack_generic, unpack_generic

from tests.test_ethercat_slave import address, send, to_preop

# a mapping of every width and signedness a drive's objects have: 0x6040 UINT, 0x607A DINT,
# 0x6060 SINT, 0x6071 INT, 0x60FE:1 UDINT, 0x60B8 UINT
RX = [(0x6040, 0, 16), (0x607A, 0, 32), (0x6060, 0, 8), (0x6071, 0, 16), (0x60FE, 1, 32), (0x60B8, 0, 16)]
TX = [(0x6041, 0, 16), (0x6064, 0, 32), (0x606C, 0, 32), (0x6077, 0, 16), (0x6061, 0, 8), (0x60FD, 0, 32)]


def test_compiled_image_reads_and_writes_what_the_entry_by_entry_route_does():
    od = build_chain(default_lathe()).slaves[0].od
    rx, tx = PdoImage.compile(RX, od), PdoImage.compile(TX, od)
    assert rx is not None and tx is not None and rx.reader.size == 15 and tx.writer.size == 17
    rng = random.Random(17)
    for _ in range(300):
        raw = bytes(rng.getrandbits(8) for _ in range(15))
        rx.read(raw)
        fast = [od.value(i, s) for i, s, _ in RX]
        unpack_generic(raw, RX, od)
        assert fast == [od.value(i, s) for i, s, _ in RX]  # signed objects come back negative alike
        for (i, s, _), v in zip(TX, fast):  # out-of-range and negative values wrap the same way
            od.set(i, s, v * rng.choice((1, -1, 1 << 20)))
        assert tx.write() == pack_generic(TX, od)
    assert od.value(0x607A) < 0 or any(od.value(i, s) < 0 for i, s, _ in RX)  # the draw hit negatives


def test_image_that_cannot_be_compiled_is_left_to_the_entry_by_entry_route():
    od = build_chain(default_lathe()).slaves[0].od
    assert PdoImage.compile([(0x6040, 0, 16), (0x7777, 0, 16)], od) is None  # no such object
    assert PdoImage.compile([(0x6040, 0, 12)], od) is None  # not byte-wide


def _to_op(chain, fmmu_in: int) -> None:
    """Drive X (station 0x1001) in OP with its default mapping: outputs at logical 0, inputs at `fmmu_in`."""
    s = chain.slaves[0]
    to_preop(chain)
    d = s.device
    sms = struct.pack("<HHBBBB", d.sms[2].start, 12, d.sms[2].control, 0, 1, 0) \
        + struct.pack("<HHBBBB", d.sms[3].start, 22, d.sms[3].control, 0, 1, 0)
    send(chain, (E.FPWR, 0x1001, E.R_SM + 16, sms))
    fmmus = struct.pack("<IHBBHBBBxxx", 0, 12, 0, 7, d.sms[2].start, 0, 2, 1) \
        + struct.pack("<IHBBHBBBxxx", fmmu_in, 22, 0, 7, d.sms[3].start, 0, 1, 1)
    send(chain, (E.FPWR, 0x1001, E.R_FMMU, fmmus))
    for state in (E.SAFEOP, E.OP):
        send(chain, (E.FPWR, 0x1001, E.R_AL_CONTROL, struct.pack("<H", state)))
    assert s.al_state == E.OP


def test_process_data_follows_the_fmmu_the_master_writes_in_op():
    chain = build_chain(default_lathe())
    address(chain)
    _to_op(chain, 0x100)
    drive = chain.slaves[0].app.drive
    out = struct.pack("<HiiH", 0x06, 0, 0, 0)  # shutdown
    (_, data, wkc), = send(chain, (E.LRW, 0, 0, out + bytes(0x100 - 12 + 22)))
    assert wkc == 3  # written and read
    sw = struct.unpack_from("<H", data, 0x100)[0]
    assert sw == drive.feedback().statusword and sw & 0x6F == 0x21  # ready to switch on
    # the master moves the inputs to logical 0x40: the next frame carries them there, not at 0x100
    send(chain, (E.FPWR, 0x1001, E.R_FMMU + 16, struct.pack("<I", 0x40)))
    (_, data, wkc), = send(chain, (E.LRW, 0, 0, out + bytes(0x100 - 12 + 22)))
    assert wkc == 3
    assert struct.unpack_from("<H", data, 0x40)[0] == sw and data[0x100:0x100 + 22] == bytes(22)
    # an output FMMU switched off: the datagram is read only (WKC 1), the drive keeps its last command
    send(chain, (E.FPWR, 0x1001, E.R_FMMU + 12, b"\x00"))
    (_, data, wkc), = send(chain, (E.LRW, 0, 0, struct.pack("<HiiH", 0x07, 0, 0, 0) + bytes(0x40 - 12 + 22)))
    assert wkc == 1 and struct.unpack_from("<H", data, 0x40)[0] & 0x6F == 0x21


def test_watchdog_time_the_master_writes_in_op_takes_effect():
    import time

    chain = build_chain(default_lathe())
    address(chain)
    _to_op(chain, 0x100)
    frame = (E.LRW, 0, 0, struct.pack("<HiiH", 0x06, 0, 0, 0) + bytes(0x100 - 12 + 22))
    send(chain, frame)
    time.sleep(0.002)
    (_, _, wkc), = send(chain, frame)  # 2 ms without outputs: within the default 100 ms
    assert wkc == 3 and chain.slaves[0].al_state == E.OP
    send(chain, (E.FPWR, 0x1001, E.R_WD_PD, struct.pack("<H", 5)))  # 5 ticks of 100 µs
    time.sleep(0.002)
    send(chain, frame)
    s = chain.slaves[0]
    assert s.al_state == E.SAFEOP and s.mem[E.R_AL_STATUS] & E.AL_ERROR and s.al_code == E.AL_SM_WATCHDOG


def _rx_by_entries(od, outputs: bytes, rx_map) -> dict[str, int]:
    """What DriveApp did per frame before its codec: the outputs into their objects entry by entry, then
    the RxPdo fields read back from the objects."""
    from virtual_bus.ethercat.app import RX_ATTR

    unpack_generic(outputs, rx_map, od)
    return {attr: od.value(i, s) for (i, s), attr in RX_ATTR.items() if i in od.objects}


def test_drive_codec_moves_the_values_the_entry_by_entry_route_moves():
    from dataclasses import asdict

    from fieldbus.pdo import TxPdo
    from virtual_bus.ethercat.app import RX_ATTR, TX_ATTR
    from virtual_bus.ethercat.pdo_image import DriveCodec

    rng = random.Random(1702)
    # the ESI default set, a short CSP set (0x6060 and the rest then come from their objects: SDO) and
    # the wide test mapping above
    maps = [([(0x6040, 0, 16), (0x607A, 0, 32), (0x60FF, 0, 32), (0x6071, 0, 16), (0x6060, 0, 8), (0x60B8, 0, 16)],
             [(0x6041, 0, 16), (0x6064, 0, 32), (0x606C, 0, 32), (0x6077, 0, 16), (0x6061, 0, 8), (0x60B9, 0, 16),
              (0x60BA, 0, 32), (0x60FD, 0, 32)]),
            ([(0x6040, 0, 16), (0x607A, 0, 32)], [(0x6041, 0, 16), (0x6064, 0, 32)]),
            (RX, TX)]
    for rx_map, tx_map in maps:
        fast_od = build_chain(default_lathe()).slaves[0].od
        slow_od = build_chain(default_lathe()).slaves[0].od
        for od in (fast_od, slow_od):
            od.set(0x6060, 0, 9)  # by SDO: the short set does not carry the mode
        codec = DriveCodec.compile(rx_map, tx_map, fast_od, RX_ATTR, TX_ATTR)
        assert codec is not None
        size = sum(b for *_, b in rx_map) // 8
        for _ in range(200):
            raw = bytes(rng.getrandbits(8) for _ in range(size))
            rx = codec.read_rx(raw, 8)
            want = _rx_by_entries(slow_od, raw, rx_map)
            assert {a: v for a, v in asdict(rx).items() if a in want} == want
            fb = TxPdo(*(rng.randrange(-1 << 31, 1 << 31) for _ in range(10)))
            for (i, s), attr in TX_ATTR.items():  # DriveApp._publish, then PdoImage.write's packing
                if i in slow_od.objects:
                    slow_od.set(i, s, int(getattr(fb, attr)))
            assert codec.write_tx(fb) == pack_generic(tx_map, slow_od)
            assert [e.value for o in fast_od.objects.values() for e in o.entries.values()] \
                == [e.value for o in slow_od.objects.values() for e in o.entries.values()]  # the dictionaries agree
        if (0x6060, 0, 8) not in rx_map:
            assert rx.mode == 9  # the mode written by SDO, not the caller's default
