"""Drive homing before a program (issue 23): every axis whose bench entry has `homing = {...}` is homed by its
own drive in CiA 402 homing mode (6) — the way an NC with EtherCAT/CANopen servos references its axes when
the home switch is wired to the drive — then switched back to CSP for the program.

The bench gives the method (CiA 402 0x6098), the machine position of the home position (0x607C, as counts),
the search speeds (0x6099, motor rpm) and the acceleration time (0x609A). They are written over SDO before the
drives start; the run then cycles with mode 6 and controlword bit 4 until every drive reports homing attained
and target reached (statusword bits 12 + 10), an error (bit 13), or the timeout.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING

from nc.alarms import Alarm

if TYPE_CHECKING:
    from hil.runner import BenchRunner

HOMING_FAILED = 0xDE11  # deltahil's own (nc/alarm_table.py)
MODE_NOT_SUPPORTED = 0x1604  # App. A: "The home mode is not supported."
LIMIT_DURING_HOMING = 0x1601  # App. A: "The hardware limit is triggered during execution of home mode 4 ..."
HOMING_MODE = 6
CSP = 8


@dataclass(frozen=True)
class DriveHoming:
    """An axis's bench `homing` table."""

    method: int  # CiA 402 homing method (0x6098)
    position: float = 0.0  # machine position of the home position, mm/deg (0x607C)
    switch_rpm: float = 100.0  # motor speed while searching the switch (0x6099:1)
    zero_rpm: float = 20.0  # motor speed of the final approach (0x6099:2)
    accel_ms: int = 200  # 0x609A: ms from 0 to 3000 rpm
    timeout: float = 60.0  # s of simulated (bench) time


def _objects(runner: BenchRunner, i: int, h: DriveHoming) -> list[tuple[int, int, bytes]]:
    sc = runner.scales[i]

    def speed(motor_rpm: float) -> bytes:  # 0x6099 in the drive's velocity unit, as 0x60FF (0.1 rpm on Delta)
        return struct.pack("<I", sc.units.velocity_to_raw(motor_rpm / 60.0 * sc.counts_per_rev, sc.counts_per_rev))

    return [(0x6098, 0, struct.pack("<b", h.method)),
            (0x607C, 0, struct.pack("<i", sc.to_counts(h.position))),
            (0x6099, 1, speed(h.switch_rpm)),
            (0x6099, 2, speed(h.zero_rpm)),
            (0x609A, 0, struct.pack("<I", h.accel_ms))]


def _homing_error(runner: BenchRunner, i: int, method: int, sw: int) -> Alarm:
    """The drive ended homing with an error (bit 13). With a limit switch active (0x60FD bit 0/1) that is App. A
    0x1601, "the hardware limit is triggered during homing ... check if the homing search direction is correct"
    (decisions ethercat.md E16); otherwise deltahil's 0xDE11."""
    axis = runner.axes[i]
    switch = {1: "negative", 2: "positive"}.get(runner.tx[i].digital_inputs & 0x3, "both")
    if runner.tx[i].digital_inputs & 0x3:
        return Alarm(LIMIT_DURING_HOMING, f"axis {axis}: the {switch} limit switch was met during homing (method "
                                          f"{method}): check the search direction and that the axis starts off the "
                                          f"limits", axis=axis)
    return Alarm(HOMING_FAILED, f"axis {axis}: the drive reports a homing error (method {method}, statusword "
                                f"0x{sw:04X})", axis=axis)


def home_axes(runner: BenchRunner) -> bool:
    """Home the axes that ask for it, in parallel; False (after raising the alarm) when one fails or a
    stop is requested. Called with every drive enabled, before the program's first cycle."""
    todo = {i: a.homing for i, a in enumerate(runner.bench.axes) if a.homing is not None}
    if not todo:
        return True
    for i, h in todo.items():
        for index, sub, data in _objects(runner, i, h):
            try:
                runner.link.sdo_write(i, index, sub, data)
            except Exception as exc:  # an SDO abort (a drive without that method) or no SDO at all
                code = getattr(exc, "code", None)
                why = f"SDO abort 0x{code:08X}" if isinstance(code, int) else str(exc)
                runner._alarm(Alarm(MODE_NOT_SUPPORTED, f"axis {runner.axes[i]}: the drive refuses homing method "
                                                        f"{h.method} (object 0x{index:04X}:{sub}: {why})",
                                    axis=runner.axes[i]))
                return False
    limit = int(round(max(h.timeout for h in todo.values()) / runner.bench.cycle))
    moded: set[int] = set()  # axes whose mode 6 went out in an earlier cycle (a start in the same frame is no edge)
    armed: set[int] = set()  # axes whose start (bit 4) went out in an earlier cycle: their statusword counts
    done: set[int] = set()
    ok = False
    for _ in range(limit):
        for i in armed - done:
            sw = runner.tx[i].statusword
            if sw & 0x3400 == 0x1400:  # homing attained, target reached
                done.add(i)
            elif sw & 0x2000:
                runner._alarm(_homing_error(runner, i, todo[i].method, sw))
                break
        else:
            if len(done) == len(todo):
                ok = True
                break
            if runner.stop_request is not None:
                break
            start = []
            for i in todo:
                rx, tx = runner.rx[i], runner.tx[i]
                rx.mode = CSP if i in done else HOMING_MODE
                # 0x6061 may not travel (CANopen axes' TPDOs): one cycle after the mode is the drive's
                if i not in done and i in moded and tx.statusword & 0x6F == 0x27:
                    rx.controlword |= 0x10  # homing operation start, held high until the drive is done
                    start.append(i)
            runner._exchange()
            moded.update(todo)
            armed.update(start)
            if any(m.faulted for m in runner.masters):
                break
            continue
        break
    else:
        late = [runner.axes[i] for i in todo if i not in done]
        runner._alarm(Alarm(HOMING_FAILED, f"axis {', '.join(late)}: homing not done within "
                                           f"{limit * runner.bench.cycle:g} s", axis=late[0]))
    for i in todo:
        runner.rx[i].controlword &= ~0x10  # bit 4 low: an unfinished homing is interrupted, the drive brakes
        if ok:
            runner.rx[i].mode = CSP  # on to the program where the axis stands (the runner sends that position)
    return ok
