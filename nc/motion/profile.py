"""Jerk-limited profiles solved once by ruckig and sampled for many cycles at once.

A ruckig `Trajectory` is piecewise constant in jerk; `Piecewise` copies its phases (brake
pre-phases, then the seven main phases) into numpy arrays so a whole chunk of cycles is
evaluated in one vectorised polynomial step instead of one `at_time` call per cycle.

Never pass intermediate positions to ruckig: the community build sends those to a web service.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import ruckig
from ruckig import ControlInterface, InputParameter, Result, Ruckig, Synchronization, Trajectory

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.alarms import NcAlarm
from nc.motion.block import Block
from nc.motion.compiled import direct_ruckig


def clip(x: np.ndarray | float, lo: float, hi: float) -> np.ndarray | np.floating:
    """np.clip(x, lo, hi) for non-empty arrays and scalars, bit for bit (the same comparisons: NaN kept, lo
    or hi returned on a tie, so 0.0 for −0.0), without np.clip's Python dispatch (≈ 1.5 µs a call; the
    planner samples with it several times a cycle, issue 17)."""
    return np.minimum(hi, np.maximum(lo, x))


_OK = (Result.Working, Result.Finished)
# ruckig's control interfaces, read once (each read of an enum member through its class is ≈ 1k instructions)
_POSITION, _VELOCITY = ControlInterface.Position, ControlInterface.Velocity
_POOL: dict[int, tuple[Ruckig, InputParameter]] = {}  # one calculator per DoF count, never per cycle
# The control interface `_one_dof` last set on the pooled 1-DoF input (with synchronisation Time and target
# acceleration 0); `solve_axes` drops its entry where it sets those fields itself
_MODE: dict[int, ControlInterface] = {}


def _calc(dofs: int) -> tuple[Ruckig, InputParameter]:
    if dofs not in _POOL:
        _POOL[dofs] = (Ruckig(dofs), InputParameter(dofs))
    return _POOL[dofs]


# The floats `_one_dof` last wrote to the pooled 1-DoF input, in its order (p0, v0, a0, p1, v1, v_max, a_max, j_max):
# a field holding the same double already is not written again (≈ 0.6k instructions a field through pybind, issue
# 17, session 28). NaN where unknown: `_calculate`'s retries and `solve_axes` write those fields themselves.
_WROTE: list[float] = [math.nan] * 8
# One Trajectory per DoF count, filled by every calculate (as ruckig's own update() refills its output's): a solve
# reads its phases out before the next (Trajectory(n) was ≈ 1.8k instructions a solve, session 28)
_TRAJ: dict[int, Trajectory] = {}


# ruckig's C++ called directly for the 1-DoF solves (nc/motion/ruckig_direct.pyx, decision bench B162): the same
# calculation and read-back as _one_dof + _calculate + _of, without pybind (≈ 24k instructions a solve, session 28);
# None (solved through the Python module) where it is not built, not current, built for another ruckig, or where
# DELTAHIL_PYTHON_PLANNER=1. RUCKIG says which. Where it is taken, every 1-DoF solve goes through it (solve_axes with
# one axis too): a velocity solve's p_max includes the final position the trajectory's solve before left (ruckig
# keeps no pf for velocity control), so the 1-DoF solves share one trajectory in the same order either way.
_DIRECT, RUCKIG = direct_ruckig(getattr(ruckig, "__version__", ""))


def _same(x: float, y: float) -> bool:
    """x and y the same double: equal and not zero (−0.0 == 0.0: a zero is written again, 149 of the CAM program's
    16,536 fields); NaN never the same."""
    return x == y and x != 0.0


@dataclass
class Piecewise:
    """Phases of a jerk-limited trajectory, one row per DoF: start times and the state there."""

    t0: np.ndarray  # (dofs, phases) phase start times
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    duration: float
    p_max: float = np.inf  # highest position of DoF 0 anywhere on the profile (ruckig's extrema)
    _vmin: tuple[tuple[int, float], float] | None = None  # v_min's last answer, with (dof, duration)
    _lists: tuple | None = None  # DoF 0's phases as plain lists, for `at` (with the duration they were made for)

    @classmethod
    def of(cls, traj: Trajectory) -> "Piecewise":
        return _of(traj, cls)

    @cython.locals(dur=cython.double, low=cython.double, jk=cython.double, ak=cython.double, t_zero=cython.double,
                   x=cython.double, tk=cython.double, tn=cython.double, k=cython.Py_ssize_t, n=cython.Py_ssize_t,
                   t0=list, v=list, a=list, j=list)
    def v_min(self, dof: int = 0) -> float:
        """Lowest velocity anywhere on the profile: at a phase boundary, or inside a phase where
        the acceleration passes zero (v − a²/2j), which the boundaries alone miss."""
        key = (dof, self.duration)
        if self._vmin is not None and self._vmin[0] == key:
            return self._vmin[1]  # the planner asks twice per solve (issue 17)
        # Plain floats: ≈ 10 phases, where numpy's per-call cost was most of the time (same
        # operations in the same order as the array form, so the same result bit for bit).
        dur = self.duration
        c = self._lists
        if dof == 0 and c is not None and c[0] == dur:  # `at`'s lists, the arrays' floats (session 12)
            _, t0, _, v, a, j = c
        else:
            t0, v, a, j = self.t0[dof].tolist(), self.v[dof].tolist(), self.a[dof].tolist(), self.j[dof].tolist()
        # min(v) as the builtin finds it, and the start times held to the duration as each is read (compiled: C
        # loops on C doubles, session 27)
        low = v[0]
        for k in range(1, len(v)):
            x = v[k]
            if x < low:
                low = x
        n = len(t0)
        if n > 1:
            tn = t0[0]
            tn = tn if tn < dur else dur
            for k in range(n - 1):
                tk = tn
                tn = t0[k + 1]
                tn = tn if tn < dur else dur
                jk = j[k]
                if jk != 0.0:
                    ak = a[k]
                    t_zero = -ak / jk
                    if 0.0 < t_zero < tn - tk:
                        x = v[k] - ak * ak / (2.0 * jk)
                        if x < low:
                            low = x
        self._vmin = (key, low)
        return low

    def v_end(self) -> float:
        """DoF 0's velocity at the end of its last phase."""
        return float(self.v[0][-1])

    @cython.locals(c=tuple)
    def at(self, t: float) -> tuple[float, float, float]:
        """sample(np.array([t])) of DoF 0 on plain floats: the same operations in the same order, so the same
        bits (numpy's maximum/minimum keep their first operand on a tie, searchsorted is bisect_right), without
        ~25 numpy calls on 1-element arrays (issue 17: the planner samples a block's one or two rows at a time).
        The work is `_row_at` (compiled: a C function, which sample_rows calls without this method call)."""
        c = _lists0(self)
        return _row_at(t, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])  # (x − 0.0 is x, bit for bit)

    def sample(self, t: np.ndarray, dof: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, velocity, acceleration) of one DoF at times t (clamped to [0, duration])."""
        t = clip(t, 0.0, self.duration)
        t0 = self.t0[dof]
        k = np.searchsorted(t0, t, side="right") - 1
        k = clip(k, 0, len(t0) - 1)
        dt = t - t0[k]
        j = self.j[dof][k]
        a = self.a[dof][k]
        v = self.v[dof][k]
        p = self.p[dof][k]
        pos = p + dt * (v + dt * (a / 2.0 + dt * j / 6.0))
        vel = v + dt * (a + dt * j / 2.0)
        acc = a + dt * j
        return pos, vel, acc


def _lists0(pw: Piecewise) -> tuple:
    """DoF 0's phases as plain lists (duration, t0, p, v, a, j), remade where the duration changed since (the ramp
    fallback stretches duration and t0 after the solve): `at`'s first step, taken once by sample_rows for all its
    probes (issue 17, session 29, decision bench B169)."""
    c = pw._lists
    dur = pw.duration
    if c is None or c[0] != dur:
        c = pw._lists = (dur, pw.t0[0].tolist(), pw.p[0].tolist(), pw.v[0].tolist(), pw.a[0].tolist(),
                         pw.j[0].tolist())
    return c


def _pos_at(t: float, dur: float, t0: list, p: list, v: list, a: list, j: list) -> float:
    """`_row_at(t, 0.0, …)[0]`: the position alone, the same operations (sample_rows' bisection probes; compiled a
    C function on C doubles, nothing boxed)."""
    t = 0.0 if 0.0 >= t else t
    t = dur if dur <= t else t
    k = _first_above(t0, t) - 1  # bisect_right(t0, t) - 1, at least 0
    if k < 0:
        k = 0
    x = t0[k]
    dt = t - x
    jk, ak, vk, pk = j[k], a[k], v[k], p[k]
    return pk + dt * (vk + dt * (ak / 2.0 + dt * jk / 6.0))


def _row_at(t: float, base: float, dur: float, t0: list, p: list, v: list, a: list,
            j: list) -> tuple[float, float, float]:
    """`Piecewise.at(t)` on its lists (from `_lists0`), the position less base: (s − base, v, a)."""
    t = 0.0 if 0.0 >= t else t
    t = dur if dur <= t else t
    k = _first_above(t0, t) - 1  # bisect_right(t0, t) - 1, at least 0 (compiled: on C doubles)
    if k < 0:
        k = 0
    x = t0[k]
    dt = t - x
    jk, ak, vk, pk = j[k], a[k], v[k], p[k]
    return ((pk + dt * (vk + dt * (ak / 2.0 + dt * jk / 6.0))) - base, vk + dt * (ak + dt * jk / 2.0),
            ak + dt * jk)


class _OneDof(Piecewise):
    """One DoF's phases (every path solve) as ruckig gave them: read through `at`, `v_min` and `v_end` as the
    plain lists, the arrays (one array, five (1, phases) views of it: t0[:, -1] written in place changes it) made on
    first use. A solve's plan is mostly sampled a row or two at a time, and np.array of its rows cost ≈ 2 µs a
    solve (issue 17, session 12); the lists hold the floats the arrays would (float64 both ways)."""

    _m: np.ndarray | None = None  # the arrays, once made

    def __init__(self, rows: tuple[list, list, list, list, list], duration: float, p_max: float) -> None:
        self._rows = rows  # (_m and _vmin: None, the class's, until made)
        self.duration = duration
        self.p_max = p_max
        self._lists = (duration, *rows)  # what `at` makes of the arrays

    def _arr(self, k: int) -> np.ndarray:
        m = self._m
        if m is None:
            m = self._m = np.array(self._rows)
        return m[k:k + 1]

    t0 = property(lambda self: self._arr(0))  # type: ignore[assignment]
    p = property(lambda self: self._arr(1))  # type: ignore[assignment]
    v = property(lambda self: self._arr(2))  # type: ignore[assignment]
    a = property(lambda self: self._arr(3))  # type: ignore[assignment]
    j = property(lambda self: self._arr(4))  # type: ignore[assignment]

    def v_end(self) -> float:
        return self._rows[2][-1] if self._m is None else float(self._m[2, -1])


# A kept profile's checks (Planner._kept, decisions motion 83, 85), nc.motion.hold_stop's: on the lists `at` reads
# (`_lists0`), each probe `_row_at` (a C call where compiled: ≈ 60k instructions a kept check as Python calls of
# `at` and reads of Block fields, session 31, decision bench B184). The same operations in the same order.
def time_at(pw: Piecewise, x: float, lo: float = 0.0) -> float:
    """The time at or after lo the profile reaches position x (its position rising from lo to its end): Newton
    steps on the position, bisection where one leaves the bracket."""
    c = _lists0(pw)
    hi = pw.duration
    t = lo
    for i in range(60):
        r = _row_at(t, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])  # pw.at(t)
        ps = r[0]
        vs = r[1]
        if ps < x:
            lo = t
        else:
            hi = t
        if abs(ps - x) <= 1e-13 or hi - lo <= 1e-15:
            break
        t = t - (ps - x) / vs if vs > 1e-12 else -1.0
        if not lo < t < hi:
            t = 0.5 * (lo + hi)
    return t


def peak_speed(pw: Piecewise, t: float) -> float:
    """The highest speed of the profile from time t on: at a phase's ends or where its acceleration passes zero."""
    c = _lists0(pw)  # (pw.at(0.0)'s lists: the phases)
    t0, a, j = c[1], c[4], c[5]
    dur = pw.duration
    top = _row_at(t, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])[1]
    x = _row_at(dur, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])[1]
    if x > top:  # max(top, x), spelt out below too (max keeps the first of equal ones)
        top = x
    n = len(t0)
    for k in range(n):
        lo = t0[k]
        if t > lo:
            lo = t
        hi = t0[k + 1] if k + 1 < n else dur
        if dur < hi:
            hi = dur
        if lo >= hi:
            continue
        x = _row_at(hi, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])[1]
        if x > top:
            top = x
        jk = j[k]
        if jk != 0.0:
            tz = t0[k] - a[k] / jk
            if lo < tz < hi:
                x = _row_at(tz, 0.0, c[0], c[1], c[2], c[3], c[4], c[5])[1]
                if x > top:
                    top = x
    return top


