"""`hil scan` on a CANopen bus: which nodes answer, and who they say they are (CiA 301 0x1000,
0x1018, 0x1008), with the NMT state their heartbeat reports."""

from __future__ import annotations

import time

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from fieldbus.canopen.link import ALARM_ESTABLISH, connect_args
from fieldbus.link import BusError, SlaveInfo, drive_state_text
from nc.alarms import Alarm


def scan(interface: str, channel: str, bitrate: int, wait: float = 0.5) -> list[SlaveInfo]:
    """Every node on the bus, in node-ID order: an SDO upload of 0x1000 to all 127 IDs (python-canopen's
    scanner), then identity and name over SDO; the state from a heartbeat within `wait` (else the
    node answered SDO, so it is PRE-OPERATIONAL or OPERATIONAL)."""
    net = canopen.Network()
    try:
        net.connect(**connect_args(interface, channel, bitrate))
    except (can.CanError, OSError, ValueError, ImportError) as exc:
        raise BusError(Alarm(ALARM_ESTABLISH, f"cannot open CAN interface {interface}"
                                              f"{':' + channel if channel else ''}: {exc}")) from None
    try:
        net.scanner.reset()
        net.scanner.search()
        time.sleep(wait)
        out = []
        for nid in sorted(net.scanner.nodes):
            node = net.add_node(nid, canopen.ObjectDictionary())
            node.sdo.RESPONSE_TIMEOUT = 0.5
            out.append(_identify(node, nid, wait))
        return out
    finally:
        net.disconnect()


def _identify(node: canopen.RemoteNode, nid: int, wait: float) -> SlaveInfo:
    try:
        state = node.nmt.wait_for_heartbeat(wait)  # if the node produces one (0x1017)
    except canopen.nmt.NmtError:
        state = "PRE-OP/OP"  # found, so it answered SDO: it is not STOPPED
    if state == "STOPPED":  # no SDO in STOPPED (CiA 301): nothing to ask it
        return SlaveInfo(nid, f"node {nid} (STOPPED, as a master's NMT stop leaves it: no SDO, so no identity, "
                              "until NMT pre-operational)", "?", 0, 0, "STOPPED")

    def u32(index: int, sub: int) -> int:
        try:
            return int.from_bytes(node.sdo.upload(index, sub)[:4], "little")
        except (SdoAbortedError, SdoCommunicationError):
            return 0

    device_type = u32(0x1000, 0)
    try:
        name = node.sdo.upload(0x1008, 0).decode("latin-1").strip("\x00 ")
    except (SdoAbortedError, SdoCommunicationError):
        name = ""
    profile = device_type & 0xFFFF
    kind = "drive" if profile == 402 else "io" if profile == 401 else f"cia{profile}"
    drive = ""
    if kind == "drive":
        try:
            drive = drive_state_text(int.from_bytes(node.sdo.upload(0x6041, 0)[:2], "little"),
                                     int.from_bytes(node.sdo.upload(0x603F, 0)[:2], "little"))
        except (SdoAbortedError, SdoCommunicationError):
            pass  # no such object: the scan shows what it has
    return SlaveInfo(nid, name or f"node {nid}", kind, u32(0x1018, 1), u32(0x1018, 2), state, drive=drive)
