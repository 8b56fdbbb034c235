"""The NC5 special M relays and D registers (NC5 manual, Appendix B.2) as a named table.

Addressing (App. B.1): ``address = block + 1000·x + index`` with block 20000 (MLC → NC) or 30000
(NC → MLC) and x the channel digit (0 = general, 1…4 = channel 1…4). ``M2x000`` (cycle start) of
channel 1 is ``M21000``; ``D3x048`` (M code data) of channel 2 is ``D32048``.

The table below is written once per App. B row or family; `signal_table(channels)` expands it into
concrete addresses (axis families 16 wide, X Y Z A B C U V W 10…16, spindle blocks every 16 from
704). Pairs (u32/s32/f32) occupy two consecutive D words, low word first (see `mlc.memory`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

from mlc.memory import DeviceError, parse_address

Width = Literal["bit", "u16", "s16", "u32", "f32"]
AXIS_LETTERS = ("X", "Y", "Z", "A", "B", "C", "U", "V", "W") + tuple(f"AX{n}" for n in range(10, 17))

MLC_TO_NC, NC_TO_MLC = 2, 3  # the ten-thousands digit


def m2(x: int, i: int) -> int:
    """Address number of special relay M2x<i> (MLC → NC)."""
    return 20000 + 1000 * x + i


def m3(x: int, i: int) -> int:
    return 30000 + 1000 * x + i


d2, d3 = m2, m3  # D registers use the same numbering


@dataclass(frozen=True)
class Row:
    kind: Literal["M", "D"]
    direction: int  # 2: MLC → NC, 3: NC → MLC
    index: int  # last three digits
    name: str
    width: Width = "bit"
    general: bool = False  # x = 0 (system-wide) instead of per channel
    count: int = 1  # family size
    stride: int = 1  # address step inside the family (2 for pairs)
    text: str = ""


@dataclass(frozen=True)
class Signal:
    address: str  # "M21000"
    number: int
    kind: Literal["M", "D", "A", "X", "Y"]
    name: str  # "CYCLE_START", "JOG_FWD_X", "TORQUE_FB_3"
    channel: int  # 0 for the general block
    direction: int
    width: Width
    text: str


def _axis(n: int) -> str:
    return AXIS_LETTERS[n]


# ---- App. B.2, row by row (names follow the manual's wording) ------------------------------
ROWS: tuple[Row, ...] = (
    # B.2.1.1 special M, MLC → NC
    Row("M", 2, 0, "CYCLE_START", text="Cycle Start"),
    Row("M", 2, 1, "FEED_HOLD", text="Feed Hold"),
    Row("M", 2, 4, "NC_RESET", text="NC Reset"),
    Row("M", 2, 5, "DRY_RUN", text="Enable Dry Run"),
    Row("M", 2, 6, "MPG_SIMULATION", text="MPG Simulation"),
    Row("M", 2, 7, "DISABLE_HW_LIMIT", text="Disable Hardware Limit"),
    Row("M", 2, 8, "SINGLE_BLOCK", text="Single Block"),
    Row("M", 2, 9, "OPTIONAL_STOP", text="Optional Stop"),
    Row("M", 2, 10, "BLOCK_SKIP", text="Single Block Skip ('/')"),
    Row("M", 2, 11, "MST_LOCK", text="M, S, and T Codes Lock"),
    Row("M", 2, 12, "SERVO_ON", text="Servo ON/ OFF"),
    Row("M", 2, 13, "EMERGENCY_STOP", text="Enable Emergency Stop"),
    Row("M", 2, 14, "SYNC_ADJUST", text="Enable Synchronization Adjustment"),
    Row("M", 2, 16, "MST_FINISH", text="M, S, and T Codes Finished"),
    Row("M", 2, 19, "M96_INTERRUPT", text="M96 Program Interruption"),
    Row("M", 2, 21, "MST_MACRO_LOCK", text="M, S, and T Codes Call Macro Lock"),
    Row("M", 2, 25, "MACRO_CALL_ACTIVATE", text="Macro Call Activation"),
    Row("M", 2, 26, "M99_CALL_STOP", text="M99 Call Stop"),
    Row("M", 2, 18, "SPINDLE1_DO", general=True, text="Spindle1 DO Control"),
    Row("M", 2, 19, "SPINDLE2_DO", general=True, text="Spindle2 DO Control"),
    Row("M", 2, 24, "ENABLE_3_MPG", general=True, text="Enable 3 MPG Control"),
    Row("M", 2, 32, "MACRO_PREPARE", count=16, text="Macro Call Preparation"),
    Row("M", 2, 48, "ROBOT_CS", count=4, text="Robot Coordinate System"),
    Row("M", 2, 64, "MAG1_FORWARD", text="Tool Magazine 1 Move Forward"),
    Row("M", 2, 65, "MAG1_BACKWARD", text="Tool Magazine 1 Move Backward"),
    Row("M", 2, 66, "MAG1_EXCHANGE", text="Tool 1 Exchange"),
    Row("M", 2, 67, "MAG1_RESET", text="Tool Magazine 1 Reset"),
    Row("M", 2, 72, "MAG2_FORWARD", text="Tool Magazine 2 Move Forward"),
    Row("M", 2, 73, "MAG2_BACKWARD", text="Tool Magazine 2 Move Backward"),
    Row("M", 2, 74, "MAG2_EXCHANGE", text="Tool 2 Exchange"),
    Row("M", 2, 75, "MAG2_RESET", text="Tool Magazine 2 Reset"),
    Row("M", 2, 80, "CANCEL_TAP_INTERRUPT", text="Canceling Tapping Interrupt Status"),
    Row("M", 2, 128, "MLC_TO_NC_BIT", count=128, text="MLC to NC Variable (#25000+n)"),
    Row("M", 2, 256, "SYNC_ENABLE", text="Synchronous Control Enable"),
    Row("M", 2, 257, "TRANSFER_ENABLE", text="Command Transfer Enable"),
    Row("M", 2, 264, "OSCILLATION_ENABLE", text="Axes Oscillation Control Enable"),
    Row("M", 2, 272, "SERVO_OFF", count=16, text="Axis Servo OFF"),
    Row("M", 2, 288, "SYNC_SLAVE", count=16, text="Slave Axis Follows the Master Axis"),
    Row("M", 2, 304, "TRANSFER_RECEIVE", count=16, text="Axis Receives Command from The Master Axis"),
    Row("M", 2, 320, "HOME", count=16, text="Axis Homing"),
    Row("M", 2, 336, "LOCK_POS", count=16, text="Lock Axis Movement in Positive Direction"),
    Row("M", 2, 352, "LOCK_NEG", count=16, text="Lock Axis Movement in Negative Direction"),
    Row("M", 2, 368, "DISABLE_SOFT_LIMIT", count=16, text="Disable Axis 1st Software Limit"),
    Row("M", 2, 384, "JOG_FWD", count=16, text="Axis JOG Forward"),
    Row("M", 2, 400, "JOG_REV", count=16, text="Axis JOG Reverse"),
    Row("M", 2, 416, "MLC_AXIS_SPEED_MODE", count=16, text="MLC Axis Control Mode"),
    Row("M", 2, 432, "MLC_AXIS_SWITCH", count=16, text="NC / MLC Axis Switching"),
    Row("M", 2, 448, "MLC_AXIS_TRIGGER", count=16, text="Trigger Axis' Movement (MLC Axis)"),
    Row("M", 2, 464, "MLC_AXIS_INCREMENTAL", count=16, text="MLC Axis Command Type"),
    *(Row("M", 2, 704 + 16 * k + off, f"SPINDLE{k + 1}_{nm}", text=f"Spindle {k + 1} {tx}")
      for k in range(8)
      for off, nm, tx in ((0, "FWD", "Forward Rotation"), (1, "REV", "Reverse Rotation"),
                          (2, "ORIENT", "Positioning Control"), (3, "TAP_RETRACT", "Retraction After Tapping"),
                          (4, "CS_SWITCH", "Switching C / S Axis"), (6, "CMD_SOURCE", "Command Source"),
                          (7, "ALARM", "Alarm"))),
    # B.2.2.1 special M, NC → MLC
    Row("M", 3, 0, "ETHERCAT_OK", general=True, text="EtherCAT Communication Status"),
    Row("M", 3, 16, "HSI", general=True, count=8, text="HSI Status"),
    Row("M", 3, 32, "EIO_CONNECTED", general=True, count=20, text="EIO Connection Status (node 501+n)"),
    Row("M", 3, 80, "CHANNEL_ENABLED", general=True, count=4, text="NC Channel Enable Status"),
    Row("M", 3, 96, "SPINDLE1_DI", general=True, text="Spindle 1 DI Status"),
    Row("M", 3, 97, "SPINDLE2_DI", general=True, text="Spindle 2 DI Status"),
    Row("M", 3, 200, "G900", general=True, count=200, text="G900 Command Control M_"),
    Row("M", 3, 0, "MODE_AUTO", text="AUTO"),
    Row("M", 3, 1, "MODE_EDIT", text="EDIT"),
    Row("M", 3, 2, "MODE_MDI", text="MDI"),
    Row("M", 3, 3, "MODE_MPG", text="MPG"),
    Row("M", 3, 4, "MODE_JOG", text="JOG"),
    Row("M", 3, 5, "MODE_RAPID", text="RAPID"),
    Row("M", 3, 6, "MODE_INC", text="INC"),
    Row("M", 3, 7, "MODE_HOME", text="HOME"),
    Row("M", 3, 16, "RUNNING", text="Cycle Start Status"),
    Row("M", 3, 17, "FEED_HOLD_STATUS", text="Feed Hold Status"),
    Row("M", 3, 18, "ESTOP_STATUS", text="Emergency Stop Status"),
    Row("M", 3, 19, "RESET_FINISHED", text="Reset Finished"),
    Row("M", 3, 20, "BREAKPOINT_SEARCH", text="Break Point Searching"),
    Row("M", 3, 21, "PROGRAM_END", text="Program End Finished"),
    Row("M", 3, 22, "M02_EXECUTED", text="M02 Executed"),
    Row("M", 3, 23, "M30_EXECUTED", text="M30 Cycle Stop and Index Reset"),
    Row("M", 3, 24, "SINGLE_BLOCK_HOLD", text="Single Block Hold"),
    Row("M", 3, 25, "NC_ERROR", text="NC Error"),
    Row("M", 3, 27, "MACRO_CALL_STATUS", text="Macro Call Status"),
    Row("M", 3, 28, "MACRO_CALL_READY", text="Macro Call Ready"),
    Row("M", 3, 29, "MACRO_CALL_ERROR", text="Macro Call Error"),
    Row("M", 3, 31, "M96_ACTIVE", text="M96 (Program Interruption) in Execution"),
    Row("M", 3, 32, "MODE_SWITCHING", text="System Mode Switching"),
    Row("M", 3, 33, "MAIN_PROGRAM_LOCK", text="Main Program Lock"),
    Row("M", 3, 34, "SERVO_ERROR", text="Servo Drive Error"),
    Row("M", 3, 35, "AUTO_SERVO_ON", text="Axes Auto Servo ON Status"),
    Row("M", 3, 36, "SYSTEM_READY", text="System Ready and Servo ON"),
    Row("M", 3, 37, "M00_HOLD", text="M00 System Hold"),
    Row("M", 3, 38, "M01_HOLD", text="M01 Optional Stop"),
    Row("M", 3, 39, "SINGLE_BLOCK_DONE", text="Block Finished on Single Block Mode"),
    Row("M", 3, 40, "USER_ALARM", text="User Define Alarm Status"),
    Row("M", 3, 44, "PROGRAM_SCANNING", text="NC Program Scanning"),
    Row("M", 3, 45, "PROGRAM_SCANNED", text="NC Program Scan finished"),
    Row("M", 3, 47, "M99_STOP_STATUS", text="M99 Call Stop Status"),
    Row("M", 3, 48, "MACRO_INIT_DONE", count=16, text="Macro Call Initial Finished"),
    Row("M", 3, 64, "M_STROBE", text="M Code Execution"),
    Row("M", 3, 65, "S_STROBE", text="S Code Execution"),
    Row("M", 3, 66, "T_STROBE", text="T Code Execution"),
    Row("M", 3, 96, "SPINDLE_CONNECTED", count=8, text="Connection Status of n-th Spindle"),
    Row("M", 3, 128, "NC_TO_MLC_BIT", count=128, text="NC Variable to MLC (#25256+n)"),
    Row("M", 3, 256, "SERVO_CONNECTED", count=16, text="Servo Connection Status"),
    Row("M", 3, 272, "SERVO_ENABLED", count=16, text="Servo Enable Status"),
    Row("M", 3, 304, "OSCILLATING", count=16, text="Oscillation Control Status"),
    Row("M", 3, 320, "HOMED", count=16, text="Axis Homed Status"),
    Row("M", 3, 336, "HOMING_DONE", count=16, text="Homing Finished Status"),
    Row("M", 3, 352, "AT_ORIGIN", count=16, text="Axis at Origin Position"),
    Row("M", 3, 432, "MLC_AXIS_SWITCHED", count=16, text="Axis Switch to MLC Axis Finished"),
    Row("M", 3, 448, "MLC_AXIS_REACHED", count=16, text="Axis Target Reached (MLC Axis)"),
    Row("M", 3, 464, "MOVING", count=16, text="Axis Is Moving"),
    Row("M", 3, 480, "MOVING_FWD", count=16, text="Axis Moving Forward"),
    Row("M", 3, 496, "MOVING_REV", count=16, text="Axis Moving Backward"),
    Row("M", 3, 512, "DIAMETER_MODE", count=16, text="Diameter or Radius Mode"),
    *(Row("M", 3, 704 + 16 * k + off, f"SPINDLE{k + 1}_{nm}", text=f"Spindle {k + 1} {tx}")
      for k in range(8)
      for off, nm, tx in ((0, "SPEED_REACHED", "Speed Reach"), (1, "ZERO_SPEED", "Zero Speed"),
                          (2, "TARGET_REACHED", "Target Reach"), (3, "RIGID_TAPPING", "Is in The Rigid Tapping"),
                          (5, "POSITION_MODE", "Is in Position Axis Mode"), (6, "READY", "Ready"))),
    # B.2.3.1 special D, MLC → NC
    Row("D", 2, 0, "CHANNEL_SELECT", "u16", general=True, text="NC Channel Selection"),
    Row("D", 2, 160, "SPINDLE_ANALOG_1", "s16", general=True, text="Spindle Analog Voltage Output Port 1 (0.01 V)"),
    Row("D", 2, 161, "SPINDLE_ANALOG_2", "s16", general=True, text="Spindle Analog Voltage Output Port 2 (0.01 V)"),
    Row("D", 2, 200, "REMOTE_OUT", "u16", general=True, count=32, text="Remote Module Output (4 words per module)"),
    Row("D", 2, 0, "MODE", "u16", text="NC Mode Switching (0 AUTO … 7 HOME)"),
    Row("D", 2, 2, "FEED_OVERRIDE", "u16", text="Feed Rate Percentage"),
    Row("D", 2, 4, "RAPID_OVERRIDE", "u16", text="Rapid Speed Percentage"),
    Row("D", 2, 6, "JOG_OVERRIDE", "u16", text="Speed Override for JOG and INC"),
    Row("D", 2, 8, "MPG1_AXIS", "u16", text="1st MPG Axes Selection"),
    Row("D", 2, 9, "MPG1_RATIO", "u16", text="1st MPG Ratio Selection"),
    Row("D", 2, 10, "MPG2_AXIS", "u16", text="2nd MPG Axes Selection"),
    Row("D", 2, 11, "MPG2_RATIO", "u16", text="2nd MPG Ratio Selection"),
    Row("D", 2, 12, "MPG3_AXIS", "u16", text="3rd MPG Axes Selection"),
    Row("D", 2, 13, "MPG3_RATIO", "u16", text="3rd MPG Ratio Selection"),
    Row("D", 2, 14, "INC_STEP", "u32", text="Axes Movement in INC Mode"),
    Row("D", 2, 16, "ROBOT_CS_SELECT", "u16", text="Robot's Coordinate System Switch"),
    Row("D", 2, 17, "ROBOT_TOOL_SELECT", "u16", text="Robot's Tool System Switch"),
    Row("D", 2, 18, "OSC_AMPLITUDE", "f32", text="Axes Oscillation Amplitude"),
    Row("D", 2, 20, "OSC_PERIOD", "f32", text="Axes Oscillation Cycle Time"),
    Row("D", 2, 22, "OSC_AXES", "u16", text="Oscillation Axes Enable"),
    Row("D", 2, 23, "OSC_WAVE", "u16", text="Axes Oscillation Wave Type"),
    Row("D", 2, 24, "SPINDLE1_SPEED", "u32", text="1st Spindle Speed (MLC source)"),
    Row("D", 2, 26, "SPINDLE1_OVERRIDE", "u16", text="1st Spindle Speed Rate"),
    Row("D", 2, 27, "SPINDLE1_GEAR", "u16", text="1st Spindle Gear"),
    Row("D", 2, 30, "SPINDLE2_SPEED", "u32", text="2nd Spindle Speed (MLC source)"),
    Row("D", 2, 32, "SPINDLE2_OVERRIDE", "u16", text="2nd Spindle Speed Rate"),
    Row("D", 2, 33, "SPINDLE2_GEAR", "u16", text="2nd Spindle Gear"),
    Row("D", 2, 36, "MAG1_TOOL", "u16", count=3, text="Tool / Standby / Command Tool Number, Magazine 1"),
    Row("D", 2, 42, "MAG2_TOOL", "u16", count=3, text="Tool / Standby / Command Tool Number, Magazine 2"),
    Row("D", 2, 64, "MACRO_NUMBER", "u16", count=16, text="Macro Call Macro Number"),
    Row("D", 2, 128, "MLC_TO_NC_WORD", "s16", count=128, text="MLC to NC Variable (#25128+n)"),
    Row("D", 2, 256, "MLC_AXIS_TARGET", "f32", count=16, stride=2, text="Target Position (MLC Axis)"),
    Row("D", 2, 288, "MLC_AXIS_VELOCITY", "f32", count=16, stride=2, text="Target Velocity (MLC Axis)"),
    # B.2.4.1 special D, NC → MLC
    Row("D", 3, 0, "SPINDLE1_PULSES", "u16", general=True, text="Pulse Feedback of Spindle 1"),
    Row("D", 3, 1, "SPINDLE2_PULSES", "u16", general=True, text="Pulse Feedback of Spindle 2"),
    Row("D", 3, 4, "MPG_PULSES", "u16", general=True, text="MPG Pulse Feedback"),
    Row("D", 3, 200, "REMOTE_IN", "u16", general=True, count=32, text="Remote Module Input (4 words per module)"),
    Row("D", 3, 240, "TORQUE_FB", "s16", general=True, count=32, text="Torque Feedback (0x6077, 0.1 %)"),
    Row("D", 3, 272, "VELOCITY_FB_MM", "f32", general=True, count=32, stride=2,
        text="Velocity Feedback (0x606C, mm/min)"),
    Row("D", 3, 336, "VELOCITY_FB_RPM", "f32", general=True, count=32, stride=2,
        text="Velocity Feedback (0x606C, RPM)"),
    Row("D", 3, 400, "TORQUE_PEAK", "u16", general=True, count=32, text="Torque Peak (0.1 %)"),
    Row("D", 3, 432, "SPINDLE_TORQUE", "s16", general=True, count=8, text="Spindle Torque (0.1 %)"),
    Row("D", 3, 14, "MULTI_Z_STATUS", "u32", text="Current Status of Multi-Z axis"),
    Row("D", 3, 16, "CURRENT_WCS", "u16", text="Current Coordinate System"),
    Row("D", 3, 24, "SPINDLE1_SPEED_CMD", "f32", text="Speed Command of 1st Spindle (RPM)"),
    Row("D", 3, 26, "SPINDLE1_SPEED_FB", "f32", text="Speed Feedback of 1st Spindle (RPM)"),
    Row("D", 3, 28, "SPINDLE1_DEGREE", "f32", text="Actual Degree of 1st Spindle"),
    Row("D", 3, 36, "MAG1_CURRENT_TOOL", "u16", text="Current Tool Number, Magazine 1"),
    Row("D", 3, 37, "MAG1_STANDBY_TOOL", "u16", text="Standby Tool Number (the latest T code)"),
    Row("D", 3, 48, "M_CODE", "u32", text="1st M Code Data"),
    Row("D", 3, 50, "S_CODE", "u32", text="1st S Code Data (RPM)"),
    Row("D", 3, 52, "T_CODE", "u32", text="1st T Code Data"),
    Row("D", 3, 128, "NC_TO_MLC_WORD", "s16", count=128, text="NC Variable to MLC (#25384+n)"),
    Row("D", 3, 320, "LOOKAHEAD_REMAINING", "u32", text="Look Ahead Remaining Command"),
)


def _member(row: Row, k: int) -> str:
    if row.count == 1:
        return row.name
    if row.count == 16 and (row.kind == "M" and row.index >= 256 or row.name.startswith("MLC_AXIS_")):
        return f"{row.name}_{_axis(k)}"  # per-channel-axis family, X Y Z A B C …
    return f"{row.name}_{k + 1}"


_MEMBERS: dict[tuple[int, int], list[Signal]] = {}  # (row index, channel) → the row's signals there, built once


def _members(i: int, row: Row, x: int) -> list[Signal]:
    """Row i's signals in channel x (0: the general block): the same objects for the table and the name index."""
    sigs = _MEMBERS.get((i, x))
    if sigs is None:
        sigs = _MEMBERS[(i, x)] = []
        for k in range(row.count):
            n = row.direction * 10000 + 1000 * x + row.index + k * row.stride
            sigs.append(Signal(f"{row.kind}{n}", n, row.kind, _member(row, k), x, row.direction, row.width, row.text))
    return sigs