def fits_queue(pw: Piecewise, t: float, end: float, blocks) -> bool:
    """True when a path profile followed from time t still fits the queue up to `end` (the path position in
    blocks[0]): `end` a junction whose planned end speed (`vend`) allows the profile's end speed, and no speed
    of it from t on above a cap of the blocks or a junction speed before `end` (decision motion 83: a profile
    kept where its re-solve in the next block missed)."""
    top = peak_speed(pw, t) * (1.0 - 1e-9) - 1e-12
    at = 0.0
    for b in blocks:
        if b.kind != "path" or b.cap < top:
            return False
        at += b.length
        if abs(at - end) <= 1e-9:
            return pw.v_end() <= b.vend * (1.0 + 1e-9) + 1e-12
        if at > end or b.vjunc < top:
            return False
    return False


def later(pw: Piecewise, t: float) -> Piecewise:
    """A path profile from time t on, its clock starting there (its phases before t start at negative times)."""
    c = _lists0(pw)
    t0 = c[1]
    return _OneDof(([x - t for x in t0], c[2], c[3], c[4], c[5]), pw.duration - t, pw.p_max)


def _of(traj: Trajectory, cls: type) -> "Piecewise":
    """Piecewise.of: a solve's Trajectory as its phases (a C function compiled, called directly by the solves)."""
    rows = [_phases(pr) for pr in traj.profiles[0]]
    if len(rows) == 1:  # one DoF (every path solve): its columns as they are, no padding (issue 17)
        return _OneDof(rows[0], float(traj.duration), float(traj.position_extrema[0].max))
    n = max(len(r[0]) for r in rows)
    arrs = []
    for k in range(5):
        m = np.empty((len(rows), n))
        for i, r in enumerate(rows):
            col = r[k]
            m[i, : len(col)] = col
            # pad with a copy of the final (resting) phase
            m[i, len(col):] = col[-1] if k else np.inf
        arrs.append(m)
    return cls(arrs[0], arrs[1], arrs[2], arrs[3], arrs[4], float(traj.duration),
               float(traj.position_extrema[0].max))


