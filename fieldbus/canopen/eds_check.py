"""Is a device file (EDS/DCF) usable for what the master does with the node? Checked when the bench
file is read, so a wrong path or a file lacking an object is a per-field error (exit 2) before any
frame is sent, not a KeyError deep inside python-canopen during `open()`."""

from __future__ import annotations

import logging
from pathlib import Path

import canopen

from fieldbus.canopen.objects import MAX_PDOS
from fieldbus.pdo import PdoLayout

# Objects the master reads or writes on every node: device type, heartbeat producer, identity.
_COMMON = [(0x1000, 0), (0x1017, 0), (0x1018, 1), (0x1018, 2)]


def drive_objects(layout: PdoLayout) -> list[tuple[int, int]]:
    """What `CanopenLink` touches on a CiA 402 drive: the PDO records it rewrites (all MAX_PDOS of
    each kind), 0x60C2 and every object of the layout's PDO mapping."""
    pdo = [(base + k, 1) for base in (0x1400, 0x1600, 0x1800, 0x1A00) for k in range(MAX_PDOS)]
    mapped = [(e.index, e.subindex) for e in layout.rx + layout.tx]
    return _COMMON + [(0x60C2, 1), (0x60C2, 2)] + pdo + mapped


def io_objects(inputs: int, outputs: int) -> list[tuple[int, int]]:
    """What it touches on a CiA 401 station: PDO1 of each kind and one 0x6000/0x6200 byte per 8 points."""
    pdo = [(0x1400, 1), (0x1600, 1), (0x1800, 1), (0x1A00, 1)]
    ins = [(0x6000, s) for s in range(1, (inputs + 7) // 8 + 1)]
    outs = [(0x6200, s) for s in range(1, (outputs + 7) // 8 + 1)]
    return _COMMON + pdo + ins + outs


def eds_problem(path: Path, needed: list[tuple[int, int]]) -> str | None:
    """Why `path` cannot serve as this node's device file, or None when it can."""
    if not path.is_file():
        return f"EDS file {path} not found" if not path.exists() else f"{path} is not a file"
    eds_log = logging.getLogger("canopen.objectdictionary.eds")  # its warnings would interleave with ours
    was, eds_log.disabled = eds_log.disabled, True
    try:
        od = canopen.import_od(str(path), 1)
    except Exception as exc:  # configparser, ValueError, KeyError …: python-canopen has no own error type
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return f"EDS file {path} cannot be parsed: {first}"
    finally:
        eds_log.disabled = was
    missing = [(i, s) for i, s in needed if not _has(od, i, s)]
    if missing:
        names = ", ".join(f"0x{i:04X}" + (f":{s}" if s else "") for i, s in missing[:6])
        more = f" and {len(missing) - 6} more" if len(missing) > 6 else ""
        return f"EDS file {path} lacks object{'s' if len(missing) > 1 else ''} {names}{more} the master uses"
    return None


def _has(od: canopen.ObjectDictionary, index: int, sub: int) -> bool:
    if index not in od:
        return False
    obj = od[index]
    if isinstance(obj, canopen.objectdictionary.ODVariable):
        return sub == 0
    return sub in obj