@lru_cache(maxsize=None)
def _clock_relays() -> tuple[Signal, ...]:
    """The four system clock relays sit in the MLC→NC block but are written by the NC (B1)."""
    return tuple(Signal(f"M{29032 + i}", 29032 + i, "M", nm, 0, 3, "bit", tx)
                 for i, (nm, tx) in enumerate((("PULSE_500MS", "Time Pulse (500 ms)"), ("PULSE_50MS", "Time Pulse (50 ms)"),
                                               ("ALWAYS_OFF", "Remaining OFF"), ("ALWAYS_ON", "Remaining ON"))))


@lru_cache(maxsize=None)
def signal_table(channels: tuple[int, ...] = (1,)) -> dict[str, Signal]:
    """Every signal of the general block and of the given channels, keyed by address."""
    out: dict[str, Signal] = {}
    for i, row in enumerate(ROWS):
        for x in (0,) if row.general else channels:
            for sig in _members(i, row, x):
                out[sig.address] = sig
    for sig in _clock_relays():
        out[sig.address] = sig
    return out


@lru_cache(maxsize=None)
def _by_name(channel: int) -> dict[str, Signal]:
    """Signal names of one channel (and the general ones), the first in the order of `signal_table` (channels 1–4)
    winning. Built from the general block's and this channel's rows alone, not from the whole table (5,308 signals
    for four channels, ≈ 10 ms of every `hil run`'s start for the lathe MLC's few names; bench decision B65)."""
    out: dict[str, Signal] = {}
    for i, row in enumerate(ROWS):
        if row.general or channel in (1, 2, 3, 4):
            for sig in _members(i, row, 0 if row.general else channel):
                out.setdefault(sig.name, sig)
    for sig in _clock_relays():
        out.setdefault(sig.name, sig)
    return out


