"""Where each App. B.2 row of `mlc.signals.ROWS` stands on a deltahil bench (the audit of session 20, helper mlc21).

One line per row (spindle rows of spindles 2–8 share spindle 1's line): ``NAME | status | where | note``.
Status: ``bench`` the NC side reads or writes it as App. B says; ``partial`` it does, with the limit the note
names; ``absent`` the NC ignores it / never writes it (the feature is not emulated: the note says which);
``hardware`` a bench cannot have it (a connector pin, a board's counter). `docs/mlc_signals.md` is rendered from
this table, `TESTS` and `mlc.signals` (``python docs/build_mlc_signals.py``); tests/test_mlc21_signal_table.py keeps
them in step, checks that every ``where`` file exists and that every test file `TESTS` cites still names the device.
"""

from __future__ import annotations

from dataclasses import dataclass

from mlc.signals import ROWS, Row

STATUSES = ("bench", "partial", "absent", "hardware")

_TABLE = """
CYCLE_START | bench | mlc/nc_link.py | rising edge; AUTO/MDI only, not under E-stop; releases M00/M01 holds (C9)
FEED_HOLD | bench | mlc/nc_link.py | rising edge; also stops manual motion in the manual modes
NC_RESET | bench | mlc/nc_link.py | rising edge; flushes the program and the handshake, M3x019 when the axes stand
DRY_RUN | bench | mlc/nc_link.py | level; cutting moves at the channel's dry-run feed × feed override
MPG_SIMULATION | absent | - | MPG-paced program run not emulated
DISABLE_HW_LIMIT | absent | - | the limit switches (0x60FD) always stop the axis (decisions M21-5, M22-3)
SINGLE_BLOCK | bench | nc/channel.py | level; stops after every block, an M/S/T-only one after its handshake (decision M22-2)
OPTIONAL_STOP | bench | mlc/nc_link.py | level; M01 holds with M3x038 only while ON
BLOCK_SKIP | bench | mlc/nc_link.py | level; '/' blocks read after the scan that saw it are skipped (decision M21-1)
MST_LOCK | bench | mlc/nc_link.py | level; no strobe, the block's motion runs (H9)
SERVO_ON | bench | hil/servo_relays.py | level, power-on image ON; OFF disables every axis at standstill, 0x0A07 if the NC moves one, a JOG/INC/MPG/HOME command refused; the spindle drives too: no speed, disabled below 1 rpm, 0x0C06 if the program turns one (decisions M22-1, M23-1, M23-2)
EMERGENCY_STOP | bench | mlc/nc_link.py | level; App. A 0x0401 on the rising edge, M3x018 follows it
SYNC_ADJUST | absent | - | gantry synchronisation not emulated
MST_FINISH | bench | mlc/nc_link.py | level; completes the handed code; the next strobe waits for it to drop (H1-H9)
M96_INTERRUPT | bench | mlc/nc_link.py | rising edge, after M96 P_ (nc/interrupt.py)
MST_MACRO_LOCK | absent | - | M/S/T macro calls (N1.123…) always run
MACRO_CALL_ACTIVATE | absent | - | MLC-triggered macro calls not emulated
M99_CALL_STOP | bench | mlc/nc_link.py | level, read when the main program's M99 is reached at rest: ON ends the program there (M25-1)
SPINDLE1_DO | hardware | - | pin 9 of the controller's spindle connector
SPINDLE2_DO | hardware | - | pin 9 of the controller's spindle connector
ENABLE_3_MPG | absent | - | only the 1st MPG (D2x008/D2x009) moves an axis
MACRO_PREPARE | absent | - | MLC-triggered macro calls not emulated
ROBOT_CS | absent | - | robot channels not emulated
MAG1_FORWARD | absent | - | tool magazine motion is the MLC's (the lathe MLC indexes its turret itself)
MAG1_BACKWARD | absent | - | as MAG1_FORWARD
MAG1_EXCHANGE | absent | - | as MAG1_FORWARD
MAG1_RESET | absent | - | as MAG1_FORWARD
MAG2_FORWARD | absent | - | as MAG1_FORWARD
MAG2_BACKWARD | absent | - | as MAG1_FORWARD
MAG2_EXCHANGE | absent | - | as MAG1_FORWARD
MAG2_RESET | absent | - | as MAG1_FORWARD
CANCEL_TAP_INTERRUPT | bench | mlc/nc_link.py | rising edge: the tapping interrupt status ends, nothing moves (M26-6)
MLC_TO_NC_BIT | bench | mlc/nc_link.py | #25000+n, re-sent when changed (C1)
SYNC_ENABLE | absent | - | synchronous control not emulated
TRANSFER_ENABLE | absent | - | command transfer not emulated
OSCILLATION_ENABLE | partial | mlc/manual_alarms.py | only App. A 0x1603 in HOME mode; no oscillation motion
SERVO_OFF | bench | hil/servo_relays.py | level, per axis slot; as SERVO_ON for one axis (decisions M22-1, M23-1)
SYNC_SLAVE | absent | - | synchronous control not emulated
TRANSFER_RECEIVE | absent | - | command transfer not emulated
HOME | bench | mlc/manual_alarms.py | HOME mode, per axis slot (decision M21-3)
LOCK_POS | bench | mlc/nc_link.py | manual modes, per axis slot
LOCK_NEG | bench | mlc/nc_link.py | manual modes, per axis slot
DISABLE_SOFT_LIMIT | bench | mlc/nc_link.py | the 1st software limit segment only, manual modes
JOG_FWD | bench | mlc/nc_link.py | JOG/RAPID level, INC rising edge, per axis slot
JOG_REV | bench | mlc/nc_link.py | as JOG_FWD
MLC_AXIS_SPEED_MODE | bench | hil/mlc_axes.py | level: the trigger's level runs the axis at D2x288+2i, its drop stops it (M26-26)
MLC_AXIS_SWITCH | bench | hil/mlc_axes.py | level; taken where the NC's command stands, back at rest with the NC's queue empty; a program moving the axis meanwhile is 0x141C (M26-21, M26-22, M26-23)
MLC_AXIS_TRIGGER | bench | hil/mlc_axes.py | position mode: rising edge (a new edge mid-move re-plans); speed mode: level (M26-25, M26-26)
MLC_AXIS_INCREMENTAL | bench | hil/mlc_axes.py | read at the trigger's edge: from the last target (M26-25)
SPINDLE_FWD | partial | mlc/nc_link.py | spindle 1 drives the bench spindle; spindles 2-8 have no drive
SPINDLE_REV | partial | mlc/nc_link.py | as SPINDLE_FWD
SPINDLE_ORIENT | partial | mlc/spindle_axis.py | spindle 1 (M19), through the C-axis switch
SPINDLE_TAP_RETRACT | partial | mlc/nc_link.py | 1st spindle: rising edge, channel idle in AUTO/MDI: the G84.48 retraction to R (M26-7)
SPINDLE_CS_SWITCH | partial | mlc/spindle_axis.py | spindle 1 only
SPINDLE_CMD_SOURCE | partial | mlc/nc_link.py | spindle 1 only (D2x024 as source)
SPINDLE_ALARM | bench | mlc/nc_link.py | rising edge raises App. A 0x0C0A, spindles 1-8
ETHERCAT_OK | bench | mlc/drive_status.py | every drive connected (slave in OP)
HSI | absent | - | the G31 probe latch reaches the channel directly (hil/runner.py), M30016… stay OFF
EIO_CONNECTED | bench | mlc/remote_io.py | remote I/O stations ([[io]])
CHANNEL_ENABLED | bench | mlc/nc_link.py | the bench's one channel
SPINDLE1_DI | hardware | - | spindle connector input
SPINDLE2_DI | hardware | - | spindle connector input
G900 | bench | mlc/nc_link.py | G900 P30200-30399 Q_ (C5)
MODE_AUTO | bench | mlc/nc_link.py | one mode bit of D2x000
MODE_EDIT | bench | mlc/nc_link.py | as MODE_AUTO
MODE_MDI | bench | mlc/nc_link.py | as MODE_AUTO
MODE_MPG | bench | mlc/nc_link.py | as MODE_AUTO
MODE_JOG | bench | mlc/nc_link.py | as MODE_AUTO
MODE_RAPID | bench | mlc/nc_link.py | as MODE_AUTO
MODE_INC | bench | mlc/nc_link.py | as MODE_AUTO
MODE_HOME | bench | mlc/nc_link.py | as MODE_AUTO
RUNNING | bench | mlc/nc_link.py | running or waiting for a finish, not in an M00/M01 hold
FEED_HOLD_STATUS | bench | mlc/nc_link.py | channel in feed hold
ESTOP_STATUS | bench | mlc/nc_link.py | follows M2x013
RESET_FINISHED | bench | mlc/nc_link.py | after NC reset once the axes stand, until the next cycle start
BREAKPOINT_SEARCH | absent | - | restart from a break point not emulated
PROGRAM_END | bench | mlc/nc_link.py | the last block, M02 or M30, until reset / cycle start
M02_EXECUTED | bench | mlc/nc_link.py | as PROGRAM_END, M02 only
M30_EXECUTED | bench | mlc/nc_link.py | as PROGRAM_END, M30 only
SINGLE_BLOCK_HOLD | bench | mlc/nc_link.py | stopped after a block in single block
NC_ERROR | bench | mlc/nc_link.py | an NC alarm (not an MLC user alarm) is active
MACRO_CALL_STATUS | absent | - | MLC-triggered macro calls not emulated
MACRO_CALL_READY | absent | - | MLC-triggered macro calls not emulated
MACRO_CALL_ERROR | absent | - | MLC-triggered macro calls not emulated
M96_ACTIVE | bench | mlc/nc_link.py | while the interrupt program runs
MODE_SWITCHING | bench | mlc/nc_link.py | the scan a mode switch is taken
MAIN_PROGRAM_LOCK | absent | - | program editing is the HMI's
SERVO_ERROR | bench | mlc/drive_status.py | a drive in FAULT / FAULT REACTION
AUTO_SERVO_ON | bench | mlc/drive_status.py | with M3x036: the bench's power-up enables every drive (decision M21-4)
SYSTEM_READY | bench | mlc/drive_status.py | every drive operation enabled
M00_HOLD | bench | mlc/nc_link.py | until cycle start
M01_HOLD | bench | mlc/nc_link.py | until cycle start, with M2x009 ON
SINGLE_BLOCK_DONE | bench | mlc/nc_link.py | as SINGLE_BLOCK_HOLD
USER_ALARM | bench | mlc/nc_link.py | any A device ON
PROGRAM_SCANNING | absent | - | the HMI's program check not emulated
PROGRAM_SCANNED | absent | - | the HMI's program check not emulated
M99_STOP_STATUS | bench | mlc/nc_link.py | ON once the program ended at its M99 under M2x026, until reset / cycle start (M25-1)
MACRO_INIT_DONE | absent | - | MLC-triggered macro calls not emulated
M_STROBE | bench | mlc/nc_link.py | with D3x048 until the finish (H1-H9)
S_STROBE | bench | mlc/nc_link.py | with D3x050 and D3x024 until the finish
T_STROBE | bench | mlc/nc_link.py | with D3x052 and D3x037, T codes in the magazine range
SPINDLE_CONNECTED | bench | mlc/drive_status.py | the bench's spindle drives
NC_TO_MLC_BIT | bench | mlc/nc_link.py | #25256+n as the program writes them (C1)
SERVO_CONNECTED | bench | mlc/drive_status.py | per axis slot
SERVO_ENABLED | bench | mlc/drive_status.py | per axis slot
OSCILLATING | absent | - | oscillation not emulated
HOMED | bench | mlc/nc_link.py | per axis slot (manual homing or drive homing)
HOMING_DONE | bench | mlc/nc_link.py | per axis slot
AT_ORIGIN | bench | mlc/nc_link.py | machine position 0, per axis slot
MLC_AXIS_SWITCHED | bench | hil/mlc_axes.py | ON the cycle the axis is the MLC's, OFF the cycle the NC has it back (M26-21, M26-23)
MLC_AXIS_REACHED | bench | hil/mlc_axes.py | position exactly on the target at rest / speed at D2x288+2i; OFF from the trigger on, stays OFF after a stop (M26-24, M26-25)
MOVING | bench | mlc/drive_status.py | |velocity| > 1e-4 per axis slot
MOVING_FWD | bench | mlc/drive_status.py | velocity > 1e-4
MOVING_REV | bench | mlc/drive_status.py | velocity < -1e-4
DIAMETER_MODE | bench | mlc/machine.py | the profile's diameter axes (N2.001 Bit10), per axis slot (decision M21-3)
SPINDLE_SPEED_REACHED | partial | mlc/drive_status.py | spindle drives of the bench (within 2 % or 1 rpm)
SPINDLE_ZERO_SPEED | partial | mlc/drive_status.py | spindle drives of the bench (below 1 rpm)
SPINDLE_TARGET_REACHED | partial | mlc/spindle_axis.py | spindle 1 orientation / C axis
SPINDLE_RIGID_TAPPING | partial | mlc/nc_link.py | 1st spindle: G74/G84 tapping strokes, their reversal, the G84.48 / M2x707 retraction (M26-5)
SPINDLE_POSITION_MODE | partial | mlc/drive_status.py | spindle drives of the bench (CSP)
SPINDLE_READY | partial | mlc/drive_status.py | spindle drives of the bench (operation enabled)
CHANNEL_SELECT | absent | - | one channel per bench
SPINDLE_ANALOG_1 | hardware | - | the controller's analog output (the lathe MLC writes it; nothing reads it)
SPINDLE_ANALOG_2 | hardware | - | the controller's analog output
REMOTE_OUT | bench | mlc/remote_io.py | remote I/O stations ([[io]])
MODE | bench | mlc/nc_link.py | taken when no program runs and no manual axis moves (D8)
FEED_OVERRIDE | bench | mlc/nc_link.py | 0-150 %
RAPID_OVERRIDE | bench | mlc/nc_link.py | % of the rapid speed, also the RAPID mode's speed
JOG_OVERRIDE | bench | mlc/nc_link.py | percentage mode (N1.011 Bit26 = 0) only
MPG1_AXIS | bench | mlc/nc_link.py | axis slot of the 1st MPG
MPG1_RATIO | bench | mlc/nc_link.py | units of N9.013 per detent
MPG2_AXIS | absent | - | as ENABLE_3_MPG
MPG2_RATIO | absent | - | as ENABLE_3_MPG
MPG3_AXIS | absent | - | as ENABLE_3_MPG
MPG3_RATIO | absent | - | as ENABLE_3_MPG
INC_STEP | bench | mlc/nc_link.py | units of N9.013 per press
ROBOT_CS_SELECT | absent | - | robot channels not emulated
ROBOT_TOOL_SELECT | absent | - | robot channels not emulated
OSC_AMPLITUDE | absent | - | oscillation not emulated
OSC_PERIOD | absent | - | oscillation not emulated
OSC_AXES | absent | - | oscillation not emulated
OSC_WAVE | absent | - | oscillation not emulated
SPINDLE1_SPEED | bench | mlc/nc_link.py | with M2x710 ON
SPINDLE1_OVERRIDE | bench | mlc/nc_link.py | applied by the NC (motion decisions 32)
SPINDLE1_GEAR | absent | - | gear ranges not emulated
SPINDLE2_SPEED | absent | - | the bench has one spindle drive
SPINDLE2_OVERRIDE | absent | - | the bench has one spindle drive
SPINDLE2_GEAR | absent | - | gear ranges not emulated
MAG1_TOOL | partial | mlc/lathe.py | written by the lathe MLC; the NC does not read it
MAG2_TOOL | absent | - | as MAG1_FORWARD
MACRO_NUMBER | absent | - | MLC-triggered macro calls not emulated
MLC_TO_NC_WORD | bench | mlc/nc_link.py | #25128+n, signed 16 bit
MLC_AXIS_TARGET | bench | hil/mlc_axes.py | machine coordinates (a lathe's X as a radius); past a software limit: 0x0A01/0x0A03, not started (M26-25)
MLC_AXIS_VELOCITY | bench | hil/mlc_axes.py | mm/min, rotary axes rpm; capped at the axis's velocity, 0 starts no position move (M26-25)
SPINDLE1_PULSES | hardware | - | the controller's spindle encoder counter
SPINDLE2_PULSES | hardware | - | the controller's spindle encoder counter
MPG_PULSES | bench | mlc/nc_link.py | the MPG's 16-bit counter (hil mpg, machine.mpg)
REMOTE_IN | bench | mlc/remote_io.py | remote I/O stations ([[io]])
TORQUE_FB | bench | mlc/drive_status.py | 0x6077 in 0.1 %
VELOCITY_FB_MM | bench | mlc/drive_status.py | 0x606C in mm/min
VELOCITY_FB_RPM | bench | mlc/drive_status.py | 0x606C in rpm
TORQUE_PEAK | bench | mlc/drive_status.py | peak |torque| while servo on
SPINDLE_TORQUE | bench | mlc/drive_status.py | spindle drives, 0.1 %
MULTI_Z_STATUS | absent | - | multi-Z not emulated
CURRENT_WCS | absent | - | not published (the interpreter's modal state runs ahead of the executed block)
SPINDLE1_SPEED_CMD | bench | mlc/nc_link.py | the S word in rpm, under G96 the rpm at the current X
SPINDLE1_SPEED_FB | bench | mlc/drive_status.py | the spindle drive's rpm
SPINDLE1_DEGREE | bench | mlc/drive_status.py | the spindle drive's angle, 0-360
MAG1_CURRENT_TOOL | absent | - | not published (the MLC keeps the tool in D2x036)
MAG1_STANDBY_TOOL | bench | mlc/nc_link.py | the latest T code
M_CODE | bench | mlc/nc_link.py | with M3x064
S_CODE | bench | mlc/nc_link.py | with M3x065 (G96: m/min)
T_CODE | bench | mlc/nc_link.py | with M3x066
NC_TO_MLC_WORD | bench | mlc/nc_link.py | #25384+n, truncated to signed 16 bit (B.3.6.4)
LOOKAHEAD_REMAINING | bench | mlc/nc_link.py | moves in the look-ahead queue
"""


