"""Guard for python-can `udp_multicast`: only inside a private network namespace.

In the host's (root) namespace multicast frames would leave through the default route onto the
real network, so the project runs `udp_multicast` only inside a namespace whose `lo` carries
224.0.0.0/4 (see docs/guide/canopen.md).
"""

from __future__ import annotations

import os
import socket


def exposed_interfaces() -> list[str]:
    """Network interfaces of this process's namespace other than loopback (where multicast could leave)."""
    return [name for _, name in socket.if_nameindex() if name != "lo"]


def check_multicast_allowed(interface: str) -> None:
    """Refuse udp_multicast where frames could reach a real network; a bench may override knowingly."""
    if interface == "udp_multicast" and exposed_interfaces() and not os.environ.get("DELTAHIL_ALLOW_MULTICAST"):
        raise ValueError(f"udp_multicast runs only inside a loopback-only network namespace, this one has "
                         f"{', '.join(exposed_interfaces())} (ip netns add NAME; "
                         "ip -n NAME link set lo up; ip -n NAME link set lo multicast on; "
                         "ip -n NAME route add 224.0.0.0/4 dev lo; ip netns exec NAME hil ...)")