@lru_cache(maxsize=None)
def _named(channel: int, name: str) -> Signal | None:
    """`_by_name(channel).get(name)`, the same object, from the rows that can hold the name alone: a row's one
    signal is its name, a family's members its name and a suffix. The lathe MLC resolves 19 names; the index of all
    of channel 1's (≈ 1,300 `Signal`s) cost ≈ 3 ms of every `hil run`'s start (bench decision B91)."""
    for i, row in enumerate(ROWS):
        if not (row.general or channel in (1, 2, 3, 4)):
            continue
        if row.name == name if row.count == 1 else name.startswith(row.name) and name[len(row.name):][:1] == "_":
            for sig in _members(i, row, 0 if row.general else channel):
                if sig.name == name:  # the first in _by_name's order, as its setdefault keeps
                    return sig
    for sig in _clock_relays():
        if sig.name == name:
            return sig
    return None


def resolve(spec: str, channel: int = 1) -> Signal:
    """A device by address (``M21016``) or by name (``MST_FINISH``, ``JOG_FWD_X``; channel-relative)."""
    try:
        kind, n = parse_address(spec)
    except DeviceError:
        sig = _named(channel, spec.strip().upper())
        if sig is not None:
            return sig
        raise DeviceError(f"{spec!r} is neither a device address nor a signal name of App. B") from None
    sig = signal_table(tuple(range(1, 5))).get(f"{kind}{n}")  # (a name needs only its channel's rows: _by_name)
    if sig is not None:
        return sig
    return Signal(f"{kind}{n}", n, kind, f"{kind}{n}", 0, 0, "bit" if kind != "D" else "u16", "ordinary MLC device")
