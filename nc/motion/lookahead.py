"""Look-ahead: per-block path limits, junction speeds and the backward pass.

Every block gets a path speed cap (feed, axis speeds projected on its direction, centripetal
limits, minimum duration) and tangential acceleration/jerk limits from the axis limits it
projects onto. The junction speed between two blocks is bounded by what one bus cycle of the
setpoint stream can absorb: a tangent jump of |Δu| at speed v changes each axis' finite-difference
velocity within one cycle, so v·|Δu_a|·2/T² must fit in the axis' corner jerk share (the 2 covers
two corners in one 3-sample stencil once segments last at least one cycle), and a curvature jump
|Δκ_a| changes the axis acceleration within one cycle: v²·|Δκ_a|/T must fit in the curvature share.

End speeds follow from a backward pass with the closed-form distance a jerk-limited speed change
needs when it starts and ends at zero acceleration (the plans execute exactly such profiles), so
no block ever has to brake harder than its limits.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

if cython.compiled:  # C's sqrt and cbrt, the functions math.sqrt and math.cbrt call (session 27, decision bench B148)
    from cython.cimports.libc.math import cbrt as _cbrt, sqrt as _c_sqrt
else:
    _cbrt, _c_sqrt = math.cbrt, math.sqrt

from nc.motion.blending import FilterCorners
if not cython.compiled:  # junction's local type: lookahead.pxd cimports the extension type under this name
    _FilterCorners = FilterCorners
from nc.motion.block import Block
from nc.motion.limits import MotionConfig, acceleration, jerk_per_acc
from nc.motion.path import Segment

# A corner blend's jerk (Limits._blend_limits, decision motion 47): its cap keeps v³·|(dκ/ds, κ²)| within
# BLEND_CAP of the axis jerk; its normal part v³·dκ/ds + 3·v·a_t·κ and its tangential part j_t + v³·κ² are
# orthogonal, so they share the axis jerk in quadrature: BLEND_NORMAL and √(1 − BLEND_NORMAL²).
BLEND_CAP = 0.8
BLEND_NORMAL = 0.9


def arc_coupling(cfg: MotionConfig) -> float:
    """Share of the axis jerk for an arc's coupling term 3·v·a_t/r (decision motion 65). An in-plane axis
    sees (j_t − v³/r²)·t_i + (3·v·a_t/r + the curvature jump's step)·n_i with t_i² + n_i² ≤ 1, so at most
    the hypot of the two parts, plus the filter's or a junction's corner (corner share, any direction).
    The tangential part is at most share_tangential + 0.3·share_curvature, the jump 0.4·share_curvature;
    the rest of the hypot goes to the coupling (defaults: 0.36 of the jerk; it was 0.3·share_curvature =
    0.075, the parts added as if parallel), never less than that."""
    sc = cfg.share_curvature
    room = (1.0 - cfg.share_corner) ** 2 - (cfg.share_tangential + 0.3 * sc) ** 2
    return max(0.3 * sc, math.sqrt(max(room, 0.0)) - 0.4 * sc) * 0.95  # 5 % kept back


MARGIN = 0.98  # the passes plan with 98 % of the limits ruckig gets, so plans are never borderline
_MARGIN = MARGIN  # C doubles where compiled (lookahead.pxd): a module global is a Python float in each product
_INF = math.inf


def _sqrt(x: float) -> float:
    """math.sqrt on a C double where compiled (lookahead.pxd): the same C sqrt, and math.sqrt's ValueError below 0."""
    if x < 0.0:
        raise ValueError("math domain error")
    return _c_sqrt(x)


@cython.locals(dv=cython.double)  # a C function of C doubles where compiled: lookahead.pxd (session 28: cimported)
def change_distance(v0: float, v1: float, a: float, j: float) -> float:
    """Path length a jerk-limited speed change v0 → v1 needs, zero acceleration at both ends."""
    dv = abs(v1 - v0)
    if dv * j <= a * a:
        return (v0 + v1) * math.sqrt(dv / j)
    return 0.5 * (v0 + v1) * (dv / a + a / j)


@cython.ccall
@cython.returns(cython.double)
@cython.locals(v0=cython.double, length=cython.double, a=cython.double, j=cython.double, q=cython.double,
               p=cython.double, disc=cython.double, x=cython.double, dv=cython.double, qa=cython.double,
               qb=cython.double, qc=cython.double)
def reach(v0: float, length: float, a: float, j: float) -> float:
    """Highest speed reachable from v0 within `length` (zero acceleration at both ends).

    By time symmetry it is also the highest entry speed that can still brake to v0 within `length`.
    """
    if length <= 0.0:
        return v0
    # No constant-acceleration phase: (2·v0 + x²)·x = L·√j with x = √Δv (one real root).
    q = length * _sqrt(j)
    p = 2.0 * v0
    disc = _sqrt(q * q / 4.0 + p ** 3 / 27.0)
    x = _cbrt(q / 2.0 + disc) + _cbrt(q / 2.0 - disc)
    dv = x * x
    if dv * j <= a * a:
        return v0 + dv
    # With a constant-acceleration phase: Δv²/a + Δv·(2·v0/a + a/j) + 2·v0·a/j − 2·L = 0.
    qa = 1.0 / a
    qb = 2.0 * v0 / a + a / j
    qc = 2.0 * v0 * a / j - 2.0 * length
    dv = (-qb + _sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)
    return v0 + (0.0 if 0.0 > dv else dv)  # max(dv, 0.0)


@cython.locals(v0=cython.double, a0=cython.double, d=cython.double, a=cython.double, j=cython.double)
def max_speed_at(v0: float, a0: float, d: float, a: float, j: float) -> float:
    """Upper bound of the speed any profile from (v0, a0) with acceleration ≤ a and jerk ≤ j can
    have after path length d: full jerk up to a, then a constant a (issue 18: a junction whose
    speed this does not exceed cannot bind a profile that starts here)."""
    return fastest_state(v0, a0, d, a, j)[0]


@cython.ccall
@cython.locals(v0=cython.double, a0=cython.double, d=cython.double, a=cython.double, j=cython.double,
               t1=cython.double, d1=cython.double, v1=cython.double, lo=cython.double, hi=cython.double,
               t=cython.double, k=cython.Py_ssize_t)
def fastest_state(v0: float, a0: float, d: float, a: float, j: float) -> tuple[float, float]:
    """Speed and acceleration after path length d of `max_speed_at`'s profile from (v0, a0) (full jerk up to a, then
    a constant a): the fastest any profile within a and j can be there, and (from a state below a) the highest
    acceleration it can have there with that speed (decisions motion 84, 86: a corner's acceleration step)."""
    a0 = a0 if a0 < a else a
    t1 = (a - a0) / j
    d1 = v0 * t1 + a0 * t1 * t1 / 2.0 + j * t1 ** 3 / 6.0
    if d >= d1:
        v1 = v0 + a0 * t1 + j * t1 * t1 / 2.0
        return _sqrt(v1 * v1 + 2.0 * a * (d - d1)), a
    lo = 0.0  # the time d is reached in the jerk phase (distance grows with t)
    hi = t1
    for k in range(40):
        t = 0.5 * (lo + hi)
        if v0 * t + a0 * t * t / 2.0 + j * t ** 3 / 6.0 < d:
            lo = t
        else:
            hi = t
    return v0 + a0 * hi + j * hi * hi / 2.0, a0 + j * hi



# What a block is, for its limits (Limits.block_limits): cutting (G01/G02/G03, cycles' feed moves, corner
# blends, fitted spans), G00 rapid, or a thread (spindle-synchronised: neither parameter set, decision motion 90).
CUT, RAPID, THREAD = 0, 1, 2


class Limits:
    """Axis limits (plain float tuples: per-block math on 3 axes is faster without numpy) and
    the planner settings, prepared once. The numpy vectors serve the independent rapids."""

    def __init__(self, cfg: MotionConfig) -> None:
        self.cfg = cfg
        self.T = cfg.cycle
        self.v = np.array([cfg.limit(a).max_velocity for a in cfg.axes])
        self.acc = np.array([cfg.limit(a).max_acceleration for a in cfg.axes])
        self.jerk = np.array([cfg.limit(a).max_jerk for a in cfg.axes])
        self._v = tuple(self.v.tolist())
        self._acc = tuple(self.acc.tolist())
        self._jerk = tuple(self.jerk.tolist())
        T = self.T
        self._corner_j = tuple(x * T * T / 2.0 for x in self._jerk)  # divided by |Δu| per junction
        self._corner_a = tuple(x * T for x in self._acc)
        self.blend = FilterCorners(cfg, self._acc, self._jerk) if cfg.filtered else None
        self._coupling = arc_coupling(cfg)
        self._rapid_limits(cfg)
        # Cutting N1.034 / N1.035 (decision motion 90): a path acceleration cap and a jerk per unit of the block's
        # acceleration; inf (nothing changes, bit for bit) where not set.
        cut = cfg.cutting
        self.cut_a = acceleration(cut.speed, cut.acc_time)
        self.cut_js = jerk_per_acc(cut.scurve_time)
        self.cut_on = self.cut_a < math.inf or self.cut_js < math.inf
        # the shortest a block may last, min_segment_cycles cycles (block_limits' cap length / this; a C double where
        # compiled, session 31: the product of two Python floats a block)
        self._min_dur = cfg.min_segment_cycles * self.T
        self._share_t = cfg.share_tangential  # block_limits' (a C double where compiled)
        # The least tangential acceleration and jerk of any line (a cutting one, under N1.034/N1.035): the braking
        # Planner._may_blend allows for (half of these) must not assume more.
        self.line_a_lo = min(cfg.share_tangential * float(self.acc.min()), self.cut_a)
        self.line_j_lo = min(cfg.share_tangential * float(self.jerk.min()), self.line_a_lo * self.cut_js)

    def _rapid_limits(self, cfg: MotionConfig) -> None:
        """The G00 limits (decisions motion 90, 91): each axis's within its N2.020-N2.022 and its own limits
        (`rv`, `racc`, `rjerk`: also the independent rapids', N1.20 bit 18), the path's N1.030-N1.032."""
        rv, ra, rj = [], [], []
        for a, v, acc, jerk in zip(cfg.axes, self._v, self._acc, self._jerk):
            ar = cfg.axis_rapid.get(a)
            if ar is not None:
                v = min(v, ar.speed) if ar.speed else v
                acc = min(acc, acceleration(ar.speed, ar.acc_time))
                jerk = min(jerk, acc * jerk_per_acc(ar.scurve_time))
            rv.append(v)
            ra.append(acc)
            rj.append(jerk)
        self._rv, self._racc, self._rjerk = tuple(rv), tuple(ra), tuple(rj)
        self.rv, self.racc, self.rjerk = np.array(rv), np.array(ra), np.array(rj)
        # An acceleration or S-curve time given: a G00's budget is the axes' whole (a rapid has no corner or
        # arc to share it with, decision motion 71's analysis); none: today's tangential share (decision 91).
        self.rapid_whole = cfg.rapid_whole
        self.rapid_share = 1.0 if self.rapid_whole else cfg.share_tangential
        self.rapid_v = cfg.rapid.speed if cfg.rapid.speed else math.inf
        self.rapid_a = acceleration(cfg.rapid.speed, cfg.rapid.acc_time)
        self.rapid_js = jerk_per_acc(cfg.rapid.scurve_time)

    def _rapid_block(self, seg: Segment) -> tuple[float, float, float]:
        """(speed cap, acceleration, jerk) of an interpolated G00 (decisions motion 90, 91): the least of the
        path's N1.030-N1.032 and each axis's rapid limits projected on the direction."""
        v = a = j = math.inf
        for d, vl, al, jl in zip(seg.direction_cosines(), self._rv, self._racc, self._rjerk):
            if d > 1e-12:
                v, a, j = min(v, vl / d), min(a, al / d), min(j, jl / d)
        if v == math.inf:
            return 0.0, 1.0, 1.0
        s = self.rapid_share
        a, j = min(a * s, self.rapid_a), j * s
        return min(v, self.rapid_v), a, min(j, a * self.rapid_js)

    def cut_caps(self, a: float, j: float) -> tuple[float, float]:
        """A cutting block's (acceleration, jerk) under N1.034 / N1.035 (decision motion 90)."""
        if a > self.cut_a:
            a = self.cut_a
        x = a * self.cut_js
        return a, (x if x < j else j)

    @cython.locals(v=cython.double, a=cython.double, j=cython.double, x=cython.double, d=cython.double,
                   vl=cython.double, al=cython.double, jl=cython.double,
                   st=cython.double, i=cython.Py_ssize_t, n=cython.Py_ssize_t, m=cython.Py_ssize_t,
                   length=cython.double, sg=Segment)
    def block_limits(self, seg: Segment, short_ok: bool = False, what: int = CUT) -> tuple[float, float, float]:
        """(speed cap, tangential acceleration, tangential jerk) of a path segment. `short_ok`: no
        minimum duration (a line whose both ends are blends has no corner for it to protect). `what`: CUT,
        RAPID or THREAD, whose parameters apply (decision motion 90)."""
        cfg = self.cfg
        if what == 1:  # RAPID (a C int compared with a C constant where compiled)
            v, a, j = self._rapid_block(seg)
            if not short_ok:
                length = seg.length
                x = length / self._min_dur
                if x < v:
                    v = x
            return v, a, j
        v = a = j = _INF
        sg = seg  # typed where compiled: its fields read from C (session 31, bench B181)
        # zip(direction cosines, _v, _acc, _jerk) as a C loop over the shortest (session 27: per block)
        cos = sg._cos  # Segment.direction_cosines()'s kept tuple, read here (session 31: a Python call a block)
        if cos is None:
            cos = sg.direction_cosines()
        vs, accs, jerks = self._v, self._acc, self._jerk
        n = len(cos)
        m = len(vs)
        if m < n:
            n = m
        m = len(accs)
        if m < n:
            n = m
        m = len(jerks)
        if m < n:
            n = m
        for i in range(n):
            d = cos[i]
            if d > 1e-12:  # v = min(v, vl / d) etc., spelt out: this runs per axis of every block
                vl = vs[i]
                al = accs[i]
                jl = jerks[i]
                x = vl / d
                if x < v:
                    v = x
                x = al / d
                if x < a:
                    a = x
                x = jl / d
                if x < j:
                    j = x
        if v == _INF:
            return 0.0, 1.0, 1.0
        st = self._share_t
        a *= st
        j *= st
        if what == 0 and self.cut_on:  # CUT
            a, j = self.cut_caps(a, j)
        kind = sg.kind
        if kind == "arc" and seg.radius > 0.0:
            k = seg.arc_len / seg.length
            rc = seg.radius / max(k * k, 1e-12)  # radius of curvature of the (helical) path
            pa = min(self._acc[seg.i1], self._acc[seg.i2])
            pj = min(self._jerk[seg.i1], self._jerk[seg.i2])
            sc = cfg.share_curvature
            v = min(v, math.sqrt(sc * pa * rc), (0.3 * sc * pj * rc * rc) ** (1.0 / 3.0))
            # d/dt of the centripetal term couples tangential acceleration into jerk: 3·v·a_t/r, along
            # the normal n, square to the tangential part (j_t − v³/r²)·t: see arc_coupling.
            a = min(a, self._coupling * pj * rc / (3.0 * max(v, 1e-9)))
        if kind == "arc" and self.blend is not None:
            v = min(v, self.blend.arc_speed(seg.radius))
        if kind == "blend":
            v, a, j = self._blend_limits(seg, v, a, j)
        if not short_ok:
            length = sg.length
            x = length / self._min_dur
            if x < v:  # min(v, x) spelt out (session 15)
                v = x
        return v, a, j

    def _blend_limits(self, seg: Segment, v: float, a: float, j: float) -> tuple[float, float, float]:
        """A clothoid pair (nc.motion.clothoid) at speed v ≤ its cap with tangential acceleration a_t and
        jerk j_t: normal acceleration v²·κ ≤ v²·κmax; jerk (j_t − v³·κ²)·t + (v³·dκ/ds + 3·v·a_t·κ)·n
        (a planar curve). t and n span the blend's plane, so each axis' component is at most the size of
        that vector times the axis' share of the plane (`normal_amplitude`), and the size is the hypot of
        the two parts: the normal part within BLEND_NORMAL of the axis jerk, the tangential part within
        √(1 − BLEND_NORMAL²) (decision motion 47; decisions 42/46 added the parts). The cap keeps
        v³·hypot(dκ/ds, κ²) within BLEND_CAP (decision 46) and leaves each part some room; a_t and j_t
        are what the parts leave at the cap (both only grow as the speed falls below it). A blend has no
        tangent or curvature jump, so the corner and curvature shares of the acceleration are its own (as
        between lines under the filter, decision 38)."""
        cfg = self.cfg
        pa = pj = math.inf
        for m, al, jl in zip(seg.normal_amplitude().tolist(), self._acc, self._jerk):
            if m > 1e-12:
                pa, pj = min(pa, al / m), min(pj, jl / m)
        km, dk = seg.kappa_max, seg.dkappa
        sa = cfg.share_curvature + cfg.share_corner
        cn = BLEND_NORMAL
        ct = math.sqrt(1.0 - cn * cn)
        v = min(v, math.sqrt(sa * pa / km), (BLEND_CAP * pj / math.hypot(dk, km * km)) ** (1.0 / 3.0),
                (0.98 * cn * pj / dk) ** (1.0 / 3.0), (0.9 * ct * pj / (km * km)) ** (1.0 / 3.0))
        v3 = v * v * v
        a = min(a, (cn * pj - v3 * dk) / (3.0 * max(v, 1e-9) * km))
        return v, a, min(j, ct * pj - v3 * km * km)

    @cython.locals(v=cython.double, d0=cython.double, d1=cython.double, d2=cython.double,
                   sq_sum=cython.double, du_n=cython.double, a=cython.double, vb=cython.double, vc=cython.double,
                   vp=cython.double, lines=cython.bint, blend=_FilterCorners, s1=Segment, s2=Segment)
    def junction(self, b1: Block, b2: Block, raw: bool = False) -> float:
        """Highest speed at the junction b1 → b2. `raw`: as without the filter (a junction where its
        share λ is below 1, nc.motion.share_zones); the filter's fields of b1 are then left alone."""
        if b1.kind != "path" or b2.kind != "path" or b1.rapid or b2.rapid or b1.move.exact_stop:
            return 0.0  # G00, G09/G61, dwells, threads and independent rapids stop at their ends
        s1, s2 = b1.seg, b2.seg
        assert s1 is not None and s2 is not None
        v = b2.cap_hard if b2.cap_hard < b1.cap_hard else b1.cap_hard  # min(), as min() picks
        # Segment.tangent's cached line direction read here (session 27: two Python calls per junction)
        t2 = s2._dir
        if t2 is None:
            t2 = s2.tangent(False)
        t1 = s1._dir
        if t1 is None:
            t1 = s1.tangent(True)
        k1, k2 = s1.kind, s2.kind
        if len(t1) == 3:  # the common case spelt out (once per pushed block, issue 17)
            d0, d1, d2 = t2[0] - t1[0], t2[1] - t1[1], t2[2] - t1[2]
            dv = (d0, d1, d2)
            du = (abs(d0), abs(d1), abs(d2))
            sq_sum = d0 * d0 + d1 * d1 + d2 * d2  # |d|·|d| is d·d bit for bit; sum() adds them in this order from 0
        else:
            dv = tuple([p - q for p, q in zip(t2, t1)])
            du = tuple([abs(d) for d in dv])
            sq_sum = sum([d * d for d in du])
        cfg = self.cfg
        blend = self.blend
        if blend is not None and not raw:
            b1.dv = dv
            b1.du = du
            b1.du_n = du_n = _sqrt(sq_sum)  # C's sqrt (sq_sum ≥ 0): math.sqrt's, without its lookup and call
            if du_n > 1e-9:
                lines = k1 == "line" and k2 == "line"
                a = b2.a if b2.a > b1.a else b1.a  # max(b1.a, b2.a) and min(v, vb, vc) spelt out (session 15)
                b1.vbud, b1.vctol = vb, vc = blend.corner_caps(du, du_n, lines, a)
                b1.viso = 0.0
                if lines:  # the proved cap of a corner alone in its windows, where it is higher (decision motion 73)
                    vp = blend.isolated_cap(du_n, a, b2.j if b2.j > b1.j else b1.j, b1, b2)
                    if vp > vc:
                        b1.viso = b1.vctol = vc = vp
                if vb < v:
                    v = vb
                if vc < v:
                    v = vc
        elif max(du) > 1e-9:
            vj = va = math.inf
            for d, cj, ca in zip(du, self._corner_j, self._corner_a):
                if d > 1e-12:  # vj = min(vj, cj / d) etc., spelt out (per axis of every junction)
                    x = cj / d
                    if x < vj:
                        vj = x
                    x = ca / d
                    if x < va:
                        va = x
            v = min(v, cfg.share_corner * vj, cfg.share_corner * va)
            if cfg.path_tolerance is not None:
                v = min(v, 4.0 * cfg.path_tolerance / (self.T * math.sqrt(sum([d * d for d in du]))))  # no closure: cpdef
        if k1 == "arc" or k2 == "arc":  # a line has no curvature: line-line skips this
            dk = np.abs(s2.curvature_vector(False) - s1.curvature_vector(True))
            if float(dk.max()) > 1e-12:
                m = dk > 1e-12
                # A curvature jump steps the axis acceleration: in one cycle without the filter,
                # spread over its first window T1 with it.
                t = blend.t_a if blend is not None and not raw else self.T
                v = min(v, float(np.min(np.sqrt(0.4 * cfg.share_curvature * self.jerk[m] * t / dk[m]))))
        return 0.0 if 0.0 > v else v  # max(v, 0.0)


# (types in lookahead.pxd: a cpdef function, which Planner.lookahead calls in C; session 31, decision bench B181)
def backward(blocks: Sequence[Block], lo: int = 0, full: bool = False, depth: int = 0) -> None:
    """Backward pass from the queue tail (which ends at rest) down to index lo.

    A junction's end speed is the least of its own limit and what the nearest *binding* junction
    downstream allows over the whole path length in between (braking may carry acceleration
    through intermediate junctions, so chains of short blocks are not forced to a = 0 at each).
    Appending a block only raises end speeds, so the incremental pass stops once a junction is
    binding and unchanged (LinuxCNC's "rising tide"); `full` recomputes everything, `depth` at
    least that many blocks from the tail (junction speeds lowered there since the last pass).
    """
    n = len(blocks)
    if n == 0:
        return
    it = reversed(blocks)  # a deque indexes its middle in O(n); iterate instead
    nx = next(it)
    nx.vend, nx.binding = 0.0, True
    # This runs ≈ 10 times per pushed block (the tail within braking distance changes on every
    # push), so it works on locals: the downstream block's fields are carried over from the
    # previous step, and min() is spelt out (same operands, same result, no builtin call).
    # One name per value, one assignment each: a tuple of four or more is built and unpacked (session 13).
    nx_vend = 0.0
    nx_binding = True
    nx_cap = nx.cap
    nx_length = nx.length
    nx_a = nx.a
    nx_j = nx.j
    nx_av = nx.anchor_v
    nx_ad = nx.anchor_d
    nx_aa = nx.anchor_a
    nx_aj = nx.anchor_j
    k_stop = n if full else depth - 2  # the pass may stop past k_stop (k + 2 > depth), never when `full`
    m = n - 1 - lo  # enumerate(islice(it, m)) as a C counter (session 31: islice's and enumerate's objects a step)
    k = 0
    for b in it:
        if k >= m:
            break
        b_cap = b.cap
        local = b.vjunc  # min(b.vjunc, b.cap, nx.cap)
        if b_cap < local:
            local = b_cap
        if nx_cap < local:
            local = nx_cap
        if local <= 0.0:
            v, av, ad, aa, aj = 0.0, 0.0, 0.0, nx_a, nx_j
        else:
            if nx_binding:
                av = nx_vend
                ad = nx_length
                aa = nx_a
                aj = nx_j
            else:
                av = nx_av
                ad = nx_ad + nx_length
                aa = nx_a if nx_a < nx_aa else nx_aa  # min(nx.anchor_a, nx.a)
                aj = nx_j if nx_j < nx_aj else nx_aj
            r = reach(av, ad, _MARGIN * aa, _MARGIN * aj)
            v = r if r < local else local
        binding = v >= local - 1e-12
        if k > k_stop and binding and b.binding and -1e-12 <= v - b.vend <= 1e-12:
            break
        b.vend = nx_vend = v
        b.binding = nx_binding = binding
        b.anchor_v = nx_av = av
        b.anchor_d = nx_ad = ad
        b.anchor_a = nx_aa = aa
        b.anchor_j = nx_aj = aj
        nx_cap = b_cap
        nx_length = b.length
        nx_a = b.a
        nx_j = b.j
        k += 1
