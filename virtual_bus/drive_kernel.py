"""The sim drive's per-cycle arithmetic, compiled where it can be (issue 17).

A drive's cycle is four sub-steps of a position loop and a first-order velocity loop (virtual_bus/drive.py), then
its feedback as integers. On the shared 2-vCPU box that arithmetic, run in the interpreter, was the largest part
of a stretched cycle (≈ 2-3 µs a drive a cycle: the lathe demo's "bus + drives" 4.5 µs of its 16). Here it is
plain Python, and `setup.py` compiles this very file with Cython (typed by `drive_kernel.pxd`, floats as C
doubles, no fused multiply-add: `-ffp-contract=off`), so each operation rounds as in Python: the compiled module
and this source give the same bits (tests/test_drive_kernel.py runs both). Without a compiler the install keeps
the source (`virtual_bus.kernels` says which one runs).

- `csp_substeps` / `csv_substeps`: one cycle's sub-steps of an enabled drive following CSP targets or its CSV
  ramp, off its limit switches (Cia402Drive._step_following, and CspRun/CsvRun below);
- `csp_cycles` / `csv_cycles`: a stretch's cycles of CspRun.step / CsvRun.step (virtual_bus/drive_stretch.py): the
  sub-steps, the supervision's two tests, the torque and the feedback columns, cycle after cycle;
- `repeat`, `at_speed`, `same`: a cycle repeated, a spindle at its speed, two states equal bit for bit;
- `nearest`, `coulomb_of`: Python's round() and the friction term on C doubles (no Python call a value compiled);
- `to_counts`: the drives' target counts of a stretch's setpoints (AxisScaling.to_counts, with `nearest`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

SW_TARGET_REACHED = 0x0400  # fieldbus.cia402.SW_TARGET_REACHED (statusword bit 10); not imported: no import here
RAW_MAX = 0x7FFFFFFF  # 0x606C is an s32
_EXACT = 4503599627370496.0  # 2^52: from there on every double is an integer


def nearest(x: float) -> int:
    """round(x): the nearest int, a half to the even one. Compiled, on C doubles: the builtin's call was ≈ 600
    instructions, four a drive a cycle (decision bench B161). x - floor(x) is exact for every |x| < 2^52 (Sterbenz:
    both within a factor 2, or x within (-1/2, 0) where a rounded fraction can only reach 1/2 from above, which
    rounds the same way); NaN, ±inf and |x| ≥ 2^52 go to the builtin (its value, or its ValueError/OverflowError)."""
    if not -_EXACT < x < _EXACT:
        return round(x)
    f = x // 1.0
    d = x - f
    if d > 0.5 or (d == 0.5 and f % 2.0 != 0.0):
        f += 1.0
    return int(f)


def coulomb_of(coulomb: float, vel: float) -> float:
    """Cia402Drive's Coulomb friction term: copysign(coulomb, vel) above 1 count/s, else 0 (as a comparison: for such
    a velocity its sign is that of vel > 0; math.copysign was a module look-up and a Python call a drive a cycle)."""
    if abs(vel) > 1:
        return abs(coulomb) if vel > 0.0 else -abs(coulomb)
    return 0.0


def to_counts(rows: list, c: int, scales: list, targets: list) -> None:
    """Each axis's 0x607A targets of the setpoints rows[c:] (lists of floats, an axis a column), appended to its list
    in `targets`: AxisScaling.to_counts's round((x - origin) × counts per unit), `nearest` on C doubles, with
    `scales` each axis's (counts per unit, origin) (a stretch over the NC's steps converts a part's rows at once,
    hil/stretch_pass.py `Pass._convert`: a round() call and a list comprehension an axis were ≈ 400 instructions a
    value, decision bench B174)."""
    for i in range(len(targets)):
        cpu, o = scales[i]
        t = targets[i]
        for k in range(c, len(rows)):
            t.append(nearest((rows[k][i] - o) * cpu))


def csp_substeps(n: int, h: float, prev: float, span: float, kff_ff: float, kp: float, pos: float, vel: float,
                 t: float, max_cps: float, alpha: float, limited: bool, lo: float, hi: float
                 ) -> tuple[float, float, float, float, bool]:
    """One CSP cycle's n sub-steps: the interpolated command, the position loop, the velocity loop; returns
    (command, position, velocity, time, whether every sub-step stayed inside the limit switches' range (lo, hi),
    tested only when `limited`: Cia402Drive._step_general's test))."""
    neg = -max_cps
    cmd = prev
    inside = True
    for k in range(1, n + 1):
        cmd = prev + span * k / n
        v_cmd = kff_ff + kp * (cmd - pos)
        if not neg <= v_cmd <= max_cps:
            v_cmd = max(neg, min(max_cps, v_cmd))
        if v_cmd != vel:
            vel += (v_cmd - vel) * alpha
        pos = pos + vel * h
        if limited and not lo < pos < hi:
            inside = False
        t += h
    return cmd, pos, vel, t, inside


def csv_substeps(n: int, h: float, ramp: float, want: float, tv: float, pos: float, vel: float, t: float,
                 max_cps: float, alpha: float, every: int) -> tuple[float, float, float, float, float, bool]:
    """One CSV cycle's n sub-steps: the ramp towards 0x60FF, the velocity loop; the command follows the actual
    position. Returns (command, position, velocity, time, ramped target velocity, whether a sub-step passed an
    encoder index edge, tested only when `every` (counts between index pulses) is not 0: Cia402Drive._probe)."""
    neg = -max_cps
    cmd = pos
    edge = False
    for _k in range(n):
        tv += max(-ramp, min(ramp, want - tv))
        v_cmd = tv
        cmd = pos
        if not neg <= v_cmd <= max_cps:
            v_cmd = max(neg, min(max_cps, v_cmd))
        if v_cmd != vel:
            vel += (v_cmd - vel) * alpha
        new_pos = pos + vel * h
        if every and math.floor(pos / every) != math.floor(new_pos / every):
            edge = True
        pos = new_pos
        t += h
    return cmd, pos, vel, t, tv, edge


class Stretch:
    """Feedback per cycle of the cycles done (`done` ≤ len(targets)); `last` is the last cycle's TxPdo (re-exported
    by virtual_bus/drive_stretch.py). Here, not there, so that the compiled kernel reads and writes its fields as
    typed C fields (drive_kernel.pxd; a generic attribute look-up ≈ 170 instructions, 9 a csp_cycles call: issue 17,
    decision bench B196)."""

    def __init__(self, done: int = 0, position_actual: list[int] | None = None,
                 velocity_actual: list[int] | None = None, torque_actual: list[int] | None = None,
                 following_error: list[int] | None = None, statusword: list[int] | None = None,
                 last: object = None, limit: float = math.inf, over_at: int = -1) -> None:
        self.done = done
        self.position_actual = [] if position_actual is None else position_actual
        self.velocity_actual = [] if velocity_actual is None else velocity_actual
        self.torque_actual = [] if torque_actual is None else torque_actual
        self.following_error = [] if following_error is None else following_error
        self.statusword = [] if statusword is None else statusword
        self.last = last
        # the bench's overspeed bound on 0x606C (App. A 0x0602; inf: none) and the first cycle above it (-1: none),
        # which csp_cycles keeps as it writes the cycles (a pass checks it a part at a time)
        self.limit = limit
        self.over_at = over_at


def csp_cycles(targets: Sequence[int], consts: tuple, state: tuple, still: object, out: Stretch
               ) -> tuple[tuple, object, bool]:
    """CspRun.step's loop (`CspCore.cycles`) over `targets` from `state`: one cycle per target, feedback appended to
    `out`'s columns (and `out.over_at` set: the first cycle above `out.limit`); stops before a cycle that would fault
    (a limit switch, the following error window, overspeed: exchange() takes it). Returns (state, the target of a
    cycle that left the drive as it found it or None, whether it ran to the end)."""
    core = CspCore(consts, state, out)
    core.still = still
    ok = core.cycles(targets if type(targets) is list else list(targets), 0, len(targets))
    return core.state(), core.still, ok


class CspCore:
    """A CSP drive's constants and state between the parts a stretch steps it over (virtual_bus/drive_stretch.py
    `CspRun`, hil/stretch_pass.py): typed C fields where compiled (drive_kernel.pxd), so a part costs its cycles, not
    a tuple of 21 constants and one of 7 state values taken apart and made again, nor a Python call (issue 17,
    decision bench B198). `consts`: the sub-step factors, gains, units, load, the limit switches' range and whether
    one is set (CspRun); `state`: position, velocity, time, command, last target (None: none yet), acceleration,
    torque. `still`: the target of a cycle that left the drive as it found it (None: not so); `lag`: still cycles
    counted in out.done, not written yet; `ok` False once a part stopped before a faulting cycle."""

    def __init__(self, consts: tuple, state: tuple, out: Stretch) -> None:
        (self.n, self.h, self.max_cps, self.alpha, self.rad, self.reached_v, self.kp, self.kff, self.window,
         self.origin, self.k_raw, self.t_pct, self.inertia, self.viscous, self.coulomb, self.rated, self.lo, self.hi,
         self.base, self.dt, self.limited) = consts
        self.set_state(state)
        self.out = out
        self.still = None
        self.ok = True
        self.lag = 0

    def set_state(self, state: tuple) -> None:
        prev_target: object
        self.pos, self.vel, self.t, self.command, prev_target, self.acc, self.torque = state
        # the last target as a C double (`has_prev`: there is one), boxed only by state(): not a float object a cycle
        self.has_prev = prev_target is not None
        self.last_target = prev_target if prev_target is not None else 0.0

    def state(self) -> tuple:
        """(position, velocity, time, command, last target or None, acceleration, torque)."""
        return (self.pos, self.vel, self.t, self.command, self.last_target if self.has_prev else None, self.acc,
                self.torque)

    def step(self, targets: list, a: int, b: int) -> None:
        """The cycles of targets[a:b], one per target; stops (for good) before a cycle that would fault."""
        if b <= a or not self.ok:
            return
        still = self.still
        if still is not None:
            k = a
            while k < b and targets[k] == still:
                k += 1
            if k == b:  # a standing axis (Z in an XY contour): no loop, written later (settle)
                self.lag += b - a
                self.out.done += b - a
                return
        if self.lag:
            self.settle()
        self.ok = self.cycles(targets, a, b)

    def settle(self) -> None:
        """The still cycles counted (`lag`) written: the cycle that left the drive as it found it (_same), again, its
        time summed on."""
        self.t = repeat(self.out, self.t, self.h, self.n, True, self.lag)
        self.out.done = len(self.out.position_actual)
        self.lag = 0

    def cycles(self, targets: list, a: int, b: int) -> bool:
        """The cycles of targets[a:b] (the still cycles' repeat included); False where it stopped before a cycle
        that would fault."""
        n, h, max_cps, alpha, rad, reached_v = self.n, self.h, self.max_cps, self.alpha, self.rad, self.reached_v
        kp, kff, window, origin, k_raw, t_pct = self.kp, self.kff, self.window, self.origin, self.k_raw, self.t_pct
        inertia, viscous, coulomb, rated = self.inertia, self.viscous, self.coulomb, self.rated
        lo, hi, base, dt, limited = self.lo, self.hi, self.base, self.dt, self.limited
        pos, vel, t, command, acc, torque = self.pos, self.vel, self.t, self.command, self.acc, self.torque
        has_prev, last_target, still = self.has_prev, self.last_target, self.still
        out = self.out
        pa, va, ta, fe, sws = out.position_actual, out.velocity_actual, out.torque_actual, out.following_error, \
            out.statusword
        over = 1.2 * max_cps
        neg = -max_cps
        # the bench's overspeed bound (App. A 0x0602, `Stretch.limit`): the first cycle whose 0x606C is above it is
        # kept in `Stretch.over_at`, so a caller stepping a part at a time (hil/stretch_pass.py) does not scan them
        lim = out.limit
        first = out.over_at
        ok = True
        rep = 0  # still cycles not written yet: a run of them is written at once (repeat)
        for j in range(a, b):
            tgt = targets[j]
            if still is not None and tgt == still:  # the same target again after a cycle that changed nothing: the
                rep += 1  # same cycle, the time on
                continue
            if rep:
                t = repeat(out, t, h, n, True, rep)
                rep = 0
            target = float(tgt) - origin
            prev = last_target if has_prev else command
            ff_vel = (target - prev) / dt
            kff_ff = kff * ff_vel
            span = target - prev
            # csp_substeps, inline (the same operations in the same order): its tuple of five made and taken apart
            # a cycle was ≈ 400 instructions compiled (issue 17, decision bench B196)
            cmd = prev
            c_pos, c_vel, c_t = pos, vel, t
            inside = True
            for k in range(1, n + 1):
                cmd = prev + span * k / n
                v_cmd = kff_ff + kp * (cmd - c_pos)
                if not neg <= v_cmd <= max_cps:
                    v_cmd = max(neg, min(max_cps, v_cmd))
                if v_cmd != c_vel:
                    c_vel += (v_cmd - c_vel) * alpha
                c_pos = c_pos + c_vel * h
                if limited and not lo < c_pos < hi:
                    inside = False
                c_t += h
            if not inside or abs(cmd - c_pos) > window or abs(c_vel) > over:
                ok = False
                break
            moved = not (c_pos == pos and c_vel == vel and has_prev and target == last_target)
            before = None if moved else (pos, vel, command, last_target, acc, torque)
            c_acc = (c_vel - vel) / dt
            # Cia402Drive.step's torque of an energised drive (0.1 % of rated), DriveUnits.velocity_to_raw
            torque = (inertia * c_acc * rad + viscous * c_vel * rad
                      + coulomb_of(coulomb, c_vel)) / rated * 1000.0
            pos, vel, t, command, acc, last_target, has_prev = c_pos, c_vel, c_t, cmd, c_acc, target, True
            gap = command - pos
            sws.append(base | SW_TARGET_REACHED if abs(vel) < reached_v and abs(gap) < 10 else base)
            pa.append(nearest(pos + origin))  # (round of a float: an int)
            raw = nearest(vel * k_raw)
            v_raw = raw if -RAW_MAX <= raw <= RAW_MAX else max(-RAW_MAX, min(RAW_MAX, raw))
            va.append(v_raw)
            if first < 0 and (v_raw > lim or -v_raw > lim):
                first = len(va) - 1  # (a still cycle repeats the last one: never the first above the bound)
            ta.append(nearest(torque * 0.1 / t_pct))
            fe.append(nearest(gap))
            still = tgt if before is not None and same(before, (pos, vel, command, last_target, acc, torque)) \
                else None
        if rep:
            t = repeat(out, t, h, n, True, rep)
        out.over_at = first
        out.done = len(pa)  # (step settles its still cycles before: every cycle stepped is written)
        self.pos, self.vel, self.t, self.command, self.acc, self.torque = pos, vel, t, command, acc, torque
        self.has_prev, self.last_target, self.still = has_prev, last_target, still
        return ok


def drive_parts(runs: list, targets: list, a: int, upto: int, n_axes: int) -> int:
    """hil/stretch_pass.py `Pass._drive`'s loop: each drive over cycles a … upto-1 (a `CspCore` over its axis's
    targets[i][a:upto], else a CsvRun, or a CspRun that cannot stretch, by its own step); the first cycle a drive
    stops before (its `done`) or whose 0x606C is above the bench's bound (its `over_at`), else upto (decision bench
    B198: a Python call and a list slice a drive a part were most of a part's drive cost)."""
    m = upto
    for i in range(len(runs)):
        run = runs[i]
        if type(run) is CspCore:
            core = run
            core.step(targets[i], a, upto)
            out = core.out
        else:
            run.step(targets[i][a:upto] if i < n_axes else upto - a)
            out = run.out
        if out.done < m:
            m = out.done
        if 0 <= out.over_at < m:
            m = out.over_at
    return m


def csv_cycles(cycles: int, consts: tuple, state: tuple, still: bool, out: Stretch) -> tuple[tuple, bool, bool]:
    """CsvRun.step's loop: `cycles` cycles of a CSV drive at its 0x60FF speed; stops before a cycle that would
    latch the encoder index or overspeed. Returns (state, whether the last cycle left the drive as it found it,
    whether it ran to the end)."""
    n, h, max_cps, alpha, rad, reached_v, origin, ramp, want, every, k_raw, t_pct, inertia, viscous, coulomb, \
        rated, base, dt = consts
    pos, vel, t, command, tv, acc, torque = state
    pa, va, ta, sws = out.position_actual, out.velocity_actual, out.torque_actual, out.statusword
    neg, over = -max_cps, 1.2 * max_cps
    ok = True
    c = 0
    while c < cycles:
        if still:  # a standing spindle (a mill's CAM program): the same cycle from here on, the time on
            t = repeat(out, t, h, n, False, cycles - c)
            break
        v_cmd = tv if neg <= tv <= max_cps else max(neg, min(max_cps, tv))
        if tv == want and tv != 0.0 and vel != 0.0 and ramp >= 0.0 and abs(vel) <= over \
                and (v_cmd == vel or vel + (v_cmd - vel) * alpha == vel):
            # at its speed (the ramp's step 0, the velocity loop's step none, or under half an ulp: a velocity
            # 7e-9 short of 2.56e7 counts/s stays): only the position and the time move, as far as the cycles
            # move it and pass no index edge
            c_acc = (vel - vel) / dt
            c_torque = (inertia * c_acc * rad + viscous * vel * rad
                        + coulomb_of(coulomb, vel)) / rated * 1000.0
            raw = nearest(vel * k_raw)
            done, pos, t, command = at_speed(out, cycles - c, pos, t, command, vel * h, h, n, every,
                                             raw if -RAW_MAX <= raw <= RAW_MAX else max(-RAW_MAX, min(RAW_MAX, raw)),
                                             nearest(c_torque * 0.1 / t_pct), base, abs(vel) < reached_v, origin)
            if done:
                acc, torque = c_acc, c_torque
                c += done
                if c == cycles:
                    break
        c += 1
        cmd, c_pos, c_vel, c_t, c_tv, edge = csv_substeps(n, h, ramp, want, tv, pos, vel, t, max_cps, alpha, every)
        if edge or abs(c_vel) > over:
            ok = False
            break  # the index latches in this cycle, or overspeed: exchange() takes it
        moved = not (c_pos == pos and c_vel == vel and c_tv == tv)
        before = None if moved else (pos, vel, command, tv, acc, torque)
        c_acc = (c_vel - vel) / dt
        torque = (inertia * c_acc * rad + viscous * c_vel * rad
                  + coulomb_of(coulomb, c_vel)) / rated * 1000.0
        pos, vel, t, command, tv, acc = c_pos, c_vel, c_t, cmd, c_tv, c_acc
        sws.append(base | SW_TARGET_REACHED if abs(vel) < reached_v and abs(command - pos) < 10 else base)
        pa.append(nearest(pos + origin))
        raw = nearest(vel * k_raw)
        va.append(raw if -RAW_MAX <= raw <= RAW_MAX else max(-RAW_MAX, min(RAW_MAX, raw)))
        ta.append(nearest(torque * 0.1 / t_pct))
        still = before is not None and same(before, (pos, vel, command, tv, acc, torque))
    return (pos, vel, t, command, tv, acc, torque), still, ok


def repeat(out: Stretch, t: float, h: float, n: int, csp: bool, times: int) -> float:
    """The last cycle's feedback `times` more times (`same`), and the time after their n sub-steps each (summed one
    sub-step at a time, as they sum it)."""
    for col in (out.statusword, out.position_actual, out.velocity_actual, out.torque_actual):
        col += [col[-1]] * times
    if csp:  # (CSV fills 0x60F4 after the part)
        out.following_error += [out.following_error[-1]] * times
    for _k in range(n * times):
        t += h
    return t


def at_speed(out: Stretch, cycles: int, pos: float, t: float, command: float, dp: float, h: float, n: int,
             every: int, va_raw: int, ta_raw: int, base: int, slow: bool, origin: float
             ) -> tuple[int, float, float, float]:
    """csv_cycles' cycles of a spindle at its speed: each sub-step moves the position by dp (its velocity × h, the
    same product) and the time by h; velocity, torque and status bits stay. As many cycles as move the position
    and pass no index edge (that cycle is csv_cycles' own): (cycles done, position, time, command after them)."""
    pa, va, ta, sws = out.position_actual, out.velocity_actual, out.torque_actual, out.statusword
    done = 0
    while done < cycles:
        c_pos, c_t, cmd = pos, t, command
        edge = False
        for _k in range(n):
            cmd = c_pos
            new_pos = c_pos + dp
            if every and math.floor(c_pos / every) != math.floor(new_pos / every):
                edge = True
            c_pos = new_pos
            c_t += h
        if edge or c_pos == pos:
            break
        pos, t, command = c_pos, c_t, cmd
        sws.append(base | SW_TARGET_REACHED if slow and abs(command - pos) < 10 else base)
        pa.append(nearest(pos + origin))
        va.append(va_raw)
        ta.append(ta_raw)
        done += 1
    return done, pos, t, command


def same(a: tuple, b: tuple) -> bool:
    """The same values bit for bit (a zero's sign too): a cycle that starts from `b` as it did from `a` computes the
    same (the time aside, which only adds up), so a cycle that ended where it started repeats itself exactly."""
    return all(type(x) is type(y) and x == y
               and (type(x) is not float or x != 0.0 or math.copysign(1.0, x) == math.copysign(1.0, y))
               for x, y in zip(a, b))