def _first_above(xs: list[float], x: float) -> int:
    """bisect_right(xs, x) on floats, its comparisons as bisect makes them."""
    lo, hi = 0, len(xs)
    while lo < hi:
        mid = (lo + hi) // 2
        y = xs[mid]
        if x < y:
            hi = mid
        else:
            lo = mid + 1
    return lo


def _at_or_above(xs: list[float], x: float, lo: int, hi: int) -> int:
    """bisect_left(xs, x, lo, hi) on floats, its comparisons (xs[mid] < x) as bisect makes them: a C loop where
    compiled (decision bench B153; nc.motion.blending's junction history and nc.motion.shares' scan both search with
    it)."""
    while lo < hi:
        mid = (lo + hi) // 2
        y = xs[mid]
        if y < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


def _gather(t: float, n: int, pt, pp, pv, pa, pj, t0: list, p: list, v: list, a: list, j: list) -> float:
    """Append the first n of a ruckig profile's (or brake's) phases that last (t > 0) to the lists, each starting at
    the time summed so far; the time after them."""
    for k in range(n):
        x = pt[k]
        if x > 0.0:
            t0.append(t)
            p.append(pp[k])
            v.append(pv[k])
            a.append(pa[k])
            j.append(pj[k])
            t += x
    return t


def _phases(pr) -> tuple[list, list, list, list, list]:
    """One DoF's phases of a ruckig Profile as lists: (start times, p, v, a, j), the brake pre-phases first, the
    final state last (a C function compiled, its types in profile.pxd: the floats ruckig gives are appended as
    they are, the start times summed on a C double in the same order; session 27)."""
    t0, p, v, a, j = [], [], [], [], []
    t = 0.0
    # ruckig's fields are read once each: every read converts the whole array to a new list (issue 17)
    b = pr.brake
    if b.duration > 0.0:
        t = _gather(t, 2, b.t, b.p, b.v, b.a, b.j, t0, p, v, a, j)
    pp, pv, pa = pr.p, pr.v, pr.a
    t = _gather(t, 7, pr.t, pp, pv, pa, pr.j, t0, p, v, a, j)  # the phases kept, their start times summed in order
    # The final state, integrated from the last phase (pf is not kept for velocity control).
    if len(t0) > 0:
        h = t - t0[-1]
        pl, vl, al, jl = p[-1], v[-1], a[-1], j[-1]
        pe = pl + h * (vl + h * (al / 2.0 + h * jl / 6.0))
        ve = vl + h * (al + h * jl / 2.0)
        ae = al + h * jl
    else:
        pe, ve, ae = pp[0], pv[0], pa[0]
    t0.append(t)
    p.append(pe)
    v.append(ve)
    a.append(ae)
    j.append(0.0)
    return t0, p, v, a, j


