"""A software EtherCAT Slave Controller: the register file, datagram handling with working
counters, SII EEPROM access, the AL state machine, SyncManagers (mailbox and process data),
FMMUs, the process-data watchdog and the distributed-clock registers.

The register map follows the ESC datasheets (ET1100/ET1200 section II); only what masters use
is active, everything else is plain memory.
"""

from __future__ import annotations

import struct
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from virtual_bus.ethercat.coe import CoeServer, ObjectDictionary
from virtual_bus.ethercat.device import Device
from virtual_bus.ethercat.sii import build_sii
from virtual_bus.ethercat.registers import (
    AL_BOOTSTRAP_NOT_SUPPORTED, AL_ERROR, AL_INVALID_DC_SYNC, AL_INVALID_INPUT, AL_INVALID_MAILBOX,
    AL_INVALID_OUTPUT, AL_INVALID_STATE_CHANGE, AL_INVALID_SYNC0_CYCLE, AL_SM_WATCHDOG, AL_UNKNOWN_STATE, INIT,
    PREOP, BOOT, SAFEOP, OP, MBX_TYPE_ERR, MBX_TYPE_COE, LRD, LWR, LRW, ARMW, FRMW, RO, R_AL_CONTROL, R_AL_STATUS,
    R_AL_CODE, R_DC_ACTIVATION, R_DC_SYNC0_CYCLE, R_DC_RECV, R_DC_SYSTIME, R_DC_RECV_PU, R_DC_OFFSET, R_DC_DELAY,
    R_DC_DIFF, R_EEP_CTRL, R_EEP_ADDR, R_EEP_DATA, R_FMMU, R_SM, R_STATION, R_ALIAS, R_WD_DIV, R_WD_PD,
    R_WD_STATUS
)

_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
HOP_NS = 500  # forwarding delay per ESC and cable, what the DC delay measurement sees
STATE_TEXT = {1: "INIT", 2: "PRE-OP", 3: "BOOT", 4: "SAFE-OP", 8: "OP"}
COAST_MAX_STEPS = 60_000  # cycles a silent line's slave runs on in one idle tick (a minute at 1 ms)


@dataclass
class Sm:
    start: int
    length: int
    control: int
    enabled: bool

    @property
    def end(self) -> int:
        return self.start + self.length


class SlaveApp:
    """What sits behind the process data (drive, I/O). `esc.py` calls these."""

    def attach(self, od: ObjectDictionary) -> None: ...

    def cycle(self, outputs: bytes | memoryview, rx_map, tx_map, step: bool, dt: float = 0.0,
              lost: bool = False) -> bytes:
        """`outputs`: the SM2 area (a view of the ESC's memory, valid during the call). `lost`: the slave
        fell out of OP by an error; its outputs are stale, its time runs on."""
        return b""

    def refresh(self, index: int) -> None: ...

    def coast(self, dt: float) -> str | None:
        """The application's own time while the master sends nothing (the line silent after the slave fell out
        of OP by an error): `dt` seconds of it. Returns a line for the log when something a bench engineer
        watches happened (a drive reached standstill, outputs went to their safe state), else None."""
        return None

    @property
    def coasting(self) -> bool:
        """Whether `coast` still has something to do (a drive braking)."""
        return False


def _al_text(code: int) -> str:
    """ETG.1000.6's name of an AL status code, as the master's side prints it (pysoem's table)."""
    try:
        import pysoem
        return pysoem.al_status_code_to_string(code)
    except Exception:  # pysoem missing or refusing the code: the number alone says it
        return "AL status code"


