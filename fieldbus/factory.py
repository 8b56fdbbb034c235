"""Bus names → links: `sim`, `ethercat:IFACE`, `canopen:INTERFACE[:CHANNEL]`."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class BusSpec:
    kind: str  # "sim", "ethercat", "canopen"
    interface: str = ""
    channel: str = ""

    def __str__(self) -> str:
        return ":".join(p for p in (self.kind, self.interface, self.channel) if p)


IFNAMSIZ = 16  # Linux <net/if.h>; SOEM copies the name into fixed buffers of this size


def check_ifname(name: str) -> None:
    """Refuse a network interface name Linux could never have, before it reaches pysoem: SOEM copies it
    unchecked, and a 56+ character name corrupts the heap (decisions inputs.md I5)."""
    if len(name.encode()) > IFNAMSIZ - 1:
        raise ValueError(f"EtherCAT interface name {name[:40]!r}{'...' if len(name) > 40 else ''} is "
                         f"{len(name.encode())} bytes; a Linux interface name has at most {IFNAMSIZ - 1}")
    if name in (".", "..") or any(c in name for c in "/:") or any(c.isspace() or not c.isprintable() for c in name):
        raise ValueError(f"EtherCAT interface name {name!r} is not a valid interface name "
                         "(no '/', ':', spaces or control characters)")


def parse_bus(spec: str) -> BusSpec:
    parts = spec.split(":", 2)
    kind = parts[0].strip().lower()
    if kind == "sim":
        if len(parts) > 1:
            raise ValueError("bus 'sim' takes no interface")
        return BusSpec("sim")
    if kind == "ethercat":
        if len(parts) != 2 or not parts[1]:
            raise ValueError("EtherCAT bus needs an interface: ethercat:IFACE")
        check_ifname(parts[1])
        return BusSpec("ethercat", parts[1])
    if kind == "canopen":
        if len(parts) < 2 or not parts[1]:
            raise ValueError("CANopen bus needs an interface: canopen:virtual | canopen:socketcan:can0 | "
                             "canopen:udp_multicast:239.74.163.2")
        return BusSpec("canopen", parts[1], parts[2] if len(parts) > 2 else "")
    raise ValueError(f"unknown bus {spec!r}: use sim, ethercat:IFACE or canopen:INTERFACE[:CHANNEL]")
