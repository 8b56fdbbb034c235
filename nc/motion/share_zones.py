"""Where the position filter gives way to corner blends: its share λ along the path (decision motion 45).

A corner blend under the filter (nc.motion.corner_blends) is taken at λ = 0: the output is the raw path
delayed by the filter's group delay (PositionFilter.push(x, lam)), so the blend's deviation is the only
one and its speed is planned on its own curvature. λ is a function of the path position s (Block.s_end's
scale), 0 on each blend's core [start − R, end + R] (R = vtop·(T1 + T2): the filter's reach, so the
filter window of a ramp never sees the blend's curvature) and rising to 1 over a quintic smoothstep of
`RAMP` seconds at the fastest the blocks there may run (decision 40 f: ramps under 30 ms add jerk).

A junction the filter rounds ("hard": a tangent step or a curvature jump, not blended) needs λ = 1 within
its own reach R_H, where the raw path has its step. So a blend is built only when its λ < 1 region starts
R_H after the last such junction, and a hard junction that comes within a zone's reach after a blend is
planned as without the filter (`Limits.junction(raw=True)`: a one-cycle corner, near a stop) and leaves
λ at 0. A stop (vjunc = 0) cuts every zone: the planner waits there for the filter to settle, where
F(p) = p(t − D) = p and λ may change at once.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

try:
    import cython  # compiled: the types in share_zones.pxd (setup.py; this module since session 28, decision bench B157)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

RAMP = 0.03  # s: the shortest λ ramp (decision 40 f)
# C doubles where compiled (share_zones.pxd): a module global is a Python float in each product or comparison
_RAMP = RAMP
_INF = math.inf


@dataclass
class Zone:
    lo: float  # the stop before it (λ is 1 at and before it)
    c0: float  # the core, λ = 0
    c1: float
    rr: float  # ramp length
    hi: float = math.inf  # the stop after it, once pushed

    @cython.locals(d=cython.double, x=cython.double)
    def lam(self, s: float) -> float:
        if s <= self.lo or s > self.hi:
            return 1.0
        d = self.c0 - s if s < self.c0 else s - self.c1
        if d <= 0.0:
            return 0.0
        if d >= self.rr:
            return 1.0
        x = d / self.rr
        return x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)


class ShareZones:
    def __init__(self, window: float) -> None:
        self.window = window  # T1 + T2, s
        self.zones: deque[Zone] = deque()
        self._stop = -_INF  # the newest stop junction
        self._hard = -_INF  # λ = 1 needed up to here (the newest hard junction plus its reach)

    def reach(self, vtop: float) -> float:
        return vtop * self.window

    @cython.locals(z=Zone)
    def stop(self, s: float) -> None:
        """A stop junction at s: zones end there; nothing before it constrains what comes after."""
        self._stop = s
        self._hard = -_INF
        for z in reversed(self.zones):
            if z.hi < _INF:
                break
            if z.lo >= s:
                continue  # it begins after this stop (a fitted run's zone, added before its first junction)
            z.hi = s

    @cython.locals(z=Zone, r=cython.double, lo=cython.double)
    def blend_allowed(self, start: float, vtop: float, now: float, rest: bool) -> bool:
        """Whether a blend starting at path position `start` keeps its λ < 1 region clear of the last
        hard junction's reach, and ahead of `now` (the position of the sample going out: λ must not
        jump) unless an open zone already covers it or the planner stands (`rest`: λ changes only once
        it moves on, after the filter has settled)."""
        r = self.reach(vtop)
        lo = start - r - _RAMP * vtop
        z = self.zones[-1] if self.zones else None
        if z is not None and z.hi == _INF and lo <= z.c1 + 2.0 * z.rr:
            return lo >= self._hard and (rest or now < z.c0 - z.rr or now <= z.c1)  # it extends that zone
        return lo >= self._hard and (rest or lo > now)

    @cython.locals(z=Zone, r=cython.double)
    def add_blend(self, start: float, end: float, vtop: float) -> None:
        r = self.reach(vtop)
        z = self.zones[-1] if self.zones else None
        if z is not None and z.hi == _INF and start - r <= z.c1 + 2.0 * z.rr:
            z.c1 = max(z.c1, end + r)  # the same stretch: one core
            z.rr = max(z.rr, _RAMP * vtop)
            return
        self.zones.append(Zone(self._stop, start - r, end + r, _RAMP * vtop))

    @cython.locals(z=Zone)
    def block(self, start: float, vtop: float) -> None:
        """A block pushed from path position `start`: a ramp it runs in lasts RAMP at its speed too."""
        z = self.zones[-1] if self.zones else None
        if z is not None and z.hi == _INF and start < z.c1 + z.rr:
            z.rr = max(z.rr, _RAMP * vtop)

    @cython.locals(z=Zone)
    def inside(self, s: float, vtop: float) -> bool:
        """Whether λ < 1 may reach a junction at s (its reach overlaps the newest open zone's)."""
        z = self.zones[-1] if self.zones else None
        return z is not None and z.hi == _INF and s - self.reach(vtop) < z.c1 + z.rr

    @cython.locals(x=cython.double)
    def hard(self, s: float, vtop: float) -> bool:
        """A hard junction at s: True when it lies where λ < 1 may reach it (plan it raw, λ stays 0);
        else it is the filter's, and λ = 1 within its reach."""
        if self.inside(s, vtop):
            return True
        x = s + self.reach(vtop)
        if x > self._hard:  # max(self._hard, x) spelt out (once a push, session 15)
            self._hard = x
        return False

    @cython.locals(z=Zone, out=cython.double)
    def lam(self, s: float) -> float:
        zs = self.zones
        while zs and (zs[0].hi < s or zs[0].c1 + zs[0].rr < s):
            zs.popleft()  # passed
        out = 1.0
        for z in zs:
            if z.c0 - z.rr > s:
                break
            out = min(out, z.lam(s))
        return out

    @cython.locals(z=Zone)
    def near(self, lo: float, hi: float) -> bool:
        """Whether λ < 1 anywhere on [lo, hi]."""
        for z in self.zones:
            if z.c0 - z.rr > hi:
                break
            if max(z.lo, z.c0 - z.rr) < hi and min(z.hi, z.c1 + z.rr) > lo:
                return True
        return False