@dataclass(frozen=True)
class Status:
    name: str
    status: str
    where: str  # a file of the project, "-" when nothing implements it
    note: str


def _parse() -> dict[str, Status]:
    out: dict[str, Status] = {}
    for line in _TABLE.strip().splitlines():
        name, status, where, note = (part.strip() for part in line.split("|", 3))
        out[name] = Status(name, status, where, note)
    return out


STATUS = _parse()


def key(row: Row) -> str:
    """The table line of a row: spindle k's relays share the line ``SPINDLE_<what>``."""
    name = row.name
    if name.startswith("SPINDLE") and name[7:8].isdigit() and name[8:9] == "_" and row.index >= 704:
        return "SPINDLE_" + name[9:]
    return name


def status(row: Row) -> Status:
    return STATUS[key(row)]


def rows_with_status() -> list[tuple[Row, Status]]:
    return [(row, status(row)) for row in ROWS]
# test files (tests/test_<stem>.py) naming each row's device, channel 1 address, App. B form or name: chosen
# when the table was written; tests/test_mlc21_signal_table.py checks that each still names it
TESTS: dict[str, tuple[str, ...]] = {
    'CYCLE_START': ('mlc_memory', 'run_stops_and_holds'),
    'FEED_HOLD': ('hil_run_events', 'mlc_exchange_edges', 'mlc_manual'),
    'NC_RESET': ('mlc_manual', 'run_stops_and_holds'),
    'SINGLE_BLOCK': ('mlc21_program_switches', 'mlc22_single_block'),
    'SERVO_ON': ('mlc22_servo_relays',),
    'SERVO_OFF': ('mlc22_servo_relays',),
    'OPTIONAL_STOP': ('formats_lathe_guide', 'run_stops_and_holds'),
    'M99_CALL_STOP': ('mlc25_m99_call_stop',),
    'M99_STOP_STATUS': ('mlc25_m99_call_stop',),
    'BLOCK_SKIP': ('mlc21_block_skip',),
    'MST_LOCK': ('mlc21_program_switches',),
    'EMERGENCY_STOP': ('campaign', 'mlc_manual', 'run_stops_and_holds', 'stop_matrix'),
    'MST_FINISH': ('alarms_servo', 'bench_tools', 'mlc_caxis_drilling', 'mlc_cli'),
    'M96_INTERRUPT': ('examples_benches', 'formats_mill', 'hil_run_events', 'lang_examples_mill'),
    'ENABLE_3_MPG': ('mlc_memory',),
    'MLC_TO_NC_BIT': ('mlc_exchange_edges',),
    'OSCILLATION_ENABLE': ('mlc_manual',),
    'HOME': ('alarms_manual_limits', 'mlc_manual'),
    'LOCK_POS': ('mlc_manual',),
    'DISABLE_SOFT_LIMIT': ('alarms_manual_limits', 'softlimits_inside'),
    'JOG_FWD': ('mlc_memory', 'run_imports'),
    'JOG_REV': ('mlc_memory',),
    'SPINDLE_FWD': ('mlc_on_change',),
    'MLC_AXIS_SPEED_MODE': ('mlcaxis27_axes',),
    'MLC_AXIS_SWITCH': ('mlcaxis27_axes',),
    'MLC_AXIS_TRIGGER': ('mlcaxis27_axes',),
    'MLC_AXIS_INCREMENTAL': ('mlcaxis27_axes',),
    'MLC_AXIS_SWITCHED': ('mlcaxis27_axes',),
    'MLC_AXIS_REACHED': ('mlcaxis27_axes',),
    'MLC_AXIS_TARGET': ('mlcaxis27_axes',),
    'MLC_AXIS_VELOCITY': ('mlcaxis27_axes',),
    'SPINDLE_ORIENT': ('alarms_servo',),
    'SPINDLE_CS_SWITCH': ('mlc_caxis',),
    'SPINDLE_ALARM': ('alarms_servo', 'mlc_exchange_edges'),
    'CANCEL_TAP_INTERRUPT': ('tap27_interrupted_tap',),
    'SPINDLE_TAP_RETRACT': ('tap27_interrupted_tap',),
    'SPINDLE_RIGID_TAPPING': ('tap27_interrupted_tap',),
    'ETHERCAT_OK': ('ethercat_io', 'ethercat_io_modules', 'ethercat_status', 'mlc21_drive_status_devices'),
    'HSI': ('alarms_appendix_a',),
    'EIO_CONNECTED': ('canopen_io', 'ethercat_io', 'ethercat_io_modules', 'ethercat_status'),
    'G900': ('formats_mill', 'lang_coords'),
    'MODE_MPG': ('mlc_manual',),
    'RUNNING': ('mlc21_program_switches', 'mlc_exchange_edges', 'mlc_handshake', 'mlc_manual'),
    'FEED_HOLD_STATUS': ('mlc_exchange_edges', 'mlc_manual'),
    'ESTOP_STATUS': ('mlc_manual',),
    'RESET_FINISHED': ('mlc_manual',),
    'PROGRAM_END': ('mlc_handshake',),
    'M30_EXECUTED': ('mlc_handshake',),
    'SINGLE_BLOCK_HOLD': ('mlc21_program_switches',),
    'NC_ERROR': ('mlc_manual',),
    'M96_ACTIVE': ('hil_run_events', 'mlc_interrupt'),
    'SERVO_ERROR': ('mlc21_drive_status_devices',),
    'AUTO_SERVO_ON': ('mlc21_status_relays',),
    'SYSTEM_READY': ('mlc21_status_relays',),
    'M00_HOLD': ('mlc_handshake', 'run_stops_and_holds'),
    'SINGLE_BLOCK_DONE': ('mlc21_program_switches',),
    'USER_ALARM': ('mlc_exchange_edges',),
    'M_STROBE': ('alarms_servo', 'bench_tools', 'cli_bad_input', 'mlc21_program_switches'),
    'S_STROBE': ('alarms_servo', 'mlc_handshake', 'mlc_on_change', 'motion_sync_css'),
    'T_STROBE': ('alarms_servo', 'mlc_handshake', 'mlc_on_change', 'report_html'),
    'NC_TO_MLC_BIT': ('lang_calls',),
    'SERVO_CONNECTED': ('ethercat_status', 'mlc21_drive_status_devices'),
    'HOMED': ('mlc_manual', 'motion_homing'),
    'HOMING_DONE': ('mlc_memory', 'motion_homing'),
    'DIAMETER_MODE': ('mlc21_status_relays',),
    'SPINDLE_SPEED_REACHED': ('mlc21_drive_status_devices',),
    'SPINDLE_TARGET_REACHED': ('mlc_caxis',),
    'SPINDLE_POSITION_MODE': ('mlc_caxis', 'mlc_caxis_drilling'),
    'SPINDLE_ANALOG_1': ('mlc_on_change',),
    'MODE': ('drive_modes',),
    'FEED_OVERRIDE': ('campaign_interrupt', 'hil_run_events', 'realtime_stretch', 'run_output'),
    'JOG_OVERRIDE': ('hil_run_events', 'run_stops_and_holds', 'script_api_args'),
    'SPINDLE1_OVERRIDE': ('motion_sync_css', 'motion_sync_thread', 'stretch_spindle'),
    'MPG_PULSES': ('mlc_memory',),
    'TORQUE_FB': ('drive_units', 'mlc21_drive_status_devices'),
    'VELOCITY_FB_MM': ('mlc21_drive_status_devices', 'mlc_on_change'),
    'VELOCITY_FB_RPM': ('mlc21_drive_status_devices', 'mlc_memory'),
    'TORQUE_PEAK': ('mlc21_drive_status_devices',),
    'SPINDLE1_SPEED_CMD': ('motion_sync_css',),
    'SPINDLE1_SPEED_FB': ('mlc21_drive_status_devices',),
    'SPINDLE1_DEGREE': ('mlc21_drive_status_devices',),
    'M_CODE': ('bench_tools', 'hil_run_events', 'mlc21_program_switches', 'mlc_caxis_drilling'),
    'S_CODE': ('mlc_handshake', 'mlc_memory', 'motion_sync_css', 'report_html'),
    'T_CODE': ('mlc_handshake', 'mlc_memory', 'report_html'),
    'LOOKAHEAD_REMAINING': ('bench_file',),
}
