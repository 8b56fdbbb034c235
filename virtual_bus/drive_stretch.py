"""A CSP drive stepped over a stretch of cycles at once (issue 17: "the sim drives step over the stretch").

`csp_stretch(drive, rx, targets, dt)` (and `csv_stretch(drive, rx, cycles, dt)` for a spindle) does what `drive.exchange(rx, dt)` does once per target, for an
enabled CSP drive whose master holds enable operation, without limit switches, touch probe or injected
fault: the same arithmetic in the same order (Cia402Drive.step → _step_following, feedback), in
virtual_bus/drive_kernel.py's loops (compiled at install, decision bench B113), with no PDO objects per cycle. It stops before the first cycle that would fault (following
error window, overspeed): that cycle is left to `exchange`, which takes the fault as always. The CSP
model's sub-step recurrence is sequential, so this is a loop, not a filter: a filter over the stretch
(lfilter) would round differently and could flip an integer count.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from fieldbus.cia402 import SW_FOLLOWING, State
from fieldbus.pdo import RxPdo, TxPdo
from virtual_bus.kernels import drive_kernel
from virtual_bus.drive import AL_FORWARD_LIMIT, AL_REVERSE_LIMIT, _STATUS_BASE, Cia402Drive, DriveParams

Stretch = drive_kernel.Stretch  # the feedback of a stretch's cycles (typed fields where the kernel is compiled, B196)

ENABLE_HELD = 0x0F  # controlword bits 0-3 (and not 7) of enable operation


def can_stretch(drive: Cia402Drive, rx: RxPdo, mode: int = 8) -> bool:
    """The drive runs the plain CSP (mode 8) or CSV (9) path the stretch reproduces. CSV may have its touch
    probe armed on the encoder index (a spindle's thread sync): a latched probe waits, unchanged; one not
    latched yet (a spindle running up, or standing in a mill's CAM program without M03) latches in the cycle
    whose sub-steps pass an index edge (Cia402Drive._probe), before which csv_stretch stops."""
    p = drive.params
    cw = rx.controlword
    probe_ok = not rx.touch_probe_function & 1 or (mode == 9 and (drive._probe_latched or p.probe_position is None))
    return (drive.state is State.OPERATION_ENABLED and drive.mode == mode and rx.mode == mode
            and not drive.external_fault and cw == drive._last_cw and cw & 0x8F == ENABLE_HELD
            and (mode == 8 or (p.negative_limit is None and p.positive_limit is None)) and probe_ok)


def csp_stretch(drive: Cia402Drive, rx: RxPdo, targets: Sequence[int], dt: float) -> Stretch:
    """Step `drive` once per target position (0x607A counts) as exchange() would; see the module doc."""
    run = CspRun(drive, rx, dt)
    run.step(targets)
    return run.finish()


def csv_stretch(drive: Cia402Drive, rx: RxPdo, cycles: int, dt: float) -> Stretch:
    """Step a CSV drive (a spindle at its 0x60FF speed) `cycles` times as exchange(rx, dt) would."""
    run = CsvRun(drive, rx, dt)
    run.step(cycles)
    return run.finish()


class CspRun:
    """csp_stretch a part at a time (a stretch that runs the NC's steps, hil/stretch_pass.py): the drive's state is
    carried here from one `step` to the next and written to the drive by `finish`, so a part costs its cycles
    and not the set-up and the TxPdo of a call (issue 17: a CAM pass steps its drives ≈ 14 times). `out` holds
    every cycle stepped; a part that stops before a faulting cycle leaves the run stopped (`ok` False)."""

    def __init__(self, drive: Cia402Drive, rx: RxPdo, dt: float) -> None:
        self.drive, self.rx, self.dt = drive, rx, dt
        self.out = Stretch()
        # the drive's constants and state from part to part, and the part's loop (drive_kernel.CspCore, typed C
        # fields where compiled: decision bench B198); None where the drive cannot stretch
        self.core: drive_kernel.CspCore | None = None
        if not can_stretch(drive, rx):
            return
        p = drive.params
        units, cpr = p.units, p.counts_per_rev
        model = _model(p, dt)
        gains = (p.kp, p.kff, p.following_error_window, drive.modes.origin)
        k_units = (units.raw_per_count_per_s(cpr), units.torque_percent)  # velocity_to_raw, 0x6077
        load = (p.inertia, p.viscous, p.coulomb, p.rated_torque)
        # limit switches (Cia402Drive._limit): a cycle that would reach one is left to exchange(); short of them
        # the limited drive's sub-steps are the plain ones
        lo = float(p.negative_limit) if p.negative_limit is not None else -math.inf
        hi = float(p.positive_limit) if p.positive_limit is not None else math.inf
        # the sub-step factors, gains, units, load, the limit switches' range and whether one is set
        consts = (*model, *gains, *k_units, *load, lo, hi, _STATUS_BASE[State.OPERATION_ENABLED] | SW_FOLLOWING, dt,
                  lo > -math.inf or hi < math.inf)
        state = (drive.position, drive.velocity, drive.time, drive.command, drive._prev_target, drive.acceleration,
                 drive.torque)
        self.core = drive_kernel.CspCore(consts, state, self.out)

    @property
    def ok(self) -> bool:
        """The drive can stretch and no part stopped before a faulting cycle."""
        return self.core is not None and self.core.ok

    @property
    def still(self) -> int | None:
        """The target of a cycle that left the drive as it found it (drive_kernel.same), None: not so."""
        return None if self.core is None else self.core.still

    def step(self, targets: Sequence[int]) -> None:
        """The next cycles, one per target; stops (for good) before a cycle that would fault. A standing axis's
        parts (Z through an XY contour, ≈ 1,400 parts of 1-10 cycles in the CAM program) cost a count, written
        later (CspCore.lag)."""
        if self.core is not None:
            self.core.step(targets if type(targets) is list else list(targets), 0, len(targets))

    def finish(self) -> Stretch:
        """The drive's state after the last cycle stepped, and that cycle's TxPdo (`out.last`)."""
        core, out = self.core, self.out
        if core is None:
            return out
        if core.lag:
            core.settle()
        if out.position_actual:
            pos, vel, t, command, prev_target, acc, torque = core.state()
            self.drive._prev_target = prev_target
            _finish(self.drive, self.rx, out, pos, vel, t, command, acc, torque)
        return out


class CsvRun:
    """csv_stretch a part at a time, as CspRun."""

    def __init__(self, drive: Cia402Drive, rx: RxPdo, dt: float) -> None:
        self.drive, self.rx, self.dt = drive, rx, dt
        self.out = Stretch()
        self.lag = 0  # still cycles counted in out.done, not written yet (as CspRun.lag: a mill's standing spindle)
        self.ok = can_stretch(drive, rx, 9)
        if not self.ok:
            return
        p = drive.params
        units, cpr = p.units, p.counts_per_rev
        self.model = _model(p, dt)
        self.want = units.raw_to_velocity(rx.target_velocity, cpr)  # apply()'s latch of 0x60FF
        self.units = (units.raw_per_count_per_s(cpr), units.torque_percent)  # as in CspRun
        self.load = (p.inertia, p.viscous, p.coulomb, p.rated_torque)
        self.origin, self.ramp = drive.modes.origin, p.csv_accel * self.model[1]
        # the encoder index armed and not latched yet (Cia402Drive._probe): the stretch ends before the cycle
        # whose sub-steps pass an index edge, which exchange() latches
        self.every = (p.index_pulse_every or cpr) if rx.touch_probe_function & 1 and not drive._probe_latched else 0
        self.state = (drive.position, drive.velocity, drive.time, drive.command, drive.target_velocity,
                      drive.acceleration, drive.torque)
        self.still = False  # the last cycle left the drive as it found it (`same`): the next ones are the same
        self.consts = (*self.model, self.origin, self.ramp, self.want, self.every, *self.units, *self.load,
                       _STATUS_BASE[State.OPERATION_ENABLED] | SW_FOLLOWING, dt)  # drive_kernel.csv_cycles'

    def step(self, cycles: int) -> None:
        """The next `cycles` cycles; stops (for good) before a cycle that would fault or latch the index."""
        if cycles <= 0 or not self.ok:
            return
        if self.still:  # a standing spindle (a mill's CAM program): no set-up, no loop, written at finish()
            self.lag += cycles
            self.out.done += cycles
            return
        self.state, self.still, self.ok = drive_kernel.csv_cycles(cycles, self.consts, self.state, False, self.out)
        out = self.out
        pa = out.position_actual
        out.following_error += [0] * (len(pa) - len(out.following_error))  # 0x60F4 is a CSP object: 0 in CSV
        out.done = len(pa)

    def finish(self) -> Stretch:
        """The drive's state after the last cycle stepped, and that cycle's TxPdo (`out.last`)."""
        if self.lag:  # (a still spindle stays still: its lag is written here, once)
            _stand(self, self.lag, False)
            self.lag = 0
        out = self.out
        if out.position_actual:
            pos, vel, t, command, tv, acc, torque = self.state
            self.drive.target_velocity = tv
            _finish(self.drive, self.rx, out, pos, vel, t, command, acc, torque)
        return out


def _stand(run: "CsvRun", cycles: int, csp: bool) -> None:
    """A still drive's next cycles (`lag`, written by CsvRun.finish; a CSP drive's by CspCore.settle): its feedback
    repeated, its time summed on."""
    n, h = run.model[0], run.model[1]
    state = run.state
    out = run.out
    run.state = (*state[:2], drive_kernel.repeat(out, state[2], h, n, csp, cycles), *state[3:])
    if not csp:  # 0x60F4 is a CSP object: 0 in CSV (as CsvRun.step fills it)
        out.following_error += [0] * (len(out.position_actual) - len(out.following_error))
    out.done = len(out.position_actual)


def _model(p: DriveParams, dt: float) -> tuple[int, float, float, float, float, float]:
    """Cia402Drive.step's per-cycle constants, by the same expressions: sub-steps, sub-step, speed limit,
    velocity-loop gain, counts → rad, and the speed under which the target counts as reached."""
    n = max(1, p.substeps)
    h = dt / n
    max_cps = p.max_speed_rpm / 60.0 * p.counts_per_rev
    return (n, h, max_cps, 1.0 - math.exp(-p.velocity_bandwidth * h), 2.0 * math.pi / p.counts_per_rev,
            0.001 * (p.max_speed_rpm / 60.0 * p.counts_per_rev))


def _finish(drive: Cia402Drive, rx: RxPdo, out: Stretch, pos: float, vel: float, t: float, command: float,
            acc: float, torque: float) -> None:
    """The drive's state after the stretch's last cycle, and that cycle's TxPdo as feedback() builds it."""
    p = drive.params
    out.done = len(out.position_actual)
    drive._rx = rx
    drive._want_cps = p.units.raw_to_velocity(rx.target_velocity, p.counts_per_rev)  # apply()'s latch of 0x60FF
    drive.position, drive.velocity, drive.time, drive.command = pos, vel, t, command
    drive.acceleration, drive.torque = acc, torque
    drive._limit_flags = 0  # _no_limit, _step_following's tail
    if drive.error_code in (AL_REVERSE_LIMIT, AL_FORWARD_LIMIT):
        drive.error_code = 0
    probing = bool(rx.touch_probe_function & 1)
    if not probing:
        drive._probe_latched = False
    di = 0x4 if p.home_switch is not None and pos < p.home_switch else 0
    origin = drive.modes.origin
    out.last = TxPdo(statusword=out.statusword[-1], position_actual=out.position_actual[-1],
                     velocity_actual=out.velocity_actual[-1], torque_actual=out.torque_actual[-1],
                     following_error=out.following_error[-1], error_code=drive.error_code, mode_display=drive.mode,
                     touch_probe_status=0x0003 if drive._probe_latched else (0x0001 if probing else 0),
                     touch_probe_pos1=drive._probe_pos + int(round(origin)), digital_inputs=di)
