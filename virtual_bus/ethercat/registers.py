"""EtherCAT Slave Controller registers (ET1100/ET1200 datasheet section II), datagram commands, AL states
and AL status codes (ETG.1000.6 table 11): the names the virtual ESC and its tests share."""

from __future__ import annotations


# datagram commands
NOP, APRD, APWR, APRW, FPRD, FPWR, FPRW, BRD, BWR, BRW, LRD, LWR, LRW, ARMW, FRMW = range(15)
CMD_NAMES = ["NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD", "BWR", "BRW", "LRD", "LWR", "LRW",
             "ARMW", "FRMW"]

INIT, PREOP, BOOT, SAFEOP, OP = 1, 2, 3, 4, 8
AL_ERROR = 0x10

# AL status codes (ETG.1000.6 table 11)
AL_INVALID_STATE_CHANGE = 0x0011
AL_UNKNOWN_STATE = 0x0012
AL_BOOTSTRAP_NOT_SUPPORTED = 0x0013
AL_INVALID_MAILBOX = 0x0016
AL_INVALID_SM = 0x0017
AL_SYNC_ERROR = 0x001A
AL_SM_WATCHDOG = 0x001B
AL_INVALID_OUTPUT = 0x001D
AL_INVALID_INPUT = 0x001E
AL_INVALID_DC_SYNC = 0x0030
AL_INVALID_SYNC0_CYCLE = 0x0036

R_TYPE, R_STATION, R_ALIAS, R_DL_CONTROL, R_DL_STATUS = 0x0000, 0x0010, 0x0012, 0x0100, 0x0110
R_AL_CONTROL, R_AL_STATUS, R_AL_CODE = 0x0120, 0x0130, 0x0134
R_WD_DIV, R_WD_PD, R_WD_STATUS = 0x0400, 0x0420, 0x0440
R_EEP_CFG, R_EEP_CTRL, R_EEP_ADDR, R_EEP_DATA = 0x0500, 0x0502, 0x0504, 0x0508
R_FMMU, R_SM = 0x0600, 0x0800
R_DC_RECV, R_DC_SYSTIME, R_DC_RECV_PU, R_DC_OFFSET, R_DC_DELAY, R_DC_DIFF = 0x0900, 0x0910, 0x0918, 0x0920, \
    0x0928, 0x092C
R_DC_CYCLIC, R_DC_ACTIVATION, R_DC_SYNC0_START, R_DC_SYNC0_CYCLE = 0x0980, 0x0981, 0x0990, 0x09A0
MBX_TYPE_ERR, MBX_TYPE_COE = 0x00, 0x03


def _ro_mask() -> bytearray:
    """Registers the EtherCAT side may not write (the PDI or the ESC itself owns them)."""
    m = bytearray(0x1000)
    for a, n in ((0x0000, 0x10), (R_ALIAS, 2), (R_DL_STATUS, 2), (R_AL_STATUS, 6), (R_WD_STATUS, 2),
                 (R_DC_RECV, 0x10), (R_DC_SYSTIME, 8), (R_DC_RECV_PU, 8), (R_DC_DIFF, 4), (0x098E, 2)):
        m[a:a + n] = b"\x01" * n
    for k in range(16):
        m[R_SM + 8 * k + 5] = 1  # SM status
        m[R_SM + 8 * k + 7] = 1  # SM PDI control
    return m


RO = _ro_mask()
