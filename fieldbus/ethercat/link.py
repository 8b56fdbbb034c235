"""`EthercatLink`: the `BusLink` over a real (or veth) EtherCAT line, with pysoem as the master.

Bring-up: config_init → per-slave PDO mapping over SDO in pysoem's config hook (the Delta ASDA
preset, or a layout per slave) → config_map → SAFE-OP → distributed clocks (SYNC0 at the bench
cycle, first DC slave the reference clock) → OP, checking the state after every step. Each
`exchange` is one LRW frame; the working counter is checked every cycle. Short outages (lost
frames, a slave off the line for a few cycles) are ridden through on the last inputs; longer ones,
and any AL error, raise `BusError` with the NC5 alarm.

Why one file of ~520 lines: bring-up, the cyclic exchange and the outage riding read and write the same
slave table, PDO views and working-counter state, in the order the line's state machine needs; the
pure parts live beside it (PDO mapping in pdo_mapping.py, alarms in alarms.py, images in fieldbus.pdo).
"""

from __future__ import annotations

import struct
import time
from time import perf_counter_ns
from collections.abc import Sequence
from dataclasses import dataclass, field

import pysoem

from fieldbus.ethercat import alarms as A
from fieldbus.ethercat.pdo_mapping import mapping_sdos, mapping_sdos_complete
from fieldbus.link import BusError, LinkStatus, SlaveInfo, drive_state_text
from fieldbus.cia402 import SW_FAULT
from fieldbus.pdo import ASDA_E, LAYOUTS, PdoLayout, RxPdo, TxPdo
from nc.alarms import Alarm

DELTA_VENDOR = 0x000001DD
STATE_NAMES = {0: "NONE", 1: "INIT", 2: "PRE-OP", 3: "BOOT", 4: "SAFE-OP", 8: "OP"}
R_DC_DIFF = 0x092C


class SdoAbort(Exception):
    """The slave refused an SDO transfer; `code` is the CoE abort code."""

    def __init__(self, code: int, message: str) -> None:
        self.code = code
        super().__init__(message)


def state_name(state: int) -> str:
    base = STATE_NAMES.get(state & 0x0F, f"0x{state & 0x0F:X}")
    return base + ("+ERR" if state & 0x10 else "")


@dataclass
class LinkStats:
    cycles: int = 0
    bad_cycles: int = 0  # cycles answered late, lost, or with a wrong working counter
    lost_frames: int = 0
    recoveries: int = 0
    max_drift_ns: int = 0
    events: list[str] = field(default_factory=list)


LOST_LINE_TIMEOUT_US = 2_000  # receive timeout once the line is lost after its alarm (SOEM's EC_TIMEOUTRET)


