"""The virtual slaves' shortcuts for the cyclic frame (issue 17) answer as the general routes do: a drive slave
runs its drive through `Cia402Drive.exchange` (apply, step and feedback in one call), and the line hands the DC
FRMW to `Esc.frmw` instead of the generic datagram handling. Frame for frame, the answers (inputs, working
counters, DC time) are the ones the general routes give, through enabling, motion, quick stop and fault reset."""

from __future__ import annotations

import struct
import time

import pytest

from benchmarks.bench_ecat_slaves import RX_BYTES, TX_BYTES, bring_up, frame
from hil.bench import default_lathe
from hil.commands.sim import build_chain
from virtual_bus.ethercat import registers as E
from virtual_bus.ethercat.network import Chain


@pytest.fixture
def clock(monkeypatch):
    """The slaves' monotonic clock, 1 µs a reading: DC times and watchdogs the same in both runs."""
    now = [10**12]

    def ns() -> int:
        now[0] += 1_000
        return now[0]

    monkeypatch.setattr(time, "monotonic_ns", ns)
    return now


def _three_calls(drive):
    """The drive as the slave ran it before: apply, step, feedback."""
    def exchange(rx, dt):
        drive.apply(rx)
        drive.step(dt)
        return drive.feedback()
    return exchange


def _generic_frmw(chain: Chain):
    """`Esc.frmw` replaced by the line's generic datagram handling of FRMW."""
    for s in chain.slaves:
        s.frmw = lambda adp, ado, data, s=s: Chain._datagram(s, E.FRMW, adp, ado, data)[0]


def _run(clock, general: bool, alias: bool = False, wkc_fault: int | None = None) -> list[bytes]:
    clock[0] = 10**12
    chain = build_chain(default_lathe())
    if general:
        for s in chain.slaves:
            s.app.drive.exchange = _three_calls(s.app.drive)
        _generic_frmw(chain)
    n = len(chain.slaves)
    size = bring_up(chain)
    ref = 0x1001
    if alias:  # the DC reference addressed by its alias (0x0012, as its EEPROM loads it; DL control bit 24 set)
        struct.pack_into("<H", chain.slaves[0].mem, E.R_ALIAS, 0x0777)
        chain.process(frame((E.FPWR, 0x1001, E.R_DL_CONTROL, struct.pack("<I", 1 << 24))))
        ref = 0x0777
    home = [0] * n

    def pd(cw: int, k: int) -> bytes:
        outs = b"".join(struct.pack("<HiiH", cw, home[j] + 40 * k * (j + 1), 0, 0) for j in range(n))
        return frame((E.LRW, 0, 0, outs.ljust(size, b"\x00")), (E.FRMW, ref, E.R_DC_SYSTIME, bytes(8)))

    answer, _ = chain.process(pd(0x06, 0))
    first = 16 + 10 + RX_BYTES * n
    home[:] = [struct.unpack_from("<i", answer, first + TX_BYTES * j + 2)[0] for j in range(n)]
    out = []
    for k in range(400):
        cw = 0x06 if k < 2 else 0x07 if k < 4 else 0x0F if k < 300 else 0x0B if k < 350 else 0x80 if k < 360 else 0x06
        if wkc_fault is not None:
            chain.slaves[wkc_fault].wkc_fault = 100 <= k < 110
        answer, _ = chain.process(pd(cw, k))
        out.append(answer)
    assert len({s.app.drive.position for s in chain.slaves}) == n  # the axes moved, each its own way
    return out


@pytest.mark.parametrize("alias, wkc_fault", [(False, None), (True, None), (False, 0), (False, 2)])
def test_cyclic_frames_answer_as_the_general_routes(clock, alias, wkc_fault):
    fast = _run(clock, general=False, alias=alias, wkc_fault=wkc_fault)
    general = _run(clock, general=True, alias=alias, wkc_fault=wkc_fault)
    assert fast == general
    lrw_wkc = [struct.unpack_from("<H", a, 16 + 10 + (RX_BYTES + TX_BYTES) * 3)[0] for a in fast]
    assert lrw_wkc[50] == 9 and (wkc_fault is None or lrw_wkc[105] == 6)  # 3 a slave; a faulty one counts none
    frmw_wkc = [struct.unpack_from("<H", a, len(a) - 2)[0] for a in fast]
    assert frmw_wkc[50] == 3  # the reference reads, the two others write
    assert any(fast[50][len(fast[50]) - 10:len(fast[50]) - 2])  # what it read: its system time, not the zeros sent
    positions = [struct.unpack_from("<i", a, 16 + 10 + RX_BYTES * 3 + 2)[0] for a in fast]
    assert positions[299] != positions[10]  # X followed its setpoints