def _one_dof(interface: ControlInterface, p0: float, v0: float, a0: float, p1: float, v1: float,
             v_max: float, a_max: float, j_max: float) -> tuple[Ruckig, InputParameter]:
    """The pooled 1-DoF calculator with its input set: (p0, v0, a0) → (p1, v1, 0) within the limits."""
    otg, inp = _calc(1)
    if _MODE.get(1) is not interface:  # what is set already is not set again (≈ 0.3 µs a field, issue 17)
        inp.control_interface = interface
        inp.synchronization = Synchronization.Time
        inp.target_acceleration = [0.0]
        _MODE[1] = interface
    w = _WROTE
    if not _same(p0, w[0]):
        inp.current_position = [p0]
        w[0] = p0
    if not _same(v0, w[1]):
        inp.current_velocity = [v0]
        w[1] = v0
    if not _same(a0, w[2]):
        inp.current_acceleration = [a0]
        w[2] = a0
    if not _same(p1, w[3]):
        inp.target_position = [p1]
        w[3] = p1
    if not _same(v1, w[4]):
        inp.target_velocity = [v1]
        w[4] = v1
    if not _same(v_max, w[5]):
        inp.max_velocity = [v_max]
        w[5] = v_max
    if not _same(a_max, w[6]):
        inp.max_acceleration = [a_max]
        w[6] = a_max
    if not _same(j_max, w[7]):
        inp.max_jerk = [j_max]
        w[7] = j_max
    return otg, inp


