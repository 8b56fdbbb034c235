"""The virtual EtherCAT slaves' own work per process-data frame, in-process (no socket, no root).

The default lathe's line (`hil sim ethercat`'s chain: X, Z, S1) is brought to OP with frames as a
master sends them (station addresses, mailbox and process-data SyncManagers, FMMUs, AL states; the
ESI's default PDO mapping), the drives are enabled, and then every frame is what pysoem sends each
cycle: one LRW over all process data plus the FRMW that distributes the DC reference time. Prints
CPU µs per frame (the best of a few rounds: other jobs on a shared host only ever add to it).
Usage: python benchmarks/bench_ecat_slaves.py [FRAMES] [ROUNDS]
"""

from __future__ import annotations

import argparse
import struct
import sys
import time

from fieldbus.cia402 import State
from hil.bench import default_lathe
from hil.commands.sim import build_chain
from virtual_bus.ethercat import registers as E

RX_BYTES, TX_BYTES = 12, 22  # the ESI default mapping: 0x1600 (6040 607A 60FF 60B8), 0x1A01 (…)


def frame(*datagrams: tuple[int, int, int, bytes]) -> bytes:
    body = b""
    for k, (cmd, adp, ado, data) in enumerate(datagrams):
        more = 0x8000 if k < len(datagrams) - 1 else 0
        body += struct.pack("<BBHHHH", cmd, k, adp, ado, len(data) | more, 0) + data + b"\x00\x00"
    return b"\xff" * 6 + b"\x01" * 6 + b"\x88\xa4" + struct.pack("<H", len(body) | 0x1000) + body


def bring_up(chain) -> int:
    """Every slave to OP, outputs of slave k at logical 12·k, inputs after all outputs. Returns the
    LRW length."""
    n = len(chain.slaves)
    send = chain.process
    for k in range(n):
        send(frame((E.APWR, (-k) & 0xFFFF, E.R_STATION, struct.pack("<H", 0x1001 + k))))
    for k, s in enumerate(chain.slaves):
        st, d = 0x1001 + k, s.device
        mbx = b"".join(struct.pack("<HHBBBB", x.start, x.size, x.control, 0, 1, 0) for x in d.sms[:2])
        pd = struct.pack("<HHBBBB", d.sms[2].start, RX_BYTES, d.sms[2].control, 0, 1, 0) \
            + struct.pack("<HHBBBB", d.sms[3].start, TX_BYTES, d.sms[3].control, 0, 1, 0)
        fmmu = struct.pack("<IHBBHBBBxxx", RX_BYTES * k, RX_BYTES, 0, 7, d.sms[2].start, 0, 2, 1) \
            + struct.pack("<IHBBHBBBxxx", RX_BYTES * n + TX_BYTES * k, TX_BYTES, 0, 7, d.sms[3].start, 0, 1, 1)
        # watchdog off (0x0420 = 0): building the frames up front is a pause no master makes in OP
        send(frame((E.FPWR, st, E.R_SM, mbx + pd), (E.FPWR, st, E.R_FMMU, fmmu), (E.FPWR, st, E.R_WD_PD, b"\0\0")))
        for state in (E.PREOP, E.SAFEOP, E.OP):
            send(frame((E.FPWR, st, E.R_AL_CONTROL, struct.pack("<H", state))))
        if s.al_state != E.OP:
            raise SystemExit(f"slave {s.name} stopped in AL state {s.al_state} (code 0x{s.al_code:04X})")
    return (RX_BYTES + TX_BYTES) * n


def cycle_frames(chain, frames: int) -> float:
    """CPU seconds the chain spends on `frames` cyclic frames (after enabling the drives)."""
    n = len(chain.slaves)
    size = bring_up(chain)

    home = [0] * n

    def pd(cw: int, k: int) -> bytes:
        outs = b"".join(struct.pack("<HiiH", cw, home[j] + 37 * k * (j + 1), 0, 0) for j in range(n))
        return frame((E.LRW, 0, 0, outs.ljust(size, b"\x00")), (E.FRMW, 0x1001, E.R_DC_SYSTIME, bytes(8)))

    answer, _ = chain.process(pd(0x06, 0))
    assert answer is not None
    inputs = 16 + 10 + RX_BYTES * n  # the drives start where the bench left them: hold that position
    home[:] = [struct.unpack_from("<i", answer, inputs + TX_BYTES * j + 2)[0] for j in range(n)]
    for cw in (0x06, 0x07, 0x0F):
        chain.process(pd(cw, 0))
    work = [pd(0x0F, k) for k in range(frames)]  # the setpoints move every cycle
    c0 = time.thread_time()
    for f in work:
        chain.process(f)
    cpu = time.thread_time() - c0
    off = [s.name for s in chain.slaves if s.app.drive.state is not State.OPERATION_ENABLED]
    if off:
        raise SystemExit(f"drives not enabled: {', '.join(off)}: the figure would not be the following cycle's")
    return cpu


def model_share(chain, frames: int) -> float:
    """CPU seconds of the drive models alone over `frames` cycles (each drive's `exchange` on its last
    outputs, as a frame makes it), the part of a frame that is virtual_bus/drive.py, not the ESC."""
    drives = [(s.app.drive, s.app.drive._rx, s.cycle_time) for s in chain.slaves]
    c0 = time.thread_time()
    for _ in range(frames):
        for d, rx, dt in drives:
            d.exchange(rx, dt)
    return time.thread_time() - c0


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("frames", nargs="?", type=int, default=3000, help="frames a round (default 3000)")
    ap.add_argument("rounds", nargs="?", type=int, default=5, help="rounds, the best is printed (default 5)")
    args = ap.parse_args(argv)
    frames, rounds = args.frames, args.rounds
    best, models = float("inf"), float("inf")
    for _ in range(rounds):
        chain = build_chain(default_lathe())
        best = min(best, cycle_frames(chain, frames))
        models = min(models, model_share(chain, frames))
    print(f"virtual slaves in-process ({len(chain.slaves)} drives, LRW + FRMW a frame): {best / frames * 1e6:.1f} µs CPU "
          f"per process-data frame (best of {rounds} rounds of {frames} frames; the drive models "
          f"{models / frames * 1e6:.1f} µs of it, the ESCs and the line the rest), "
          f"{frames / best:,.0f} frames/s of slave work alone")


if __name__ == "__main__":
    main(sys.argv[1:])
