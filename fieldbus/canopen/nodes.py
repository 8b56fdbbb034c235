"""The CANopen master's view of its nodes: configuration, per-node cycle state, drive fault episodes."""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import canopen

from fieldbus.canopen.emcy import Emcy, emcy_alarm
from fieldbus.canopen.objects import ASDA_B3_EDS
from fieldbus.cia402 import SW_FAULT
from fieldbus.pdo import PdoLayout, TxPdo
from nc.alarms import Alarm

log = logging.getLogger("fieldbus.canopen")


@dataclass
class NodeConfig:
    node_id: int
    name: str  # axis or spindle name
    layout: PdoLayout
    eds: str | Path = ASDA_B3_EDS  # EDS or DCF of the device


@dataclass
class IoNodeConfig:
    """A CiA 401 remote I/O station (mlc/remote_io.py): `inputs` / `outputs` digital points, inputs sent
    on every SYNC (`tpdo="sync"`) or on change of state (`"change"`)."""

    node_id: int
    name: str
    inputs: int = 16
    outputs: int = 16
    tpdo: str = "sync"
    eds: str | Path = ""  # default: fieldbus/canopen/eds/delta_dio_401.eds


@dataclass
class IoNode:
    cfg: IoNodeConfig
    remote: canopen.RemoteNode
    inputs: int = 0  # from the last TPDO
    outputs: int = 0  # what the next RPDO carries
    received: bool = False
    nmt_state: int | None = None
    last_heartbeat: float = 0.0
    lost: bool = False
    tpdo_misses: int = 0


@dataclass
class Node:
    cfg: NodeConfig
    remote: canopen.RemoteNode
    rx_frames: list[PdoLayout]
    tx_frames: list[PdoLayout]
    tx: TxPdo = field(default_factory=TxPdo)
    tx_cobs: dict[int, PdoLayout] = field(default_factory=dict)
    received: set[int] = field(default_factory=set)
    nmt_state: int | None = None
    last_heartbeat: float = 0.0
    lost: bool = False
    tpdo_misses: int = 0
    fault: "FaultEpisode | None" = None  # the fault being reported, until the drive is reset


@dataclass
class FaultEpisode:
    """One drive fault from its first sign (EMCY or statusword fault bit) to its reset (the fault bit
    falling): the NC raises one alarm for it. `reported_by` says which path raised it: "EMCY" (the
    link, with the EMCY's code) or "statusword" (the CiA 402 master in the runner, with 0x603F)."""

    reported_by: str
    emcys: list[Emcy] = field(default_factory=list)  # every EMCY of the episode, the first one raised
    fault_bit_seen: bool = False


def interpolation_period(cycle: float) -> tuple[int, int]:
    """0x60C2: the cycle as value (sub 1, 1-255) × 10^index s (sub 2)."""
    for index in range(-3, -7, -1):
        value = cycle / 10.0 ** index
        if abs(value - round(value)) < 1e-6 and 1 <= round(value) <= 255:
            return int(round(value)), index
    raise ValueError(f"cycle {cycle * 1000:g} ms cannot be written as 0x60C2 (1-255 × 10^-3..-6 s)")


def fault_episodes(nodes: list[Node], emcys: list[tuple[Node, Emcy]], faults: list[tuple[str, FaultEpisode]],
                   label: Callable[[Node], str]) -> Alarm | None:
    """One alarm per drive fault, whichever of its two signs comes first. An EMCY opens an episode
    and is the alarm (it carries the drive's error code and Delta alarm number); a statusword fault
    bit without an EMCY before it opens one that the CiA 402 master raises from 0x603F. Later EMCYs
    of the same episode are kept in `faults` but raise nothing; the episode ends when the fault
    bit falls (fault reset), or at EMCY 0x0000 (error reset) if the fault bit never rose. Each new
    episode is appended to `faults` with its drive's name."""
    alarm = None
    for n, emcy in emcys:
        if emcy.code == 0x0000:
            if n.fault is not None and not n.fault.fault_bit_seen:
                n.fault = None
            continue
        if n.fault is not None:
            n.fault.emcys.append(emcy)
            log.info("EMCY 0x%04X from %s belongs to the fault already reported by %s", emcy.code,
                     label(n), n.fault.reported_by)
            continue
        n.fault = FaultEpisode("EMCY", [emcy])
        faults.append((n.cfg.name, n.fault))
        alarm = alarm or emcy_alarm(emcy, n.cfg.node_id, n.cfg.name)
    for n in nodes:
        faulted = bool(n.tx.statusword & SW_FAULT) and not n.lost
        if faulted and n.fault is None:
            n.fault = FaultEpisode("statusword")
            faults.append((n.cfg.name, n.fault))
        if n.fault is not None:
            if faulted:
                n.fault.fault_bit_seen = True
            elif n.fault.fault_bit_seen:
                n.fault = None  # reset: the next fault is a new episode
    return alarm
