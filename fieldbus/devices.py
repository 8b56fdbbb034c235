"""The real Delta EtherCAT servo drives a bench can name, as their published data describes them:
identity, predefined PDO sets, default encoder resolution and object units.

Sources (docs/decisions/ethercat.md E11–E14): the devices' ESI data as ingested by
linuxcnc-ethercat/esi-data ("ASDA-A3-E CoE Drive" r3, "ASDA-B3-E CoE Drive" r3, "ASDA-A2-E CoE
Drive" r516), linuxcnc-ethercat `lcec_deasda.c` (0.1 rpm velocity; 1 280 000 counts/rev on the A2-E, 16 777 216 on the
A3-E/B3-E "x3 series"; its 0x1602/0x1A02 remap) and Delta's encoder data (A3/B3: 24 bit).
The master uses it to name and check slaves; the virtual slaves' ESI-like file holds the same.
"""

from __future__ import annotations

from dataclasses import dataclass

from fieldbus.units import DELTA_UNITS, DriveUnits

Entry = tuple[int, int, int]  # (index, subindex, bits)

_CW, _TPOS, _TVEL, _TTOR, _MODE, _TPF = (0x6040, 0, 16), (0x607A, 0, 32), (0x60FF, 0, 32), (0x6071, 0, 16), \
    (0x6060, 0, 8), (0x60B8, 0, 16)
_SW, _POS, _VEL, _TOR, _MDISP, _TPS, _TPP, _DI, _ERR = (0x6041, 0, 16), (0x6064, 0, 32), (0x606C, 0, 32), \
    (0x6077, 0, 16), (0x6061, 0, 8), (0x60B9, 0, 16), (0x60BA, 0, 32), (0x60FD, 0, 32), (0x603F, 0, 16)
_PTL, _NTL = (0x60E0, 0, 16), (0x60E1, 0, 16)

_A3_RX: dict[int, tuple[Entry, ...]] = {
    0x1600: (_CW, _TPOS, _TVEL, _TPF),
    0x1601: (_CW, _TPOS, _TVEL, _TTOR, _TPF),
    0x1602: (_CW, _TPOS, _TVEL, _TTOR, _MODE, _TPF),
    0x1603: (_CW, _TPOS, _TVEL, _TTOR, _MODE, _PTL, _NTL, _TPF),
}
_A3_TX: dict[int, tuple[Entry, ...]] = {
    0x1A00: (_SW, _POS, _VEL, _TPS, _TPP, _DI),
    0x1A01: (_SW, _POS, _VEL, _TOR, _TPS, _TPP, _DI),
    0x1A02: (_SW, _POS, _VEL, _TOR, _MDISP, _TPS, _TPP, _DI),
    0x1A03: (_SW, _POS, _TOR, _MDISP, _TPS, _TPP, _ERR, _DI),
}
_A2_RX: dict[int, tuple[Entry, ...]] = {
    0x1600: (_CW, _TPOS, _TVEL, _TTOR, _MODE), 0x1601: (_CW, _TPOS), 0x1602: (_CW, _TVEL), 0x1603: (_CW, _TTOR),
}
_A2_TX: dict[int, tuple[Entry, ...]] = {
    0x1A00: (_SW, _POS, _VEL, _TOR, _MDISP), 0x1A01: (_SW, _POS), 0x1A02: (_SW, _POS, _VEL), 0x1A03: (_SW, _POS, _TOR),
}
# Objects mappable beyond the predefined sets: 0x60FE:1 (digital outputs) and 0x2511 (auxiliary
# encoder, which lcec_deasda maps into 0x1A02); on the A2-E also the touch probe, digital inputs and
# error code its object list has (assumed mappable, decisions E12).
_EXTRA_RX: tuple[Entry, ...] = ((0x60FE, 1, 32),)
_EXTRA_TX: tuple[Entry, ...] = ((0x2511, 0, 32),)
_A2_EXTRA_RX: tuple[Entry, ...] = _EXTRA_RX + (_TPF,)
_A2_EXTRA_TX: tuple[Entry, ...] = _EXTRA_TX + (_TPS, _TPP, _DI, _ERR)


@dataclass(frozen=True)
class DeviceModel:
    key: str  # what a bench names: asda-a3-e, asda-b3-e, asda-a2-e
    type_name: str  # ESI <Type>
    vendor_id: int
    product_code: int
    revision: int
    counts_per_rev: int  # 0x6064 counts per motor revolution at the drive's defaults
    rx_sets: dict[int, tuple[Entry, ...]]
    tx_sets: dict[int, tuple[Entry, ...]]
    default_rx: int  # 0x1C12:1 at power-on
    default_tx: int  # 0x1C13:1 at power-on
    extra_rx: tuple[Entry, ...] = _EXTRA_RX
    extra_tx: tuple[Entry, ...] = _EXTRA_TX
    units: DriveUnits = DELTA_UNITS
    max_entries: int = 8  # entries per PDO (the largest predefined set)
    modes: tuple[int, ...] = (1, 3, 6, 8, 9, 10)  # 0x6060 values the virtual drive runs (0x6502 = 0x3A5 advertises them)
    sync0_min_ns: int = 125_000

    def mappable(self, direction: str) -> set[tuple[int, int]]:
        """(index, subindex) a PDO of `direction` ("R" / "T") may map."""
        sets, extra = (self.rx_sets, self.extra_rx) if direction == "R" else (self.tx_sets, self.extra_tx)
        return {(i, s) for entries in sets.values() for i, s, _ in entries} | {(i, s) for i, s, _ in extra}


DELTA = 0x000001DD
MODELS: dict[str, DeviceModel] = {m.key: m for m in (
    DeviceModel("asda-a3-e", "ASDA-A3-E CoE Drive", DELTA, 0x00006010, 0x00030000, 16_777_216, _A3_RX, _A3_TX,
                0x1600, 0x1A01),
    DeviceModel("asda-b3-e", "ASDA-B3-E CoE Drive", DELTA, 0x00006080, 0x00030000, 16_777_216, _A3_RX, _A3_TX,
                0x1600, 0x1A01),
    DeviceModel("asda-a2-e", "ASDA-A2-E CoE Drive", DELTA, 0x10305070, 0x02040608, 1_280_000, _A2_RX, _A2_TX,
                0x1600, 0x1A00, _A2_EXTRA_RX, _A2_EXTRA_TX),
)}
DEFAULT_MODEL = "asda-a3-e"


def model_by_identity(vendor_id: int, product_code: int) -> DeviceModel | None:
    return next((m for m in MODELS.values() if (m.vendor_id, m.product_code) == (vendor_id, product_code)), None)
