"""EtherCAT bus faults → NC5 alarms (App. A, kernel group 0x14xx, axis 0x0601).

Which step of the bring-up failed decides the code; see docs/decisions/ethercat.md.
"""

from __future__ import annotations

import pysoem

from nc.alarms import Alarm

INIT_ERROR = 0x1429  # EtherCAT communication initialization error (interface cannot be opened)
NO_SLAVES = 0x142B  # EtherCAT slave devices not found
SLAVE_MISMATCH = 0x1416  # the slave address (identity/position) does not match the configuration
PDO_MISMATCH = 0x141E  # system PDO mapping mismatch
CYCLE_UNSUPPORTED = 0x141F  # the servo does not support the interpolation (cycle) time
ESTABLISH_FAILED = 0x1420  # EtherCAT communication establish failed (INIT/PRE-OP)
OP_TRIGGER_FAILED = 0x1427  # failed to trigger OP mode (SAFE-OP not reached)
OP_SWITCH_FAILED = 0x1428  # failed to switch to OP mode
DISCONNECTED = 0x0601  # communication disconnected after established
EIO_MISMATCH = 0x142E  # the EIO station on the line does not match the configured one (points)
EIO_NOT_FOUND = 0x142F  # the configured EIO station's port (k-th I/O slave) is not on the line
EIO_FAILED = 0x1426  # the system remote module (EIO) failed: only I/O slaves left OP (mlc/remote_io.py)
DC_DRIFT = CYCLE_UNSUPPORTED  # a slave's DC clock drifted past the limit: it cannot hold the sync cycle (E8)

# AL status codes that name a mapping problem, and those that name a cycle/sync problem
AL_MAPPING = {0x0017, 0x001D, 0x001E, 0x0024, 0x0025}
AL_CYCLE = {0x001A, 0x0028, 0x0029, 0x002C, 0x0030, 0x0032, 0x0035, 0x0036, 0x0037}


def al_text(code: int) -> str:
    try:
        return f"AL status 0x{code:04X} ({pysoem.al_status_code_to_string(code)})"
    except Exception:  # an unknown code must still produce the alarm
        return f"AL status 0x{code:04X}"


def bringup_alarm(target: str, code: int, who: str) -> Alarm:
    """The alarm for a slave `who` that refused `target` (PRE-OP / SAFE-OP / OP) with AL `code`."""
    if code in AL_MAPPING:
        return Alarm(PDO_MISMATCH, f"{who} refused {target}: {al_text(code)}")
    if code in AL_CYCLE:
        return Alarm(CYCLE_UNSUPPORTED, f"{who} refused {target}: {al_text(code)}")
    number = {"PRE-OP": ESTABLISH_FAILED, "SAFE-OP": OP_TRIGGER_FAILED, "OP": OP_SWITCH_FAILED}[target]
    return Alarm(number, f"{who} did not reach {target}: {al_text(code)}")