@dataclass
class Esc:
    device: Device
    app: SlaveApp = field(default_factory=SlaveApp)
    name: str = ""
    drift_ppm: float = 0.0
    clock_base_ns: int = 0  # this slave's local clock at monotonic zero (clocks start unsynchronised)
    cycle_time: float = 0.001  # bench cycle: the drive model advances this much per process-data frame
    lockstep: bool = True
    mem: bytearray = field(default_factory=lambda: bytearray(0x10000))

    def __post_init__(self) -> None:
        self.name = self.name or self.device.name
        self.sii = bytearray(build_sii(self.device))
        self.od = ObjectDictionary(self.device, state=lambda: self.al_state)
        self.od.before_read = lambda index: self.app.refresh(index)
        self.app.attach(self.od)
        self.coe = CoeServer(self.od, self.device.mailbox_out.size)
        self.mbx_out: deque[bytes] = deque()
        self.mbx_full = False
        self.mbx_last = b""
        self.mbx_counter = 0
        self.rx_map: list[tuple[int, int, int]] = []
        self.tx_map: list[tuple[int, int, int]] = []
        self.position = 0
        self.chain_len = 1
        self.frame_ns = 0
        self.last_output_ns = 0
        self.last_cycle_ns = 0
        self.outputs_written = 0
        self.events: list[str] = []
        self.wkc_fault = False
        self.refuse: dict[int, int] = {}  # AL state -> AL status code it is refused with (fault injection)
        # SyncManager, FMMU and watchdog settings decoded once, and the copy plan of each logical datagram
        # seen, until the master writes those registers again (issue 17: no per-frame decoding).
        self._sms: dict[int, Sm] = {}
        self._fmmus: list[tuple[int, int, int, int]] | None = None
        self._plans: dict[tuple[int, int, int], tuple[list, list, memoryview, int]] = {}
        self._wd_ns: int | None = None  # the process-data watchdog time, from 0x0400 and 0x0420
        self.power_on()

    # ---- reset --------------------------------------------------------------------------
    def power_on(self) -> None:
        m = self.mem
        m[:] = bytes(len(m))
        m[0] = 0x11  # ESC type: ET1100-class
        m[1] = 0x02  # revision
        m[4], m[5], m[6], m[7] = 8, 8, 8, 0x0F  # FMMUs, SMs, RAM (KiB), ports 0/1 MII
        struct.pack_into("<H", m, 0x0008, 0x01CC)  # features: DC, 64-bit DC, enhanced link, FMMU bit ops
        struct.pack_into("<H", m, R_ALIAS, struct.unpack_from("<H", self.sii, 8)[0])
        struct.pack_into("<H", m, R_AL_STATUS, INIT)
        struct.pack_into("<H", m, R_WD_DIV, 0x09C2)  # 100 µs watchdog ticks
        struct.pack_into("<H", m, 0x0410, 1000)
        struct.pack_into("<H", m, R_WD_PD, 1000)  # 100 ms process-data watchdog
        struct.pack_into("<H", m, R_WD_STATUS, 1)
        struct.pack_into("<H", m, R_EEP_CTRL, 0x0040)  # idle, 8-byte reads
        struct.pack_into("<H", m, 0x0140, 0x0008)  # PDI: 32-bit digital I/O... any non-zero PDI
        self.mbx_out.clear()
        self.mbx_full = False
        self.rx_map, self.tx_map = [], []
        self._layout_changed()

    def _layout_changed(self) -> None:
        self._sms.clear()
        self._fmmus = None
        self._plans.clear()
        self._wd_ns = None

    # ---- small register helpers -----------------------------------------------------------
    def u16(self, a: int) -> int:
        return _U16.unpack_from(self.mem, a)[0]

    def u32(self, a: int) -> int:
        return _U32.unpack_from(self.mem, a)[0]

    def u64(self, a: int) -> int:
        return _U64.unpack_from(self.mem, a)[0]

    @property
    def station(self) -> int:
        return self.u16(R_STATION)

    @property
    def al_state(self) -> int:
        return self.mem[R_AL_STATUS] & 0x0F

    @property
    def al_code(self) -> int:
        return self.u16(R_AL_CODE)

    def sm(self, k: int) -> Sm:
        got = self._sms.get(k)
        if got is None:
            start, length, control, _status, act = struct.unpack_from("<HHBBB", self.mem, R_SM + 8 * k)
            got = self._sms[k] = Sm(start, length, control, bool(act & 1))
        return got

    # ---- DC clock -------------------------------------------------------------------------
    def local_ns(self, mono_ns: int | None = None) -> int:
        t = time.monotonic_ns() if mono_ns is None else mono_ns
        return (self.clock_base_ns + int(t * (1.0 + self.drift_ppm * 1e-6))) & 0xFFFFFFFFFFFFFFFF

    def system_ns(self, mono_ns: int | None = None) -> int:
        return (self.local_ns(mono_ns) + self.u64(R_DC_OFFSET)) & 0xFFFFFFFFFFFFFFFF

    def _latch_receive_times(self) -> None:
        t_in = self.frame_ns + self.position * HOP_NS
        p0 = self.local_ns(t_in)
        last = self.position >= self.chain_len - 1
        p1 = 0 if last else self.local_ns(self.frame_ns + (2 * (self.chain_len - 1) - self.position) * HOP_NS)
        struct.pack_into("<IIII", self.mem, R_DC_RECV, p0 & 0xFFFFFFFF, p1 & 0xFFFFFFFF, 0, 0)
        struct.pack_into("<Q", self.mem, R_DC_RECV_PU, p0)

    def _system_time_written(self, value: int) -> None:
        """A master (FRMW/ARMW) distributes the reference time: the ESC's control loop compares it
        with its own system time and trims the offset, and shows the difference in 0x092C."""
        # every process-data frame of a DC master comes here on all but the reference slave: system_ns
        # and local_ns inlined (the same expressions), the offset read once
        mem = self.mem
        received = (value + _U32.unpack_from(mem, R_DC_DELAY)[0]) & 0xFFFFFFFFFFFFFFFF
        offset = _U64.unpack_from(mem, R_DC_OFFSET)[0]
        t = self.frame_ns + self.position * HOP_NS
        local = (self.clock_base_ns + int(t * (1.0 + self.drift_ppm * 1e-6))) & 0xFFFFFFFFFFFFFFFF
        own = (local + offset) & 0xFFFFFFFFFFFFFFFF
        diff = ((received - own + (1 << 63)) % (1 << 64)) - (1 << 63)
        mag = min(abs(diff), 0x7FFFFFFF)
        _U32.pack_into(mem, R_DC_DIFF, mag | (0x80000000 if diff < 0 else 0))
        step = max(-5000, min(5000, diff // 8)) if abs(diff) < 1_000_000 else diff
        _U64.pack_into(mem, R_DC_OFFSET, (offset + step) & 0xFFFFFFFFFFFFFFFF)

    # ---- register access with side effects ------------------------------------------------
    def read(self, addr: int, n: int) -> bytes | None:
        end = addr + n
        if addr < R_DC_SYSTIME + 8 and end > R_DC_SYSTIME:
            # the DC reference's system time, read by every cycle's FRMW: system_ns at the frame's arrival, inlined
            mem = self.mem
            local = self.local_ns(self.frame_ns + self.position * HOP_NS)
            _U64.pack_into(mem, R_DC_SYSTIME, (local + _U64.unpack_from(mem, R_DC_OFFSET)[0]) & 0xFFFFFFFFFFFFFFFF)
        mi = self._sms.get(1) or self.sm(1)
        if mi.enabled and mi.length and addr < mi.end and end > mi.start:
            if not self.mbx_full:
                return None  # an empty read mailbox does not answer (no WKC)
            data = bytes(self.mem[addr:end])
            if end >= mi.end:
                self._mailbox_read_done()
            return data
        return bytes(self.mem[addr:end])

    def write(self, addr: int, data: bytes) -> bool:
        end = addr + len(data)
        mo = self.sm(0)
        if mo.enabled and mo.length and addr < mo.end and end > mo.start:
            self.mem[addr:end] = data
            if end >= mo.end:
                self._mailbox_written()
            return True
        if addr < 0x1000:
            for i, b in enumerate(data):
                a = addr + i
                if a < 0x1000 and not RO[a]:
                    self.mem[a] = b
                elif a >= 0x1000:
                    self.mem[a] = b
            self._after_register_write(addr, end)
        else:
            self.mem[addr:end] = data
        return True

    def _after_register_write(self, addr: int, end: int) -> None:
        def hit(a: int, n: int = 1) -> bool:
            return addr < a + n and end > a

        if hit(R_AL_CONTROL, 2):
            self._al_request(self.u16(R_AL_CONTROL))
        if hit(R_EEP_CTRL, 2):
            self._eeprom_command()
        if hit(R_DC_RECV, 4):
            self._latch_receive_times()
        if hit(0x0300, 0x14):
            self.mem[0x0300:0x0314] = bytes(0x14)  # writing any error counter clears them
        if hit(R_FMMU, 0x100) or hit(R_SM, 0x80) or hit(R_WD_DIV, 2) or hit(R_WD_PD, 2):
            self._layout_changed()
        if hit(R_SM + 6, 1) or hit(R_SM + 8 + 6, 1):
            self._mailbox_repeat()

    def fixed_address(self, adp: int) -> bool:
        """Whether a configured-address datagram (FPxx, FRMW) is this slave's: its station address, or its
        alias where DL control 0x0103 bit 0 enables alias addressing."""
        mem = self.mem
        return adp == _U16.unpack_from(mem, R_STATION)[0] or (bool(mem[0x0103] & 0x01) and adp == _U16.unpack_from(mem, R_ALIAS)[0])

    def frmw(self, adp: int, ado: int, data: bytearray | memoryview) -> int:
        """FRMW, in every process-data frame of a DC master: the addressed slave (the reference clock) reads,
        every other one takes the value as the system time (or a plain write elsewhere). Returns the WKC
        increment, as the line's generic datagram handling counts it."""
        if self.fixed_address(adp):
            got = self.read(ado, len(data))
            if got is None:
                return 0
            data[:] = got
        else:
            self.dc_write(ado, bytes(data))
        return 0 if self.wkc_fault else 1

    def dc_write(self, addr: int, data: bytes) -> None:
        """System-time write from ARMW/FRMW (not a plain register write)."""
        if addr == R_DC_SYSTIME and len(data) in (4, 8):
            value = int.from_bytes(data, "little")
            if len(data) == 4:
                value = (self.system_ns() & ~0xFFFFFFFF) | value
            self._system_time_written(value)
        else:
            self.write(addr, data)

    # ---- EEPROM ---------------------------------------------------------------------------
    def _eeprom_command(self) -> None:
        ctrl = self.u16(R_EEP_CTRL)
        cmd = ctrl & 0x0700
        word = self.u32(R_EEP_ADDR) & 0xFFFF
        status = 0x0040  # 8-byte reads supported
        if cmd == 0x0100:  # read
            off = 2 * word
            chunk = bytes(self.sii[off:off + 8]).ljust(8, b"\xff")
            self.mem[R_EEP_DATA:R_EEP_DATA + 8] = chunk
        elif cmd == 0x0200:  # write one word
            self.sii[2 * word:2 * word + 2] = self.mem[R_EEP_DATA:R_EEP_DATA + 2]
        elif cmd == 0x0400:  # reload
            pass
        elif cmd:
            status |= 0x2000  # command error
        struct.pack_into("<H", self.mem, R_EEP_CTRL, status)

    # ---- AL state machine -----------------------------------------------------------------
    def al_error(self, code: int, state: int | None = None, why: str = "") -> None:
        s = state if state is not None else self.al_state
        struct.pack_into("<H", self.mem, R_AL_STATUS, s | AL_ERROR)
        struct.pack_into("<H", self.mem, R_AL_CODE, code)
        self.events.append(f"AL status 0x{code:04X} ({_al_text(code)}){why} -> {STATE_TEXT.get(s, s)} + ERROR")

    def _set_state(self, s: int) -> None:
        struct.pack_into("<H", self.mem, R_AL_STATUS, s)
        struct.pack_into("<H", self.mem, R_AL_CODE, 0)

    def _al_request(self, ctrl: int) -> None:
        req, ack = ctrl & 0x0F, bool(ctrl & 0x10)
        cur, err = self.al_state, bool(self.mem[R_AL_STATUS] & AL_ERROR)
        if err and not ack and req > cur:
            return  # an error must be acknowledged before going up
        if err and ack:
            self._set_state(cur)
        if req == cur:
            return
        if req not in (INIT, PREOP, BOOT, SAFEOP, OP):
            self.al_error(AL_UNKNOWN_STATE, cur)
            return
        if req == BOOT:
            self.al_error(AL_BOOTSTRAP_NOT_SUPPORTED, cur)
            return
        if req < cur:
            self._set_state(req)
            if req <= PREOP:
                self.rx_map, self.tx_map = [], []
            return
        allowed = {INIT: (PREOP,), PREOP: (SAFEOP,), SAFEOP: (OP,)}
        if req not in allowed.get(cur, ()):
            self.al_error(AL_INVALID_STATE_CHANGE, cur)
            return
        # The SYNC0 cycle is judged on the way into SAFE-OP when the master programmed DC before (TwinCAT,
        # ETG.1020 order), and again into OP for masters that start SYNC0 in SAFE-OP (SOEM).
        check = {PREOP: self._check_mailbox, SAFEOP: lambda: self._check_sync() or self._check_process_data(),
                 OP: self._check_sync}[req]
        code = self.refuse.get(req) or check()
        if code:
            self.al_error(code, cur)
            return
        self._set_state(req)
        if req == OP:
            self.last_output_ns = time.monotonic_ns()

    def _check_mailbox(self) -> int:
        for k, d in ((0, self.device.mailbox_out), (1, self.device.mailbox_in)):
            s = self.sm(k)
            if not s.enabled or s.start != d.start or s.length != d.size:
                return AL_INVALID_MAILBOX
        return 0

    def _check_process_data(self) -> int:
        """SM2/SM3 must match the PDO mapping in the object dictionary, and FMMUs must cover them."""
        rx = self.od.mapping(0x1C12) if 0x1C12 in self.od.objects else []
        tx = self.od.mapping(0x1C13) if 0x1C13 in self.od.objects else []
        rx_bytes = (sum(b for *_, b in rx) + 7) // 8
        tx_bytes = (sum(b for *_, b in tx) + 7) // 8
        for k, nbytes, code, ftype in ((2, rx_bytes, AL_INVALID_OUTPUT, 2), (3, tx_bytes, AL_INVALID_INPUT, 1)):
            d, s = self.device.sms[k], self.sm(k)
            if nbytes == 0:
                continue
            if not s.enabled or s.start != d.start or s.length != nbytes:
                return code
            if not any(f[2] & ftype and f[1] <= s.start < f[1] + max(f[3], 1) for f in self.fmmus()):
                return code
        self.rx_map, self.tx_map = rx, tx
        self._write_inputs(self.app.cycle(bytes(rx_bytes), rx, tx, step=False))
        return 0

    def _check_sync(self) -> int:
        act = self.mem[R_DC_ACTIVATION]
        if act & 0x01 and act & 0x02:
            if not self.device.assign_activate:
                return AL_INVALID_DC_SYNC
            cyc = self.u32(R_DC_SYNC0_CYCLE)
            d = self.device
            if cyc < d.sync0_min or cyc > d.sync0_max or (d.sync0_step and cyc % d.sync0_step):
                return AL_INVALID_SYNC0_CYCLE
        return 0

    # ---- FMMUs and process data -------------------------------------------------------------
    def fmmus(self) -> list[tuple[int, int, int, int]]:
        """Active FMMUs as (logical start, physical start, type, length)."""
        if self._fmmus is None:
            out = []
            for k in range(8):
                ls, ln, _sb, _eb, ps, _pb, typ, act = struct.unpack_from("<IHBBHBBB", self.mem, R_FMMU + 16 * k)
                if act & 1 and ln:
                    out.append((ls, ps, typ, ln))
            self._fmmus = out
        return self._fmmus

    def _write_inputs(self, data: bytes) -> None:
        if data:
            s = self.sm(3)
            self.mem[s.start:s.start + len(data)] = data

    def logical(self, cmd: int, addr: int, data: bytearray | memoryview) -> int:
        """LRD/LWR/LRW through the FMMUs. Returns the WKC increment. In lock-step the outputs are
        applied and the model advanced before the inputs are copied, so one frame = one cycle."""
        mem = self.mem
        status = mem[R_AL_STATUS]
        state = status & 0x0F
        if state != SAFEOP and state != OP:
            return 0
        key = (cmd, addr, len(data))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = self._plan(cmd, addr, len(data))
        writes, reads, outputs, inputs = plan
        inc = 0
        if writes and not status & AL_ERROR:
            # The ESC takes outputs from SAFE-OP on (the SM is enabled); only OP applies them. After
            # an error (watchdog, sync) the application deactivates the output SM: no write WKC.
            for d0, d1, p0, p1 in writes:
                mem[p0:p1] = data[d0:d1]
            inc += 2 if cmd == LRW else 1
        # A slave without outputs (an R1-EC station of input modules only) cycles on its reads.
        if state == OP and (writes or (reads and not self.rx_map)):
            now = time.monotonic_ns()
            dt = self.cycle_time
            if not self.lockstep and self.last_cycle_ns:
                dt = min(10 * self.cycle_time, max(0.0, (now - self.last_cycle_ns) * 1e-9))
            self.last_cycle_ns = now
            self.last_output_ns = now
            self.outputs_written += 1
            got = self.app.cycle(outputs, self.rx_map, self.tx_map, True, dt)
            if got:
                mem[inputs:inputs + len(got)] = got
        elif reads and state == SAFEOP:
            lost = bool(status & AL_ERROR) and self.outputs_written > 0  # dropped out of OP
            if lost:
                self.last_cycle_ns = time.monotonic_ns()  # this frame is the drive's time: `coast` goes on from it
            self._write_inputs(self.app.cycle(outputs, self.rx_map, self.tx_map, step=lost, dt=self.cycle_time,
                                              lost=lost))
        if reads:
            for d0, d1, p0, p1 in reads:
                data[d0:d1] = mem[p0:p1]
            inc += 1
        return 0 if self.wkc_fault else inc

    def _plan(self, cmd: int, addr: int, n: int) -> tuple[list, list, memoryview, int]:
        """Where a logical datagram's bytes go: (datagram slice, physical slice) per FMMU it hits,
        outputs (written) and inputs (read); then the SM2 area the application reads its outputs from
        (a view of `mem`) and where SM3, its inputs, starts. Dropped when FMMUs or SMs change."""
        reads, writes = [], []
        for ls, ps, typ, ln in self.fmmus():
            lo, hi = max(addr, ls), min(addr + n, ls + ln)
            if lo >= hi:
                continue
            part = (lo - addr, hi - addr, ps + lo - ls, ps + hi - ls)
            if typ & 2 and cmd in (LWR, LRW):
                writes.append(part)
            if typ & 1 and cmd in (LRD, LRW):
                reads.append(part)
        s2 = self.sm(2)
        return writes, reads, memoryview(self.mem)[s2.start:s2.end], self.sm(3).start

    # ---- watchdog -------------------------------------------------------------------------
    def watchdog_ns(self) -> int:
        if self._wd_ns is None:
            self._wd_ns = self.u16(R_WD_PD) * (self.u16(R_WD_DIV) + 2) * 40
        return self._wd_ns

    def check_watchdog(self, now_ns: int) -> None:
        if self.mem[R_AL_STATUS] & 0x0F != OP or not self.rx_map or not (self._sms.get(2) or self.sm(2)).control & 0x40:
            return
        wd = self._wd_ns if self._wd_ns is not None else self.watchdog_ns()  # decoded once (every slave, every frame)
        if wd and now_ns - self.last_output_ns > wd:
            struct.pack_into("<H", self.mem, R_WD_STATUS, 0)
            self.al_error(AL_SM_WATCHDOG, SAFEOP, f": no process data for {wd / 1e6:g} ms")

    def coast(self, now_ns: int) -> None:
        """The line is silent after this slave fell out of OP by an error (its master gone, stalled or cut
        off): the application's time runs on by the clock, a cycle at a time, so a drive brakes on its
        communication fault reaction to standstill as a real one does on its own (decision E33). A master
        that still reads the slave steps it frame by frame instead (`logical`)."""
        if not self.mem[R_AL_STATUS] & AL_ERROR or not self.outputs_written:
            return
        app = self.app
        if not app.coasting:
            self.last_cycle_ns = now_ns
            return
        dt = self.cycle_time
        steps = min(int((now_ns - self.last_cycle_ns) * 1e-9 / dt), COAST_MAX_STEPS)
        for _ in range(steps):
            msg = app.coast(dt)
            if msg is not None:
                self.events.append(msg)
            if not app.coasting:
                break
        self.last_cycle_ns = now_ns

    # ---- mailbox --------------------------------------------------------------------------
    def _mailbox_written(self) -> None:
        mo = self.sm(0)
        raw = bytes(self.mem[mo.start:mo.end])
        length, _addr, _chan, typ = struct.unpack_from("<HHBB", raw, 0)
        payload = raw[6:6 + length]
        if typ & 0x0F == MBX_TYPE_COE:
            for resp in self.coe.handle(payload):
                if resp:
                    self.post(MBX_TYPE_COE, resp)
        else:
            self.post(MBX_TYPE_ERR, struct.pack("<HH", 0x0001, 0x0002))  # unsupported protocol

    def post(self, typ: int, payload: bytes) -> None:
        self.mbx_counter = self.mbx_counter % 7 + 1
        msg = struct.pack("<HHBB", len(payload), 0, 0, typ | (self.mbx_counter << 4)) + payload
        if len(self.mbx_out) < 64:
            self.mbx_out.append(msg)
        self._mailbox_fill()

    def emergency(self, code: int, register: int = 0x01, data: bytes = b"") -> None:
        if self.al_state >= PREOP:
            self.post(MBX_TYPE_COE, self.coe.emergency(code, register, data))

    def _mailbox_fill(self) -> None:
        if self.mbx_full or not self.mbx_out:
            return
        mi = self.sm(1)
        if not mi.enabled:
            return
        msg = self.mbx_out.popleft()
        self.mem[mi.start:mi.end] = msg[:mi.length].ljust(mi.length, b"\x00")
        self.mbx_last = msg
        self.mbx_full = True
        self.mem[R_SM + 8 + 5] |= 0x08

    def _mailbox_read_done(self) -> None:
        self.mbx_full = False
        self.mem[R_SM + 8 + 5] &= ~0x08 & 0xFF
        self._mailbox_fill()

    def _mailbox_repeat(self) -> None:
        """Mailbox repeat: the master toggles SM1 activate bit 1; put the last message back."""
        req = self.mem[R_SM + 8 + 6] & 0x02
        if req != self.mem[R_SM + 8 + 7] & 0x02:
            if self.mbx_last and not self.mbx_full:
                self.mbx_out.appendleft(self.mbx_last)
                self._mailbox_fill()
            self.mem[R_SM + 8 + 7] = (self.mem[R_SM + 8 + 7] & ~0x02 & 0xFF) | req

    def idle(self) -> None:
        """Refresh mailbox availability after SM writes."""
        self._mailbox_fill()
