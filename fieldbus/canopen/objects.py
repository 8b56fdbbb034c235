"""How our PDO layouts travel on CAN: split into 8-byte frames, and where the device files live.

A CAN frame carries at most 8 data bytes, so a `PdoLayout` (which EtherCAT sends as one block)
is split into several RPDOs / TPDOs. First-fit decreasing keeps the frame count minimal
(18 bytes of CSP feedback → 3 TPDOs, 29 bytes of CSP+CSV feedback → 4), which is what the bus
budget counts.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fieldbus.pdo import PdoEntry, PdoLayout

MAX_PDO_BYTES = 8
MAX_PDOS = 4  # 0x1400-0x1403 / 0x1800-0x1803 in the shipped EDS (CiA 301 pre-defined connection set)

# The device description of a Delta ASDA-B3-class CANopen servo (CiA 402). Masters read it to
# build the object dictionary; the simulated slaves are built from the same file.
ASDA_B3_EDS: Path = Path(str(resources.files("fieldbus.canopen") / "eds" / "delta_asda_b3.eds"))
# A CiA 401 remote digital I/O station (up to 64 in / 64 out), master and simulated station alike.
DIO_EDS: Path = Path(str(resources.files("fieldbus.canopen") / "eds" / "delta_dio_401.eds"))

# CiA 402 objects the layouts use, with the names python-canopen gives them from the EDS.
OBJECT_ATTRS: dict[tuple[int, int], str] = {
    (0x6040, 0): "controlword", (0x607A, 0): "target_position", (0x6060, 0): "mode",
    (0x60FF, 0): "target_velocity", (0x60B8, 0): "touch_probe_function", (0x60FE, 1): "digital_outputs",
    (0x6071, 0): "target_torque",
    (0x6041, 0): "statusword", (0x6064, 0): "position_actual", (0x606C, 0): "velocity_actual",
    (0x6077, 0): "torque_actual", (0x60F4, 0): "following_error", (0x603F, 0): "error_code",
    (0x6061, 0): "mode_display", (0x60B9, 0): "touch_probe_status", (0x60BA, 0): "touch_probe_pos1",
    (0x60FD, 0): "digital_inputs",
}


def pdo_frames(entries: tuple[PdoEntry, ...], max_bytes: int = MAX_PDO_BYTES) -> list[tuple[PdoEntry, ...]]:
    """Pack entries into as few ≤ 8-byte frames as first-fit decreasing finds (stable for ties)."""
    frames: list[list[PdoEntry]] = []
    sizes: list[int] = []
    for e in sorted(entries, key=lambda e: -e.bits):
        n = e.bits // 8
        for k, used in enumerate(sizes):
            if used + n <= max_bytes:
                frames[k].append(e)
                sizes[k] += n
                break
        else:
            frames.append([e])
            sizes.append(n)
    return [tuple(f) for f in frames]


def frame_layouts(layout: PdoLayout) -> tuple[list[PdoLayout], list[PdoLayout]]:
    """One small `PdoLayout` per RPDO and per TPDO frame, so packing reuses `fieldbus.pdo`."""
    rx = [PdoLayout(f"{layout.name}-rpdo{k + 1}", f, ()) for k, f in enumerate(pdo_frames(layout.rx))]
    tx = [PdoLayout(f"{layout.name}-tpdo{k + 1}", (), f) for k, f in enumerate(pdo_frames(layout.tx))]
    if len(rx) > MAX_PDOS or len(tx) > MAX_PDOS:
        raise ValueError(f"layout {layout.name} needs {len(rx)} RPDOs and {len(tx)} TPDOs; a node has {MAX_PDOS}")
    return rx, tx


def map_entry(e: PdoEntry) -> int:
    """The 32-bit value of a 0x16xx/0x1Axx mapping entry: index, subindex, length in bits."""
    return e.index << 16 | e.subindex << 8 | e.bits
