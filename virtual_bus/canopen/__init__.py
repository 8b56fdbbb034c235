"""Simulated CANopen CiA 402 servo drives (python-canopen LocalNode + our drive model)."""

import fieldbus.canopen  # noqa: F401  (python-can without its MF4 support's asammdf, fieldbus/canopen/pycan.py)
from virtual_bus.canopen.node import Cia402Slave
from virtual_bus.canopen.nodes import SlaveBus, attach_lockstep, serve

__all__ = ["Cia402Slave", "SlaveBus", "attach_lockstep", "serve"]