def _calculate(otg: Ruckig, inp: InputParameter, n: int) -> Trajectory | None:
    """ruckig's solve, None where it cannot. ruckig 0.19 throws on some states exactly at a phase boundary:
    0 → 1.2 + 1 ulp at a 1500, j 75000 (position), or a feed hold while braking at a_max with
    v0 = a0²/2j + 1 ulp (velocity, decision motion 62). Two retries move off the boundary: the current
    accelerations 1e-12 nearer zero (the ramp neither reverses, as a lower jerk can by 1e-8 mm/s, nor steps the
    acceleration measurably), then the jerk 1 ppb lower as well."""
    traj = _TRAJ.get(n)
    if traj is None:
        traj = _TRAJ[n] = Trajectory(n)
    try:
        return traj if otg.calculate(inp, traj) in _OK else None
    except Exception:  # ruckig.RuckigError
        pass
    a = [x * (1.0 - 1e-12) for x in inp.current_acceleration]
    j0 = list(inp.max_jerk)
    _WROTE[2] = _WROTE[7] = math.nan  # written below: _one_dof writes them again
    for j in (j0, [x * (1.0 - 1e-9) for x in j0]):
        inp.current_acceleration, inp.max_jerk = a, j
        try:
            return traj if otg.calculate(inp, traj) in _OK else None
        except Exception:
            continue
    return None


