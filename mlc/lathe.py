"""The default machine MLC for the example lathe (X/Z, one spindle, a 12-station turret, coolant).

    M03 / M04 / M05  spindle forward / reverse / stop: relays M2x704 / M2x705; the finish waits for
                     "speed reached" (M3x704) or "zero speed" (M3x705) from the spindle drive
    S                the NC publishes the speed command (D3x024); the analog output D20160 follows
    M08 / M09        coolant on / off: remote I/O module 0, output 0
    M19 / M20        spindle orientation: stop (as M05), M2x706, finish on M3x706 / cancel
    M66 / M77        spindle → C axis / back (lathe P358 / P359, `params["c_axis_m"]`): stop the
                     spindle (as M05), M2x708 + M1126 ON / OFF, finish when the NC reports the
                     switch done on M2239 (mlc/spindle_axis.py does the NC side)
    T                turret: station = T // 100 (T0202 → station 2); the finish comes after the
                     turret delay per station indexed, then the current tool D2x036 is updated
    anything else    finished at once

It is an ordinary MLC program: copy it to start your own (docs/guide/mlc.md).
"""

from __future__ import annotations

from mlc.program import ScanContext

NAME = "default lathe MLC"
SCAN_ON_CHANGE = True  # the scan depends only on what it reads and on mlc.state (mlc/on_change.py)
STATIONS = 12
TURRET_DELAY = 0.15  # s per station indexed
COOLANT = (0, 0)  # (remote I/O module, digital output)
C_AXIS_M = (66, 77)  # lathe parameters 358 / 359: spindle → C axis, C axis → spindle


def setup(mlc: ScanContext) -> None:
    mlc.state.update(job=None, station=1)
    mlc.put("MAG1_TOOL_1", 1)


def scan(mlc: ScanContext) -> None:
    st = mlc.state
    strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")
    if not strobe:
        # The NC dropped the strobe (after our finish, or a reset aborted it): finish goes OFF.
        mlc.set("MST_FINISH", False)
        st["job"] = None
    elif st["job"] is None and not mlc.m("MST_FINISH"):
        st["job"] = _start(mlc)  # latched this scan; the finish comes in a later scan
    elif st["job"] is not None and not mlc.m("MST_FINISH") and _done(mlc, st["job"]):
        mlc.set("MST_FINISH")
    if mlc.rising("PROGRAM_END") and (mlc.m("M02_EXECUTED") or mlc.m("M30_EXECUTED")):
        # M02 / M30 stop the spindle and the coolant, as the machine builder's ladder usually does.
        mlc.set("SPINDLE1_FWD", False)
        mlc.set("SPINDLE1_REV", False)
        mlc.io.out(*COOLANT, False)
    _spindle_analog(mlc)


def _start(mlc: ScanContext) -> tuple:
    if mlc.m("M_STROBE"):
        code = int(mlc.d("M_CODE"))
        if code in (3, 4):
            mlc.set("SPINDLE1_FWD", code == 3)
            mlc.set("SPINDLE1_REV", code == 4)
        elif code == 5:
            mlc.set("SPINDLE1_FWD", False)
            mlc.set("SPINDLE1_REV", False)
        elif code in (8, 9):
            mlc.io.out(*COOLANT, code == 8)
        elif code == 19:
            mlc.set("SPINDLE1_FWD", False)
            mlc.set("SPINDLE1_REV", False)
            mlc.set("SPINDLE1_ORIENT")
        elif code == 20:
            mlc.set("SPINDLE1_ORIENT", False)
        elif code in _c_axis_m(mlc):
            to_c = code == _c_axis_m(mlc)[0]
            if to_c:  # the spindle stops before it becomes the C axis (lathe manual §3.2.2 note 2)
                mlc.set("SPINDLE1_FWD", False)
                mlc.set("SPINDLE1_REV", False)
            mlc.set("SPINDLE1_CS_SWITCH", to_c)
            mlc.set("M1126", to_c)
        return ("M", code)
    if mlc.m("S_STROBE"):
        return ("S", mlc.d("S_CODE"))
    tool = int(mlc.d("T_CODE"))
    target = max(1, min(STATIONS, tool // 100 or tool))
    here = mlc.state["station"]
    steps = min((target - here) % STATIONS, (here - target) % STATIONS)
    mlc.state["turret_target"] = target
    return ("T", steps * TURRET_DELAY)


def _done(mlc: ScanContext, job: tuple) -> bool:
    kind, value = job
    spindle = mlc.m("SPINDLE_CONNECTED_1")
    if kind == "M":
        if value in (3, 4):
            return not spindle or mlc.d("SPINDLE1_SPEED_CMD") == 0 or mlc.m("SPINDLE1_SPEED_REACHED")
        if value == 5:
            return not spindle or mlc.m("SPINDLE1_ZERO_SPEED")
        if value == 19:
            return not spindle or mlc.m("SPINDLE1_TARGET_REACHED")
        if value in _c_axis_m(mlc):
            return not spindle or mlc.m("M2239") == (value == _c_axis_m(mlc)[0])
        return True
    if kind == "T":
        if mlc.timer("turret", value, True):
            mlc.timer("turret", 0, False)
            mlc.state["station"] = mlc.state["turret_target"]
            mlc.put("MAG1_TOOL_1", mlc.state["station"])
            return True
        return False
    return True


def _c_axis_m(mlc: ScanContext) -> tuple[int, int]:
    return tuple(mlc.params.get("c_axis_m", C_AXIS_M))  # type: ignore[return-value]


def _spindle_analog(mlc: ScanContext) -> None:
    """±10 V (0.01 V units) proportional to the commanded speed, as an analog spindle would need."""
    fwd, rev = mlc.m("SPINDLE1_FWD"), mlc.m("SPINDLE1_REV")
    max_rpm = float(mlc.params.get("max_rpm", 6000.0))
    rpm = min(mlc.d("SPINDLE1_SPEED_CMD") * mlc.d("SPINDLE1_OVERRIDE") / 100.0, max_rpm)
    sign = 1 if fwd and not rev else -1 if rev and not fwd else 0
    mlc.put("SPINDLE_ANALOG_1", int(round(sign * rpm / max_rpm * 1000)))