@dataclass
class EthercatLink:
    iface: str
    cycle_time: float = 0.001
    names: Sequence[str] = ()  # one per drive, in bus order (axes, then spindles)
    layouts: Sequence[PdoLayout] = ()  # per drive; default ASDA_E (Delta's 0x1602/0x1A02 sets)
    complete_access: bool = False  # map with complete access first (falls back to subindex writes)
    dc: bool = True
    receive_timeout_us: int = 100_000  # Python slaves on a loaded CI host: SOEM's 2 ms is far too short
    max_bad_cycles: int = 3  # consecutive bad cycles ridden through before the alarm
    watchdog_ms: float = 500.0  # SM watchdog programmed into every slave
    drift_check_every: int = 250  # cycles between DC drift reads (0x092C of every drive)
    drift_limit_ns: int = 50_000  # |system time difference| above this raises 0x141F; 0 = only record it
    stats: LinkStats = field(default_factory=LinkStats)
    io_names: Sequence[str] = ()  # remote I/O stations, k-th I/O slave in connection order (EIO node 501+k)
    aliases: Sequence[int | None] = ()  # per drive (axes, then spindles): the station alias it must have (0x1416)

    def __post_init__(self) -> None:
        self.master: pysoem.Master | None = None
        self.drives: list = []  # pysoem slaves carrying drives, in bus order
        self.io: list = []  # other slaves (R1-EC class I/O)
        self.infos: list[SlaveInfo] = []
        self._last: list[TxPdo] = []
        self._bad = 0
        self._structs: list[PdoLayout] = []
        # per drive, decided once at bring-up: the master derives 0x60F4 / reads 0x603F (no PDO carries it)
        self._derived_fe: list[bool] = []
        self._derived_ec: list[bool] = []
        self._plan: list[tuple] = []  # (slave, layout, derive 0x60F4, read 0x603F) per drive
        self._states: list[str] = []  # per slave as `infos` lists them, refreshed on every bad cycle
        self._all_op: list[str] = []  # what `_states` reads after a good frame (shared, never changed in place)
        self._failed = False  # a bus alarm was raised and the line was not recovered since
        self._lost = 0  # consecutive lost frames (no answer at all)
        # status() of the last call, with what it was built from: `_states` (by identity: it is replaced, never
        # changed in place), `_failed` and whether the master is open
        self._status: tuple[list[str], bool, bool, LinkStatus] | None = None
        self._io_out: list[bytes] = []  # per I/O slave: the output image the next frame carries
        self._io_in: list[bytes] = []  # per I/O slave: the input image of the last good frame
        self.wait_ns = 0  # the last exchange's time in pysoem's send and receive: the wait for the line (E25)

    @classmethod
    def for_bench(cls, bench, iface: str) -> "EthercatLink":
        names = list(bench.axis_names) + [s.name for s in bench.spindles]
        params = getattr(bench, "params", {}) or {}
        layout = LAYOUTS.get(str(params.get("ethercat_pdo", "")), ASDA_E)
        link = cls(iface, bench.cycle, names, [layout] * len(names),
                   complete_access=bool(params.get("ethercat_complete_access", False)))
        link.io_names = [st.map.name for st in getattr(bench, "io", [])]
        link.aliases = [getattr(c, "station_alias", None) for c in list(bench.axes) + list(bench.spindles)]
        # bench [params]: ethercat_drift_limit_ns, ethercat_drift_check_every (docs/decisions E8)
        link.drift_limit_ns = int(params.get("ethercat_drift_limit_ns", link.drift_limit_ns))
        link.drift_check_every = int(params.get("ethercat_drift_check_every", link.drift_check_every))
        return link

    # ---- bring-up -----------------------------------------------------------------------
    def open(self) -> list[SlaveInfo]:
        t = pysoem.settings.timeouts
        t.ret = max(t.ret, self.receive_timeout_us)
        t.safe = max(t.safe, self.receive_timeout_us)
        t.eeprom = max(t.eeprom, 50_000)
        t.state = max(t.state, 5_000_000)
        m = pysoem.Master()
        try:
            m.open(self.iface)
        except Exception as exc:
            raise BusError(Alarm(A.INIT_ERROR, f"cannot open EtherCAT interface {self.iface}: {exc}")) from None
        self.master = m
        try:
            return self._bring_up(m)
        except BusError:
            self.close()
            raise

    def scan(self) -> list[SlaveInfo]:
        """Find the slaves and bring them to PRE-OP, without configuring process data."""
        m = pysoem.Master()
        try:
            m.open(self.iface)
        except Exception as exc:
            raise BusError(Alarm(A.INIT_ERROR, f"cannot open EtherCAT interface {self.iface}: {exc}")) from None
        try:
            n = m.config_init()
            if n <= 0:
                raise BusError(Alarm(A.NO_SLAVES, f"no EtherCAT slaves found on {self.iface}"))
            m.read_state()
            infos = [SlaveInfo(i, s.name, self._kind(s), s.man, s.id, state_name(s.state)) for i, s in enumerate(m.slaves)]
            for info, s in zip(infos, m.slaves):
                if info.kind == "io":
                    info.name, info.layout = self._io_identity(s)
                else:
                    info.drive = self._drive_state(s)
            return infos
        finally:
            m.close()

    @staticmethod
    def _kind(s) -> str:
        try:
            device_type = struct.unpack("<I", s.sdo_read(0x1000, 0)[:4])[0]
        except Exception:
            return "io"
        return "drive" if device_type & 0xFFFF == 402 else "io"

    @staticmethod
    def _drive_state(s) -> str:
        """The drive's CiA 402 state (0x6041) and, in fault, its error code (0x603F), over SDO: a drive left in
        fault (a master that died, E33) shows here before a run resets it (B72)."""
        try:
            sw = struct.unpack("<H", s.sdo_read(0x6041, 0)[:2])[0]
            code = struct.unpack("<H", s.sdo_read(0x603F, 0)[:2])[0]
        except Exception:  # no such object or no mailbox answer: the scan shows what it has
            return ""
        return drive_state_text(sw, code)

    @staticmethod
    def _io_identity(s) -> tuple[str, str]:
        """An I/O slave's own name (0x1008) and R1-EC module list (0xF050, "DI32+DO8"), over SDO: SOEM
        copies SII data between slaves of one identity, so the SII name of the first R1-EC would stand
        for every station whatever its modules (docs/decisions/ethercat.md, E10)."""
        try:
            name = s.sdo_read(0x1008, 0).decode("latin-1").strip() or s.name
        except Exception:
            name = s.name
        return name, "+".join(EthercatLink._read_modules(s) or [])

    @staticmethod
    def _read_modules(s) -> list[str] | None:
        """The R1-EC module list a slave reports in 0xF050; None if it keeps none."""
        from fieldbus.ethercat.r1ec_modules import ident_name

        try:
            n = s.sdo_read(0xF050, 0, 1)[0]
            return [ident_name(struct.unpack("<I", s.sdo_read(0xF050, k, 4)[:4])[0]) for k in range(1, n + 1)]
        except Exception:  # no such object (or no mailbox): nothing to compare
            return None

    def _bring_up(self, m) -> list[SlaveInfo]:
        n = m.config_init()
        if n <= 0:
            raise BusError(Alarm(A.NO_SLAVES, f"no EtherCAT slaves found on {self.iface}"))
        slaves = list(m.slaves)
        kinds = [self._kind(s) for s in slaves]
        self.drives = [s for s, k in zip(slaves, kinds) if k == "drive"]
        self.io = [s for s, k in zip(slaves, kinds) if k != "drive"]
        if len(self.drives) < len(self.names):
            raise BusError(Alarm(A.NO_SLAVES, f"{len(self.drives)} CiA 402 drives found on {self.iface}, "
                                              f"the bench needs {len(self.names)} ({', '.join(self.names)})"))
        if len(self.drives) > len(self.names):
            # Mapped by order, the bench's drives would take the line's first ones and the rest would idle in
            # PRE-OP: a line that is not the configured one (another machine's, a drive added) would have the bench's
            # spindle command drive a linear axis. A master refuses a line unlike its configuration (decisions E28).
            raise BusError(Alarm(A.PDO_MISMATCH, f"{len(self.drives)} CiA 402 drives found on {self.iface}, the bench "
                                                 f"names {len(self.names)} ({', '.join(self.names)}): the line does not "
                                                 f"match the bench; describe every drive on it"))
        self._check_aliases()
        layouts = list(self.layouts) or [ASDA_E] * len(self.names)
        self._structs = layouts
        self._derived_fe = [not layout.carries(0x60F4) for layout in layouts]
        self._derived_ec = [not layout.carries(0x603F) for layout in layouts]
        # per drive, what a good frame's cycle does with it, in one pass (E26)
        self._plan = list(zip(self.drives, layouts, self._derived_fe, self._derived_ec))
        errors: list[Alarm] = []
        for s, layout, name in zip(self.drives, layouts, self.names):
            s.config_func = self._mapper(s, layout, name, errors)
        try:
            m.config_map()
        except Exception as exc:
            raise BusError(errors[0] if errors else Alarm(A.PDO_MISMATCH, f"config_map failed: {exc}")) from None
        if errors:
            raise BusError(errors[0])
        for s, layout, name in zip(self.drives, layouts, self.names):
            if len(s.output) != layout.rx_bytes or len(s.input) != layout.tx_bytes:
                raise BusError(Alarm(A.PDO_MISMATCH, f"{name}: process image {len(s.output)}/{len(s.input)} bytes, "
                                                     f"layout {layout.name} needs {layout.rx_bytes}/{layout.tx_bytes}"))
        self._expect(m, pysoem.SAFEOP_STATE, "SAFE-OP")
        for s in slaves:
            try:
                s.set_watchdog("processdata", self.watchdog_ms)
            except Exception:  # slaves without the watchdog register keep their default
                pass
        if self.dc:
            m.config_dc()
            for s in self.drives:
                s.dc_sync(True, int(round(self.cycle_time * 1e9)))
        # SOEM's recipe: valid outputs on the wire before requesting OP
        for s, layout in zip(self.drives, layouts):
            s.output = layout.pack_rx(RxPdo(mode=0))
        m.state = pysoem.OP_STATE
        m.send_processdata()
        m.receive_processdata(self.receive_timeout_us)
        m.write_state()
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            m.send_processdata()
            m.receive_processdata(self.receive_timeout_us)
            if m.state_check(pysoem.OP_STATE, 5_000) == pysoem.OP_STATE:
                break
        self._expect(m, pysoem.OP_STATE, "OP", wait_us=1_000)
        m.read_state()
        self._last = [layout.unpack_tx(s.input) for s, layout in zip(self.drives, layouts)]
        self.infos = [SlaveInfo(i, name, "drive", s.man, s.id, state_name(s.state), layout.name)
                      for i, (s, name, layout) in enumerate(zip(self.drives, self.names, layouts))]
        for s in self.io:
            name, mods = self._io_identity(s)
            self.infos.append(SlaveInfo(len(self.infos), name, "io", s.man, s.id, state_name(s.state), mods))
        self._states = [i.state for i in self.infos]
        self._all_op = ["OP"] * len(self.infos)
        self._failed = False
        self._io_out = [bytes(len(s.output)) for s in self.io]
        self._io_in = [bytes(s.input) for s in self.io]
        return self.infos

    def _check_aliases(self) -> None:
        """App. A 0x1416 "The slave address is different from the system address setting": a drive whose bench
        entry names a station alias (`drive.alias`) must carry it in its SII (word 4)."""
        for k, (s, name, want) in enumerate(zip(self.drives, self.names, self.aliases)):
            if want is None:
                continue
            try:
                have = struct.unpack("<H", s.eeprom_read(4)[:2])[0]
            except Exception as exc:  # the SII cannot be read: the address cannot be confirmed either
                raise BusError(Alarm(A.SLAVE_MISMATCH, f"{name}: cannot read the station alias of drive slave {k + 1}: "
                                                       f"{exc}", axis=name)) from None
            if have != want:
                raise BusError(Alarm(A.SLAVE_MISMATCH, f"{name}: drive slave {k + 1} on the line has station alias "
                                                       f"{have}, the bench expects {want} (drive.alias)", axis=name))

    def _mapper(self, s, layout: PdoLayout, name: str, errors: list[Alarm]):
        def write_all(sdos, complete: bool) -> None:
            for index, sub, data in sdos:
                s.sdo_write(index, sub, data, complete)

        def configure(_pos: int) -> None:
            if self.complete_access:
                try:
                    write_all(mapping_sdos_complete(layout), True)
                    return
                except pysoem.SdoError as exc:  # no complete access on this drive: entry by entry
                    self.stats.events.append(f"{name}: complete access refused (0x{exc.abort_code:08X}), "
                                             f"mapping entry by entry")
            for index, sub, data in mapping_sdos(layout):
                try:
                    s.sdo_write(index, sub, data, False)
                except pysoem.SdoError as exc:
                    errors.append(Alarm(A.PDO_MISMATCH, f"{name}: PDO mapping {layout.name} refused at "
                                                        f"0x{index:04X}:{sub:02X}: SDO abort 0x{exc.abort_code:08X} "
                                                        f"({exc.desc})"))
                    return
        return configure

    def _expect(self, m, state: int, label: str, wait_us: int = 2_000_000) -> None:
        if m.state_check(state, wait_us) == state:
            return
        m.read_state()
        for s, name in self._named(m):
            if s.state != state:
                raise BusError(A.bringup_alarm(label, s.al_status, f"slave {name} ({state_name(s.state)})"))
        raise BusError(A.bringup_alarm(label, 0, "the line"))

    def _named(self, m):
        names = {id(s): n for s, n in zip(self.drives, self.names)}
        for k, s in enumerate(self.io):  # remote I/O stations by bench name and EIO node
            names[id(s)] = f"{self.io_names[k] if k < len(self.io_names) else s.name} (EIO node {501 + k})"
        return [(s, names.get(id(s), s.name)) for s in m.slaves]

    # ---- cyclic -------------------------------------------------------------------------
    def exchange(self, outputs: Sequence[RxPdo]) -> list[TxPdo]:
        m = self.master
        if m is None:
            raise BusError(Alarm(A.DISCONNECTED, "EtherCAT link used before open()"))
        if len(outputs) != len(self.drives):
            raise ValueError(f"{len(outputs)} output images for {len(self.drives)} drives")
        for s, layout, rx in zip(self.drives, self._structs, outputs):
            s.output = layout.pack_rx(rx)
        if self.io:
            for s, data in zip(self.io, self._io_out):  # remote I/O outputs the MLC wrote (mlc/remote_io.py)
                s.output = data
        t0 = perf_counter_ns()
        m.send_processdata()
        # A line silent for twice the slaves' SM watchdog after its alarm (every drive has dropped out of OP and
        # braked on its own fault reaction) is waited for no longer than SOEM's own 2 ms a frame: the stop path
        # cycles it until the drives' feedback is seen frozen, and 100 ms a lost frame made that minutes (E27)
        dead = self._failed and self._lost * self.receive_timeout_us > 2_000 * self.watchdog_ms
        wkc = m.receive_processdata(LOST_LINE_TIMEOUT_US if dead else self.receive_timeout_us)
        self.wait_ns = perf_counter_ns() - t0
        stats = self.stats
        stats.cycles += 1
        if wkc == m.expected_wkc:
            self._bad = self._lost = 0
            if not self._failed:  # the full working counter: every slave exchanged, so every slave is in OP
                self._states = self._all_op
            last = self._last
            # Inputs unpacked, then what the layout does not carry (no Delta PDO set maps 0x60F4; ASDA_E leaves 0x603F
            # out): the following error in CSP is the target just sent less the position reached (the drive's own
            # 0x60F4 in lock-step; 0 until enabled, the command follows the actual position), and the error code is
            # read over SDO once when the fault bit rises. Drive by drive in one pass, not three loops (E26).
            for (s, layout, fe, ec), rx, tx in zip(self._plan, outputs, last):
                layout.unpack_tx(s.input, tx)
                if fe:
                    tx.following_error = rx.target_position - tx.position_actual \
                        if tx.mode_display == 8 and tx.statusword & 0x6F == 0x27 else 0
                if ec:
                    if not tx.statusword & SW_FAULT:
                        tx.error_code = 0
                    elif not tx.error_code:
                        tx.error_code = _error_code(s)
            if self.io:
                self._io_in = [s.input for s in self.io]  # (pysoem hands out a new bytes object every read)
            if self.dc and self.drift_check_every and not self._failed and stats.cycles % self.drift_check_every == 0:
                self._check_drift()
            return list(last)
        return self._bad_cycle(m, wkc)

    def _read_error_codes(self) -> None:
        for s, derive, tx in zip(self.drives, self._derived_ec, self._last):
            if derive:
                if not tx.statusword & SW_FAULT:
                    tx.error_code = 0
                elif not tx.error_code:
                    tx.error_code = _error_code(s)

    def _bad_cycle(self, m, wkc: int) -> list[TxPdo]:
        self.stats.bad_cycles += 1
        self._bad += 1
        if wkc < 0:
            self.stats.lost_frames += 1
            self._lost += 1
        else:
            self._lost = 0
        # A lost frame says no slave answered: reading their AL states needs the same line, and on a dead line each
        # read waits out SOEM's timeouts (≈ 2.3 s with 4 slaves): they are read only where a frame came back
        # (decisions E27)
        if wkc >= 0:
            m.read_state()
            self._states = [state_name(s.state) for s in self.drives + self.io]
        if self._failed:
            return self._ride_on(wkc)
        try:
            return self._judge_bad_cycle(m, wkc)
        except BusError:
            self._failed = True
            raise

    def _ride_on(self, wkc: int) -> list[TxPdo]:
        """The alarm is already raised: keep the line cycling so the NC can stop the drives still on
        it under control (the stop must not depend on the slave that failed). A slave in SAFE-OP or OP
        still returns its inputs in the frame; a lost frame or a slave further down keeps its last."""
        if wkc >= 0:
            live = (pysoem.SAFEOP_STATE, pysoem.OP_STATE)
            self._last = [layout.unpack_tx(s.input, tx) if s.state & 0x0F in live else tx
                          for s, layout, tx in zip(self.drives, self._structs, self._last)]
            self._read_error_codes()  # a drive that faults on the bus alarm names its code (0x7500 …)
        return list(self._last)

    def _judge_bad_cycle(self, m, wkc: int) -> list[TxPdo]:
        io = {id(s) for s in self.io}
        for s, name in self._named(m):
            if s.state & pysoem.STATE_ERROR:
                code = A.EIO_FAILED if id(s) in io else A.DISCONNECTED
                raise BusError(Alarm(code, f"EtherCAT slave {name} dropped to {state_name(s.state)}: "
                                           f"{A.al_text(s.al_status)}", axis=self._axis(name), info=s.al_status))
        if self._bad > self.max_bad_cycles:
            what = "no frame returned" if wkc < 0 else f"working counter {wkc}, expected {m.expected_wkc}"
            silent = self._lost >= self._bad  # every frame of the run lost: no state could be read
            lost = [] if silent else [(s, name) for s, name in self._named(m) if s.state != pysoem.OP_STATE]
            bad = [name for _, name in lost]
            who = bad[0] if bad else (self.names[0] if self.names else "line")
            # Only remote I/O stations gone, every drive still in OP: the EIO alarm (NC5 App. A 0x1426).
            code = A.EIO_FAILED if lost and all(id(s) in io for s, _ in lost) else A.DISCONNECTED
            where = "no slave answered" if silent else f"not in OP: {', '.join(bad) or 'none'}"
            raise BusError(Alarm(code, f"EtherCAT communication lost for {self._bad} cycles ({what}); {where}",
                                 axis=self._axis(who)))
        self.stats.events.append(f"cycle {self.stats.cycles}: bad working counter {wkc}, riding through")
        return list(self._last)

    def status(self) -> LinkStatus:
        """Connected (M30000) while every slave reads OP and no bus alarm stands; per-slave states as
        last seen (a good working counter means OP; a bad cycle re-reads the AL states). The runner reads it
        every cycle and never changes it: the same object comes back until one of those changes (building
        it was 2.5 µs of a lock-step cycle's CPU)."""
        states, failed, opened = self._states, self._failed, self.master is not None
        last = self._status
        if last is not None and last[0] is states and last[1] == failed and last[2] == opened:
            return last[3]
        ok = opened and not failed and bool(states) and all(st == "OP" for st in states)
        st = LinkStatus(ok, [i.name for i in self.infos], [i.kind for i in self.infos], list(states))
        self._status = (states, failed, opened, st)
        return st

    # ---- remote I/O slaves (R1-EC class), k-th in connection order = EIO node 501+k ---------------
    def io_bits(self, k: int) -> tuple[int, int]:
        """(input bits, output bits) of the k-th I/O slave's process image; (0, 0) if there is none."""
        if k >= len(self._io_in):
            return 0, 0
        return 8 * len(self._io_in[k]), 8 * len(self._io_out[k])

    def io_modules(self, k: int) -> list[str] | None:
        """The k-th I/O slave's R1-EC modules in slot order (0xF050 over SDO); None if it lists none."""
        return self._read_modules(self.io[k]) if self.master is not None and k < len(self.io) else None

    def io_ok(self, k: int) -> bool:
        """The k-th I/O slave is in OP and the link stands (its inputs are current)."""
        pos = len(self.drives) + k
        return self.master is not None and not self._failed and pos < len(self._states) \
            and self._states[pos] == "OP"

    def io_inputs(self, k: int) -> int:
        """The k-th I/O slave's inputs from the last good frame, little-endian; 0 while it is not in OP."""
        if not self.io_ok(k):
            return 0
        return int.from_bytes(self._io_in[k], "little")

    def set_io_outputs(self, k: int, value: int) -> None:
        """Outputs the next frame carries to the k-th I/O slave (bits past its image are dropped)."""
        if k < len(self._io_out):
            n = len(self._io_out[k])
            self._io_out[k] = (value & ((1 << 8 * n) - 1)).to_bytes(n, "little")

    def _axis(self, name: str) -> str | None:
        return name if name in self.names else None

    def _check_drift(self) -> None:
        """Read each drive's system time difference (0x092C, sign-magnitude ns): past the limit the
        drive can no longer follow SYNC0, so the run stops with 0x141F on that axis (E8)."""
        worst, who = 0, ""
        for s, name in zip(self.drives, self.names):
            try:
                raw = s._fprd(R_DC_DIFF, 4)
            except Exception:
                continue
            v = struct.unpack("<I", raw[:4])[0] & 0x7FFFFFFF
            if v > worst:
                worst, who = v, name
        self.stats.max_drift_ns = max(self.stats.max_drift_ns, worst)
        if self.drift_limit_ns and worst > self.drift_limit_ns:
            self.stats.events.append(f"cycle {self.stats.cycles}: DC drift {worst} ns above {self.drift_limit_ns} ns")
            self._failed = True
            raise BusError(Alarm(A.DC_DRIFT, f"EtherCAT DC drift on {who}: system time difference {worst} ns, "
                                             f"limit {self.drift_limit_ns} ns", axis=self._axis(who), info=worst))

    # ---- recovery, SDO, close -------------------------------------------------------------
    def recover(self, timeout: float = 5.0) -> bool:
        """Bring every slave back to OP after an outage (SOEM's ecatcheck recipe): acknowledge
        errors, re-address lost slaves, reconfigure those that fell back to INIT/PRE-OP."""
        m = self.master
        if m is None:
            return False
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            m.send_processdata()
            m.receive_processdata(self.receive_timeout_us)
            m.read_state()
            pending = False
            for s in m.slaves:
                st = s.state
                if st == pysoem.OP_STATE:
                    continue
                pending = True
                if st == pysoem.SAFEOP_STATE + pysoem.STATE_ERROR:
                    s.state = pysoem.SAFEOP_STATE + pysoem.STATE_ACK
                    s.write_state()
                elif st == pysoem.SAFEOP_STATE:
                    s.state = pysoem.OP_STATE
                    s.write_state()
                elif st == pysoem.NONE_STATE:
                    s.recover()
                else:
                    s.reconfig()
            if not pending:
                self._bad = 0
                self._failed = False
                self._states = ["OP"] * len(self.infos)
                self.stats.recoveries += 1
                return True
        return False

    def sdo_read(self, position: int, index: int, sub: int = 0, size: int = 0) -> bytes:
        return self._sdo(position, lambda s: s.sdo_read(index, sub, size) if size else s.sdo_read(index, sub))

    def sdo_write(self, position: int, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        self._sdo(position, lambda s: s.sdo_write(index, sub, data, complete))

    def _sdo(self, position: int, op):
        if self.master is None:
            raise BusError(Alarm(A.DISCONNECTED, "EtherCAT link used before open()"))
        s = self.master.slaves[position]
        try:
            return op(s)
        except pysoem.SdoError as exc:
            raise SdoAbort(exc.abort_code, f"SDO abort 0x{exc.abort_code:08X} at 0x{exc.index:04X}:"
                                           f"{exc.subindex} on slave {position}: {exc.desc}") from None
        except (pysoem.MailboxError, pysoem.PacketError, pysoem.WkcError) as exc:
            raise BusError(Alarm(A.DISCONNECTED, f"mailbox error on slave {position}: {exc}")) from None

    def close(self) -> None:
        m = self.master
        self.master = None
        self._states = ["INIT"] * len(self.infos)
        if m is None:
            return
        try:
            m.state = pysoem.INIT_STATE
            m.write_state()
        except Exception:  # closing must never turn into a second fault
            pass
        m.close()


def _error_code(s) -> int:
    """The drive's 0x603F over SDO, read once when its fault bit rises."""
    try:
        return int.from_bytes(s.sdo_read(0x603F, 0, 2), "little") or 0xFF00
    except Exception:  # unreadable: still a fault; 0xFF00 is CiA 402's "device specific"
        return 0xFF00