# solve_position's last inputs (p0, v0, a0, p1, v1, v_max as held, a_max, j_max: C doubles compiled) and its answer.
# The same inputs again give the same answer (ruckig is a function of its input), and a path solve's profile is only
# read once made (the planner writes to a ramp's duration and arrays, solve_velocity's), so the answer is given again
# as it is: 320 of the CAM program's 2,067 path solves repeat the one before (session 28, decision bench B154).
_S0 = _S1 = _S2 = _S3 = _S4 = _S5 = _S6 = _S7 = math.nan
_S_PW: Piecewise | None = None


def solve_position(p0: float, v0: float, a0: float, p1: float, v1: float, v_max: float, a_max: float,
                   j_max: float) -> Piecewise | None:
    """Time-optimal 1-DoF profile (p0, v0, a0) → (p1, v1, 0); None when ruckig cannot solve it."""
    global _S0, _S1, _S2, _S3, _S4, _S5, _S6, _S7, _S_PW
    v_max = 1e-9 if 1e-9 > v_max else v_max
    if _same(p0, _S0) and _same(v0, _S1) and _same(a0, _S2) and _same(p1, _S3) and _same(v1, _S4) \
            and _same(v_max, _S5) and _same(a_max, _S6) and _same(j_max, _S7):
        return _S_PW
    direct = _DIRECT
    if direct is not None:
        r = direct(False, p0, v0, a0, p1, v1, v_max, a_max, j_max)
        pw = None if r is None else _OneDof(r[0], r[1], r[2])
    else:
        otg, inp = _one_dof(_POSITION, p0, v0, a0, p1, v1, v_max, a_max, j_max)
        traj = _calculate(otg, inp, 1)
        pw = None if traj is None else _of(traj, Piecewise)
    _S0, _S1, _S2, _S3, _S4, _S5, _S6, _S7, _S_PW = p0, v0, a0, p1, v1, v_max, a_max, j_max, pw
    return pw


def solve_velocity(p0: float, v0: float, a0: float, v1: float, a_max: float, j_max: float) -> Piecewise:
    """Jerk-limited change of velocity to v1 (ends with a = 0), e.g. a feed hold or override ramp."""
    v_max = max(abs(v0), abs(v1), 1e-9)
    direct = _DIRECT
    if direct is not None:
        r = direct(True, p0, v0, a0, p0, v1, v_max, a_max, j_max)
        if r is not None:
            return _OneDof(r[0], r[1], r[2])
    else:
        otg, inp = _one_dof(_VELOCITY, p0, v0, a0, p0, v1, v_max, a_max, j_max)
        traj = _calculate(otg, inp, 1)
        if traj is not None:
            return _of(traj, Piecewise)
    raise NcAlarm(0x0000, f"velocity ramp {v0:g} → {v1:g} mm/s cannot be planned")


def solve_axes(p0, v0, a0, p1, v_max, a_max, j_max, velocity: bool = False) -> Piecewise:
    """Every axis independently (no synchronisation) to rest at p1, or to v = 0 when `velocity`."""
    n = len(p0)
    direct = _DIRECT
    if n == 1 and direct is not None:  # as the path solves: one trajectory for every 1-DoF solve, in order (B162)
        # (ruckig's synchronisation, Time there and None here, plays no part with one DoF)
        r = direct(velocity, float(p0[0]), float(v0[0]), float(a0[0]), float(p1[0]), 0.0, float(v_max[0]),
                   float(a_max[0]), float(j_max[0]))
        if r is None:
            raise NcAlarm(0x0000, "independent-axis rapid cannot be planned")
        return _OneDof(r[0], r[1], r[2])
    otg, inp = _calc(n)
    _MODE.pop(n, None)  # _one_dof sets its fields again (a one-axis machine shares its input)
    if n == 1:
        _WROTE[:] = [math.nan] * 8
    inp.control_interface = ControlInterface.Velocity if velocity else ControlInterface.Position
    inp.synchronization = Synchronization.No
    inp.current_position = list(map(float, p0))
    inp.current_velocity = list(map(float, v0))
    inp.current_acceleration = list(map(float, a0))
    inp.target_position = list(map(float, p1))
    inp.target_velocity = [0.0] * n
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = list(map(float, v_max))
    inp.max_acceleration = list(map(float, a_max))
    inp.max_jerk = list(map(float, j_max))
    traj = _calculate(otg, inp, n)
    if traj is None:
        raise NcAlarm(0x0000, "independent-axis rapid cannot be planned")
    return _of(traj, Piecewise)
