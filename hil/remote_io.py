"""Wire a bench's remote I/O stations ([[io]]) to the MLC, whatever the bus: each station gets an
`IoPort` on the bench's link and its X/Y range (mlc/remote_io.py).

  sim              an in-process `virtual_bus.io.IoModule` per station (`link.io_devices`)
  ethercat:IFACE   the k-th I/O slave on the line (R1-EC class; `hil sim ethercat --bench` makes them)
  canopen:…        the CiA 401 station at `canopen_node` (on `canopen:virtual` simulated in-process:
                   `link.io_devices` holds the `virtual_bus.canopen.dio.Cia401Slave`s)
"""

from __future__ import annotations

from typing import Any

from hil.bench import Bench


def io_ports(bench: Bench, link: Any) -> list[Any]:
    from fieldbus.canopen.link import CanopenLink
    from fieldbus.ethercat.link import EthercatLink

    if isinstance(link, EthercatLink):
        from fieldbus.ethercat.io import EthercatIoPort

        return [EthercatIoPort(link, k, st.map.name, st.map.inputs, st.map.outputs, st.modules)
                for k, st in enumerate(bench.io)]
    if isinstance(link, CanopenLink):
        from fieldbus.canopen.io import CanopenIoPort

        return [CanopenIoPort(link, k, st.map.name) for k, st in enumerate(bench.io)]
    devices = sim_modules(bench, link)
    return list(devices)


def sim_modules(bench: Bench, link: Any) -> list[Any]:
    """The in-process modules of a SimLink bench, made once and kept on the link."""
    from virtual_bus.io import IoModule

    if not getattr(link, "io_devices", None):
        link.io_devices = [IoModule(name=st.map.name, node=st.map.node) for st in bench.io]
    return link.io_devices


class IoNotSimulated(LookupError):
    """The [[io]] station behind a point lives on a real bus, not in this process."""


def io_terminal(bench: Bench, link: Any, kind: str, n: int) -> tuple[Any, int] | None:
    """(simulated station, point) behind X<n> / Y<n> by the bench's [[io]] mapping; None when no station
    maps the point; IoNotSimulated when its station is not simulated in this process."""
    for i, st in enumerate(bench.io):
        m = st.map
        first, count = (m.x, m.inputs) if kind == "X" else (m.y, m.outputs)
        if first <= n < first + count:
            devices = getattr(link, "io_devices", None) or []
            if i >= len(devices):
                raise IoNotSimulated(f"station {m.name} is not simulated in this process (bus {bench.bus}); "
                                     "drive its terminals on the slave side")
            return devices[i], n - first
    return None


def attach_remote_io(bench: Bench, mlc: Any, link: Any) -> None:
    """Give the MLC the bench's stations (a no-op without [[io]] or for the foundation's BasicMlc)."""
    if not bench.io or not callable(getattr(mlc, "attach_io", None)):
        return
    mlc.attach_io(io_ports(bench, link), [st.map for st in bench.io])
