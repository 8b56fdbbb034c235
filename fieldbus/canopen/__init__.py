"""CANopen master for CiA 402 drives, built on python-canopen and python-can.

`CanopenLink` implements `fieldbus.link.BusLink`: NMT, SDO configuration of the PDOs, a SYNC
per bench cycle with RPDOs out and TPDOs in, heartbeat consumer and EMCY → Delta alarms.
"""

from fieldbus.canopen.pycan import load as _load_can

_load_can()  # before python-canopen or anything else imports python-can (its MF4 support's asammdf: B50)

from fieldbus.canopen.budget import BusLoad, BusBudgetError, bus_load
from fieldbus.canopen.objects import ASDA_B3_EDS, pdo_frames

__all__ = ["ASDA_B3_EDS", "BusBudgetError", "BusLoad", "bus_load", "pdo_frames"]
