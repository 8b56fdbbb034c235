"""Threading: G32 single thread, G34 variable lead, G92 threading cycle, G76 multiple threading.

Plane (Z, X radius), machine coordinates. Every thread move carries its lead (mm/rev along the
thread's major axis) and the spindle start angle; the motion layer starts each thread move when the
spindle reaches that angle, so every pass of a cycle starts on the same phase (decisions A41, A44).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.builder import PathBuilder
from nc.cycles.geometry import Pt

MAX_THREAD_PASSES = 999


@dataclass
class ThreadPass:
    depth: float  # radial depth reached by this pass (radius, from the crest line)
    finish: bool


def g76_depths(height: float, first: float, min_step: float, allowance: float, finish_passes: int) -> list[ThreadPass]:
    """Constant-area depth law (decisions A41): rough pass n reaches first·√n, each step at least
    `min_step`, the last rough pass stops at height − allowance; then `finish_passes` passes at the
    full height (the first of them removes the allowance)."""
    if height <= 0:
        raise NcAlarm(0x0246, f"G76 thread height P must be positive (got {height:g})")
    if first <= 0:
        raise NcAlarm(0x0246, f"G76 first depth of cut Q must be positive (got {first:g})")
    if allowance < 0 or allowance >= height:
        raise NcAlarm(0x0246, f"G76 finishing allowance R {allowance:g} must lie in [0, height)")
    rough_end = height - allowance
    out: list[ThreadPass] = []
    depth = 0.0
    n = 1
    while depth < rough_end - 1e-9:
        nxt = first * math.sqrt(n)
        if nxt - depth < min_step:
            nxt = depth + min_step
        depth = min(nxt, rough_end)
        out.append(ThreadPass(depth, False))
        n += 1
        if n > MAX_THREAD_PASSES:
            raise NcAlarm(0x0246, "G76 needs more than 999 passes; raise Q or Δdmin")
    for _ in range(max(finish_passes, 1)):
        out.append(ThreadPass(height, True))
    return out


def _thread_line(b: PathBuilder, p0: Pt, p1: Pt, lead: float, angle: float, chamfer: float,
                 chamfer_angle: float, out_sign: float, tags: tuple[str, ...], lead_change: float = 0.0) -> None:
    """Thread from p0 to p1 = (z, x); with a chamfer, pull out over the last `chamfer` of Z at
    `chamfer_angle` away from the work (out_sign = +1 for an OD thread)."""
    (z0, x0), (z1, x1) = p0, p1
    length = abs(z1 - z0)
    if chamfer > 1e-9 and length > 1e-9:
        c = min(chamfer, length)
        t = (length - c) / length
        zc, xc = z0 + (z1 - z0) * t, x0 + (x1 - x0) * t
        b.thread((zc, xc), lead, angle, tags, lead_change)
        rise = c * math.tan(math.radians(chamfer_angle))
        b.thread((z1, x1 + out_sign * rise), lead, angle, tags + ("chamfer",), lead_change)
    else:
        b.thread((z1, x1), lead, angle, tags, lead_change)


def g92(b: PathBuilder, end: Pt, taper: float, lead: float, angle: float, chamfer: float,
        chamfer_angle: float, code: str = "G92") -> None:
    """G92: rapid to the thread start, thread (with end chamfer), rapid out in X, rapid back in Z."""
    if lead <= 0:
        raise NcAlarm(0x1001, f"{code} needs a positive lead F")
    za, xa = b.here
    ze, xe = end
    out_sign = 1.0 if xa >= xe else -1.0
    b.rapid((za, xe + taper), (code, "approach"))
    _thread_line(b, (za, xe + taper), (ze, xe), lead, angle, chamfer, chamfer_angle, out_sign, (code, "thread"))
    b.rapid((b.here[0], xa), (code, "retract"))
    b.rapid((za, xa), (code, "return"))


@dataclass
class G76Spec:
    end: Pt  # (z, x) thread end, x = root line... the programmed X (minor diameter for OD)
    taper: float  # i: start radius − end radius
    height: float  # k (radius)
    first: float  # Δd (radius)
    min_step: float  # Δdmin
    allowance: float  # d
    finish_passes: int  # m
    chamfer: float  # mm along Z (0.1·r·L)
    chamfer_angle: float  # degrees
    tool_angle: float  # a, degrees
    lead: float
    infeed: int = 0  # L: 0 right flank, 1 radial (centre), 2 left flank, 3 alternating


def g76(b: PathBuilder, spec: G76Spec, code: str = "G76") -> list[ThreadPass]:
    """G76: one G92-like pass per depth of the law; flank infeed shifts each pass's start in Z along
    the tool's half angle so the final pass lands on the programmed thread (decisions A41)."""
    if spec.lead <= 0:
        raise NcAlarm(0x1001, f"{code} needs a positive lead F")
    if spec.tool_angle < 0 or spec.tool_angle >= 180:
        raise NcAlarm(0x0246, f"{code} tool angle {spec.tool_angle:g} out of range")
    za, xa = b.here
    ze, xe = spec.end
    if abs(ze - za) < 1e-9:
        raise NcAlarm(0x0246, f"{code} thread has no length in Z")
    s = 1.0 if xa >= xe + spec.taper else -1.0  # OD thread: the tool comes from +X
    zdir = 1.0 if ze > za else -1.0
    half = math.tan(math.radians(spec.tool_angle / 2.0))
    passes = g76_depths(spec.height, spec.first, spec.min_step, spec.allowance, spec.finish_passes)
    n_rough = 0
    rapid = b._to  # `b.rapid` without its call (a G76 makes some sixty moves)
    for i, ps in enumerate(passes):
        left = spec.height - ps.depth  # distance above the root
        side = {0: 1.0, 1: 0.0, 2: -1.0}.get(spec.infeed, 1.0 if i % 2 == 0 else -1.0)
        # right flank = shifted back toward the start of the thread (against the cutting direction)
        dz = -zdir * side * left * half
        z_start = za + dz
        # taper: the crest line runs from xe + taper at za to xe at ze
        x_line_start = xe + spec.taper * (ze - z_start) / (ze - za)
        x0 = x_line_start + s * left
        x1 = xe + s * left
        if ps.finish:
            tags = (code, "finish", str(i - n_rough + 1))
        else:
            n_rough += 1
            tags = (code, "rough", str(n_rough))
        rapid("rapid", (z_start, xa), (code, "approach"), None, False)
        rapid("rapid", (z_start, x0), (code, "infeed"), None, False)
        _thread_line(b, (z_start, x0), (ze, x1), spec.lead, 0.0, spec.chamfer, spec.chamfer_angle, s, tags)
        rapid("rapid", (b.here[0], xa), (code, "retract"), None, False)
        rapid("rapid", (za, xa), (code, "return"), None, False)
    return passes


def g34_check(length: float, lead: float, k: float) -> float:
    """Manual's law (decisions A43): distance after t turns = F·t + ½·K·t². Returns the turns the
    thread takes; alarm when the lead would reach zero before the end."""
    if lead <= 0:
        raise NcAlarm(0x1001, "G34 needs a positive lead F")
    if abs(k) < 1e-15:
        return length / lead
    disc = lead * lead + 2.0 * k * length
    if disc < 0:
        raise NcAlarm(0x0223, f"G34 lead reaches zero before the end of the thread (F{lead:g} K{k:g}, length {length:g})")
    t = (-lead + math.sqrt(disc)) / k
    if lead + k * t <= 1e-9:
        raise NcAlarm(0x0223, f"G34 lead reaches zero at the end of the thread (F{lead:g} K{k:g})")
    return t
