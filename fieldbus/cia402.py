"""CiA 402 (IEC 61800-7-201) power drive state machine: the wire-level words, and the master's
non-blocking state machine that takes one step per bus cycle.

python-canopen's BaseNode402 blocks for up to 0.8 s per transition (anchors.md §10 lesson 9),
which a cyclic bench cannot afford, so the master side lives here and is shared by EtherCAT,
CANopen and SimLink.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class State(Enum):
    NOT_READY_TO_SWITCH_ON = "not ready to switch on"
    SWITCH_ON_DISABLED = "switch on disabled"
    READY_TO_SWITCH_ON = "ready to switch on"
    SWITCHED_ON = "switched on"
    OPERATION_ENABLED = "operation enabled"
    QUICK_STOP_ACTIVE = "quick stop active"
    FAULT_REACTION_ACTIVE = "fault reaction active"
    FAULT = "fault"


# Statusword bits
SW_READY = 1 << 0
SW_SWITCHED_ON = 1 << 1
SW_OP_ENABLED = 1 << 2
SW_FAULT = 1 << 3
SW_VOLTAGE = 1 << 4
SW_QUICK_STOP = 1 << 5  # active low: set while NOT in quick stop
SW_SWITCH_ON_DISABLED = 1 << 6
SW_WARNING = 1 << 7
SW_REMOTE = 1 << 9
SW_TARGET_REACHED = 1 << 10
SW_INTERNAL_LIMIT = 1 << 11
SW_FOLLOWING = 1 << 12  # CSP/CSV: drive follows the command value
SW_FOLLOWING_ERROR = 1 << 13  # CSP: following error

# Controlword commands (bits 0-3, 7)
CW_DISABLE_VOLTAGE = 0x0000
CW_QUICK_STOP = 0x0002
CW_SHUTDOWN = 0x0006
CW_SWITCH_ON = 0x0007
CW_ENABLE_OPERATION = 0x000F
CW_FAULT_RESET = 0x0080

# (mask, value) pairs of the standard's statusword table, most specific first
_DECODE: tuple[tuple[int, int, State], ...] = (
    (0x4F, 0x00, State.NOT_READY_TO_SWITCH_ON),
    (0x4F, 0x40, State.SWITCH_ON_DISABLED),
    (0x6F, 0x21, State.READY_TO_SWITCH_ON),
    (0x6F, 0x23, State.SWITCHED_ON),
    (0x6F, 0x27, State.OPERATION_ENABLED),
    (0x6F, 0x07, State.QUICK_STOP_ACTIVE),
    (0x4F, 0x0F, State.FAULT_REACTION_ACTIVE),
    (0x4F, 0x08, State.FAULT),
)

STATE_BITS: dict[State, int] = {
    State.NOT_READY_TO_SWITCH_ON: 0x00,
    State.SWITCH_ON_DISABLED: 0x40,
    State.READY_TO_SWITCH_ON: 0x21,
    State.SWITCHED_ON: 0x23,
    State.OPERATION_ENABLED: 0x27,
    State.QUICK_STOP_ACTIVE: 0x07,
    State.FAULT_REACTION_ACTIVE: 0x0F,
    State.FAULT: 0x08,
}


def _decode(statusword: int) -> State:
    for mask, value, state in _DECODE:
        if statusword & mask == value:
            return state
    return State.NOT_READY_TO_SWITCH_ON


_DECODED = tuple(_decode(sw) for sw in range(0x80))  # the masks read bits 0-6 only: one table lookup a cycle
STATES_BY_BITS = _DECODED  # decode_state(sw) is STATES_BY_BITS[sw & 0x7F] (the bench's per-drive pass reads it)


def decode_state(statusword: int) -> State:
    return _DECODED[statusword & 0x7F]


def command_of(controlword: int) -> str:
    """Name the device-control command a controlword carries (slave side decoding)."""
    if controlword & 0x80:
        return "fault_reset"
    if controlword & 0x02 == 0:
        return "disable_voltage"
    if controlword & 0x06 == 0x02:
        return "quick_stop"
    if controlword & 0x0F == 0x06 or controlword & 0x0F == 0x0E:
        return "shutdown"
    if controlword & 0x0F == 0x07:
        return "switch_on"
    if controlword & 0x0F == 0x0F:
        return "enable_operation"
    return "none"


class Target(Enum):
    DISABLED = "disabled"
    ENABLED = "enabled"
    QUICK_STOP = "quick stop"


@dataclass
class Cia402Master:
    """Per-drive master state machine: feed it the statusword each cycle, send the controlword it returns.

    It never blocks; `cycles_in_state` lets the caller time out a transition that does not happen.
    """

    target: Target = Target.DISABLED
    auto_fault_reset: bool = False
    state: State = State.NOT_READY_TO_SWITCH_ON
    cycles_in_state: int = 0
    _reset_phase: int = 0

    def request(self, target: Target) -> None:
        self.target = target

    def fault_reset(self) -> None:
        """Start a fault reset: one cycle low, then a rising edge on bit 7."""
        self._reset_phase = 2

    @property
    def enabled(self) -> bool:
        return self.state is State.OPERATION_ENABLED

    @property
    def faulted(self) -> bool:
        return self.state in (State.FAULT, State.FAULT_REACTION_ACTIVE)

    def step(self, statusword: int) -> int:
        state = decode_state(statusword)
        self.cycles_in_state = self.cycles_in_state + 1 if state is self.state else 0
        self.state = state
        if state is State.OPERATION_ENABLED and self.target is Target.ENABLED:  # the usual cycle, as below
            self._reset_phase = 0
            return CW_ENABLE_OPERATION

        if state in (State.FAULT, State.FAULT_REACTION_ACTIVE):
            if state is State.FAULT and (self._reset_phase or self.auto_fault_reset):
                if self._reset_phase == 2 or (self.auto_fault_reset and not self._reset_phase):
                    self._reset_phase = 1
                    return CW_DISABLE_VOLTAGE
                self._reset_phase = 0
                return CW_FAULT_RESET
            return CW_DISABLE_VOLTAGE
        self._reset_phase = 0

        if self.target is Target.DISABLED:
            return CW_SHUTDOWN if state is State.OPERATION_ENABLED else CW_DISABLE_VOLTAGE
        if self.target is Target.QUICK_STOP:
            if state in (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE):
                return CW_QUICK_STOP
            return CW_DISABLE_VOLTAGE
        # Target.ENABLED: walk the standard's transitions 2, 3, 4 one per cycle
        if state in (State.SWITCH_ON_DISABLED, State.NOT_READY_TO_SWITCH_ON):
            return CW_SHUTDOWN
        if state is State.READY_TO_SWITCH_ON:
            return CW_SWITCH_ON
        if state is State.SWITCHED_ON:
            return CW_ENABLE_OPERATION
        if state is State.OPERATION_ENABLED:
            return CW_ENABLE_OPERATION
        if state is State.QUICK_STOP_ACTIVE:
            return CW_DISABLE_VOLTAGE  # leave quick stop through switch on disabled
        return CW_DISABLE_VOLTAGE
