"""A virtual EtherCAT line whose master went silent (killed, stalled past the SM watchdog, cable cut): the
slaves' own time runs on, so a drive in motion brakes on its communication fault reaction to standstill and
drops its power stage, and digital outputs go off, as real ones do with nobody in charge (decision E33).
`hil sim ethercat --verbose` logs each step. No root needed: the chain is driven in-process."""

from __future__ import annotations

import time

from fieldbus.cia402 import State
from hil.bench import default_lathe
from hil.commands.sim import build_chain
from virtual_bus.ethercat.registers import AL_ERROR, AL_SM_WATCHDOG, R_AL_CODE, R_AL_STATUS

SAFEOP, OP = 4, 8


def _in_op(esc, now_ns: int) -> None:
    """The slave as a master leaves it mid-program: in OP, outputs applied up to now."""
    esc.mem[R_AL_STATUS] = OP
    esc.outputs_written = 1
    esc.last_cycle_ns = esc.last_output_ns = now_ns


def _silent_chain(velocity: float, dio_outputs: int):
    chain = build_chain(default_lathe(), io=1, realtime=True)
    log: list[str] = []
    chain.log = log.append
    x, dio = chain.slaves[0], chain.slaves[-1]
    t0 = time.monotonic_ns() - 2_000_000_000  # the last frame, two seconds ago
    for esc in (x, dio):
        _in_op(esc, t0)
    d = x.app.drive
    d.state, d.velocity, d.position = State.OPERATION_ENABLED, velocity, 1_000_000.0
    dio.app.outputs = dio_outputs
    # the watchdog as `check_watchdog` trips it (the SM settings a master writes are not there in-process)
    for esc in (x, dio):
        esc.al_error(AL_SM_WATCHDOG, SAFEOP, ": no process data for 100 ms")
    return chain, x, dio, log


def test_a_moving_drive_brakes_to_standstill_on_its_ramp_with_no_master():
    v = 2.0e6  # counts/s
    chain, x, dio, log = _silent_chain(v, dio_outputs=0x5)
    d = x.app.drive
    chain.tick()
    assert d.state is State.FAULT and d.error_code == 0x7500 and abs(d.velocity) < 1.0
    # braked on the quick-stop ramp (0x6085): v²/2a further on, within the ramp's first cycle
    decel = d.params.quick_stop_decel
    travelled = d.position - 1_000_000.0
    assert abs(travelled - v * v / (2 * decel)) < v * x.cycle_time, travelled
    assert x.mem[R_AL_STATUS] == SAFEOP | AL_ERROR and int.from_bytes(x.mem[R_AL_CODE:R_AL_CODE + 2], "little") == 0x1B
    assert dio.app.outputs == 0
    assert log[0] == "X: AL status 0x001B (Sync manager watchdog): no process data for 100 ms -> SAFE-OP + ERROR"
    braked = [m for m in log if m.startswith("X: drive braked")]
    assert braked and f"from {v:.0f} counts/s to standstill in 0.010 s" in braked[0] and "FAULT 0x7500" in braked[0]
    assert "DIO1: outputs off (were 0x5): their safe state with no master" in log
    # standing in FAULT: nothing more to log, and the position stays
    pos, n = d.position, len(log)
    chain.tick()
    assert d.position == pos and len(log) == n


def test_a_drive_at_rest_just_faults_and_untouched_outputs_say_nothing():
    chain, x, dio, log = _silent_chain(0.0, dio_outputs=0)
    chain.tick()
    assert x.app.drive.state is State.FAULT
    assert any(m.startswith("X: drive at standstill on its communication fault reaction") for m in log)
    assert not any("outputs off" in m for m in log)


def test_a_slave_still_in_op_is_the_masters_not_coasted():
    """Silence alone is not a fault: until the watchdog trips, a slave in OP keeps its master's last outputs."""
    chain = build_chain(default_lathe(), io=1, realtime=True)
    log: list[str] = []
    chain.log = log.append
    x = chain.slaves[0]
    _in_op(x, time.monotonic_ns() - 2_000_000_000)
    d = x.app.drive
    d.state, d.velocity = State.OPERATION_ENABLED, 2.0e6
    chain.tick()
    assert d.state is State.OPERATION_ENABLED and d.velocity == 2.0e6 and not log


def test_a_drive_already_braking_when_the_line_went_silent_is_logged_from_its_speed_then():
    """A master that read the slave after the trip had begun the fault reaction frame by frame; with the line
    silent from then on, the log still gives the speed the drive braked from when the master went."""
    chain, x, _, log = _silent_chain(2.0e6, dio_outputs=0)
    d = x.app.drive
    d.fault(0x7500)  # as a read with `lost` starts it
    chain.tick()
    assert d.state is State.FAULT
    assert any(m.startswith("X: drive braked from 2000000 counts/s to standstill") for m in log), log
