"""Process data: the per-cycle images exchanged with a CiA 402 drive, and PDO layouts that say
which objects travel and how they pack on the wire.

Values are in the drive's units (`fieldbus.units.DriveUnits`): positions in counts, velocities in
0.1 rpm of the motor on Delta drives, torque in 0.1 % of rated.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from operator import attrgetter


@dataclass(slots=True)
class RxPdo:
    """Master → drive, one per drive per cycle."""

    controlword: int = 0  # 0x6040
    target_position: int = 0  # 0x607A, counts
    mode: int = 8  # 0x6060 (8 = CSP, 9 = CSV, 6 = homing)
    target_velocity: int = 0  # 0x60FF, drive units (Delta: 0.1 rpm)
    target_torque: int = 0  # 0x6071, 0.1 % of rated (CST; in Delta's 0x1602 set)
    touch_probe_function: int = 0  # 0x60B8
    digital_outputs: int = 0  # 0x60FE:1


@dataclass(slots=True)
class TxPdo:
    """Drive → master, one per drive per cycle."""

    statusword: int = 0  # 0x6041
    position_actual: int = 0  # 0x6064, counts
    velocity_actual: int = 0  # 0x606C, drive units (Delta: 0.1 rpm)
    torque_actual: int = 0  # 0x6077, 0.1 % of rated
    following_error: int = 0  # 0x60F4, counts (derived by the master where no PDO carries it)
    error_code: int = 0  # 0x603F
    mode_display: int = 0  # 0x6061
    touch_probe_status: int = 0  # 0x60B9
    touch_probe_pos1: int = 0  # 0x60BA, counts
    digital_inputs: int = 0  # 0x60FD (bit0 negative limit, bit1 positive limit, bit2 home)


_RX_FIELDS = attrgetter(*(f.name for f in fields(RxPdo)))
_TX_FIELDS = attrgetter(*(f.name for f in fields(TxPdo)))


def copy_rx(rx: RxPdo) -> RxPdo:
    """`copy.copy(rx)` without the copy module's reduce protocol (a cycle's copy of a latched image)."""
    return RxPdo(*_RX_FIELDS(rx))


def copy_tx(tx: TxPdo) -> TxPdo:
    """`copy.copy(tx)`, as `copy_rx`."""
    return TxPdo(*_TX_FIELDS(tx))


@dataclass(frozen=True, slots=True)
class PdoEntry:
    index: int
    subindex: int
    bits: int
    attr: str  # RxPdo / TxPdo field it carries
    signed: bool = False

    @property
    def struct_code(self) -> str:
        codes = {8: "b", 16: "h", 32: "i"}
        c = codes[self.bits]
        return c if self.signed else c.upper()


@dataclass(frozen=True)
class PdoLayout:
    """An ordered RxPDO and TxPDO mapping, packed little-endian as EtherCAT and CANopen do.
    On EtherCAT it is written into the PDO objects `rx_index` / `tx_index` and assigned alone."""

    name: str
    rx: tuple[PdoEntry, ...]
    tx: tuple[PdoEntry, ...]
    rx_index: int = 0x1600
    tx_index: int = 0x1A00
    rx_struct: struct.Struct = field(init=False, repr=False, compare=False)
    tx_struct: struct.Struct = field(init=False, repr=False, compare=False)
    _indices: frozenset[int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "rx_struct", struct.Struct("<" + "".join(e.struct_code for e in self.rx)))
        object.__setattr__(self, "tx_struct", struct.Struct("<" + "".join(e.struct_code for e in self.tx)))
        object.__setattr__(self, "_indices", frozenset(e.index for e in self.rx + self.tx))
        for name, fn in _codecs(self.rx, self.rx_struct, "rx").items() | _codecs(self.tx, self.tx_struct, "tx").items():
            object.__setattr__(self, name, fn)

    def carries(self, index: int) -> bool:
        return index in self._indices

    @property
    def rx_bytes(self) -> int:
        return self.rx_struct.size

    @property
    def tx_bytes(self) -> int:
        return self.tx_struct.size

    # pack_rx / unpack_rx / pack_tx / unpack_tx are compiled per layout in __post_init__ (`_codecs`).
    pack_rx: Callable[[RxPdo], bytes] = field(init=False, repr=False, compare=False)
    unpack_rx: Callable[..., RxPdo] = field(init=False, repr=False, compare=False)
    pack_tx: Callable[[TxPdo], bytes] = field(init=False, repr=False, compare=False)
    unpack_tx: Callable[..., TxPdo] = field(init=False, repr=False, compare=False)


def _codecs(entries: tuple[PdoEntry, ...], st: struct.Struct, side: str) -> dict[str, Callable]:
    """The layout's pack and unpack functions for one direction, generated once (issue 17): one
    struct call and one tuple assignment per image instead of a getattr, `_fit` and setattr per
    entry. Packing the value masked to its width with unsigned codes gives the bytes `_fit` then
    the signed code give. Unpacking reads the first `st.size` bytes, as slicing them did."""
    cls = "RxPdo" if side == "rx" else "TxPdo"
    attrs = [e.attr for e in entries]
    assert all(a.isidentifier() for a in attrs)
    masked = ", ".join(f"int(pdo.{a}) & {(1 << e.bits) - 1:#x}" for a, e in zip(attrs, entries))
    targets = "".join(f"pdo.{a}, " for a in attrs)
    src = (f"def pack_{side}(pdo):\n    return _pack({masked})\n"
           f"def unpack_{side}(data, into=None):\n    pdo = into or {cls}()\n"
           f"    {targets + ' = ' if attrs else ''}_unpack(data)\n    return pdo\n")
    unsigned = struct.Struct("<" + "".join(e.struct_code.upper() for e in entries))
    scope: dict = {"_pack": unsigned.pack, "_unpack": st.unpack_from, cls: RxPdo if side == "rx" else TxPdo}
    exec(compile(src, f"<pdo codec {side}>", "exec"), scope)
    return {f"pack_{side}": scope[f"pack_{side}"], f"unpack_{side}": scope[f"unpack_{side}"]}


def _fit(value: int, e: PdoEntry) -> int:
    """Wrap to the entry's width the way the drive's registers would."""
    v = int(value) & ((1 << e.bits) - 1)
    if e.signed and v >= 1 << (e.bits - 1):
        v -= 1 << e.bits
    return v


_RX_CSP = (
    PdoEntry(0x6040, 0, 16, "controlword"),
    PdoEntry(0x607A, 0, 32, "target_position", True),
    PdoEntry(0x6060, 0, 8, "mode", True),
)
_TX_CSP = (
    PdoEntry(0x6041, 0, 16, "statusword"),
    PdoEntry(0x6064, 0, 32, "position_actual", True),
    PdoEntry(0x606C, 0, 32, "velocity_actual", True),
    PdoEntry(0x6077, 0, 16, "torque_actual", True),
    PdoEntry(0x60F4, 0, 32, "following_error", True),
    PdoEntry(0x603F, 0, 16, "error_code"),
)

# CANopen presets (our EDS, split into 8-byte frames, fieldbus/canopen/objects.py); on EtherCAT a
# bench may still name them (`ethercat_pdo`), but a real Delta drive refuses 0x60F4 in a PDO.
# The preset named in the foundation issue: CSP objects only.
ASDA_CSP = PdoLayout("asda-csp", _RX_CSP, _TX_CSP)

# Spindle / C-axis drives switch between CSV and CSP, so they also carry target velocity,
# the mode display and the touch probe (index latch) objects.
ASDA_CSP_CSV = PdoLayout(
    "asda-csp-csv",
    _RX_CSP + (PdoEntry(0x60FF, 0, 32, "target_velocity", True), PdoEntry(0x60B8, 0, 16, "touch_probe_function")),
    _TX_CSP + (PdoEntry(0x6061, 0, 8, "mode_display", True), PdoEntry(0x60B9, 0, 16, "touch_probe_status"),
               PdoEntry(0x60BA, 0, 32, "touch_probe_pos1", True), PdoEntry(0x60FD, 0, 32, "digital_inputs")),
)

# EtherCAT default: the third Rx/Tx sets of a Delta ASDA-A3-E / B3-E with their ESI contents
# (linuxcnc-ethercat esi-data, "ASDA-A3-E CoE Drive" r3: 0x1602 = 6040 607A 60FF 6071 6060 60B8,
# 0x1A02 = 6041 6064 606C 6077 6061 60B9 60BA 60FD: 8 entries, the sets' limit). Every object the
# bench needs travels except the error code 0x603F (read over SDO when the fault bit rises) and
# the following error 0x60F4 (no Delta set maps it; the master derives it in CSP).
ASDA_E = PdoLayout(
    "asda-e",
    (PdoEntry(0x6040, 0, 16, "controlword"), PdoEntry(0x607A, 0, 32, "target_position", True),
     PdoEntry(0x60FF, 0, 32, "target_velocity", True), PdoEntry(0x6071, 0, 16, "target_torque", True),
     PdoEntry(0x6060, 0, 8, "mode", True), PdoEntry(0x60B8, 0, 16, "touch_probe_function")),
    (PdoEntry(0x6041, 0, 16, "statusword"), PdoEntry(0x6064, 0, 32, "position_actual", True),
     PdoEntry(0x606C, 0, 32, "velocity_actual", True), PdoEntry(0x6077, 0, 16, "torque_actual", True),
     PdoEntry(0x6061, 0, 8, "mode_display", True), PdoEntry(0x60B9, 0, 16, "touch_probe_status"),
     PdoEntry(0x60BA, 0, 32, "touch_probe_pos1", True), PdoEntry(0x60FD, 0, 32, "digital_inputs")),
    rx_index=0x1602, tx_index=0x1A02,
)

LAYOUTS: dict[str, PdoLayout] = {l.name: l for l in (ASDA_E, ASDA_CSP, ASDA_CSP_CSV)}
