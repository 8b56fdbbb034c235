"""G10 / G11 programmable data input, every L variant of both manuals (seed-catalog §6.12).

L2 P0–P6 work offsets (P0 = external/common offset), L10/L11 tool length / wear (lathe R nose radius,
Q tip), L12/L13 radius / radius wear (mill), L14 tolerance, L15 tool life, L20 G54 P1–P64, L21 soft
limits, and lathe-2018's L30 (spindle positioning offset), L1100 (spindle analog), L3100/L4100
(set / clear M2080–M2111) and the L-less forms ``G10 P10000+n`` (= L10) and ``G10 P n`` (= L11);
NC5's servo parameter forms L40/L41/L45/L46 are in `nc.interp.servo`.
Values follow the decimal-point rule; an X value is a diameter in diameter mode (A6).  G10 stops
preview; the data take effect from the next motion block (7.3.29).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

from nc.alarms import NcAlarm
from nc.interp.servo import SERVO_L, servo_g10
from nc.interp.state import N_EXT_WCS
from nc.moves import Aux, Event

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.host import InterpHost
    from nc.program.blocks import Block


def _int(block: "Block", letter: str, code: int = 0x0243) -> int | None:
    w = block.get(letter)
    if w is None:
        return None
    if w.value != int(w.value):
        raise NcAlarm(code, f"{letter} must be an integer in G10")
    return int(w.value)


def g10(ip: "InterpHost", block: "Block") -> Iterator[Event]:
    legacy = ip.profile.legacy
    L = _int(block, "L")
    if L in SERVO_L and not legacy:  # servo parameter read / write through the bench's bus (App. B.3.4.1)
        servo_g10(ip, block, L)
        return
    P = _int(block, "P")
    if L is None:
        if not legacy or P is None:
            raise NcAlarm(0x0207, "G10 needs L")
        L, P = (10, P - 10000) if P > 10000 else (11, P)
    max_tool = 64 if legacy else 512
    words = ip._axis_words(block)
    allowed = {2, 10, 11, 20, 21} | ({30, 1100, 3100, 4100} if legacy else {12, 13, 14, 15})
    if L not in allowed:
        raise NcAlarm(0x021D, f"G10 L{L} is not supported on {ip.profile.name}")
    if L == 2:
        if P is None or not 0 <= P <= 6:
            raise NcAlarm(0x0243, "G10 L2 P must be 0-6")
        target = ip.frames.external if P == 0 else ip.frames.writable_offsets()[P - 1]
        _set_axes(ip, target, words)
        return
    if L == 20:
        if P is None or not 1 <= P <= N_EXT_WCS:
            raise NcAlarm(0x0237, f"G10 L20 P must be 1-{N_EXT_WCS}")
        _set_axes(ip, ip.frames.writable_offsets()[5 + P], words)
        return
    if L == 21:
        if P is None or not 1 <= P <= 4:
            raise NcAlarm(0x0243, "G10 L21 P must be 1-4")
        for a, (w, inc) in words.items():
            key = f"soft limit {P} {a}"
            v = ip.distance(w, a)
            ip.profile.params[key] = ip.profile.params.get(key, 0.0) + v if inc else v
        return
    if L in (10, 11, 12, 13, 14, 15):
        if P is None or not 1 <= P <= max_tool:
            raise NcAlarm(0x021C, f"G10 L{L} P must be 1-{max_tool}")
        t = ip.tools
        r = block.get("R")
        if L in (10, 11):
            table = t.lengths if L == 10 else t.wears
            for a, (w, inc) in words.items():
                v = ip.distance(w, a)
                table[(a, P)] = table.get((a, P), 0.0) + v if inc else v
            if r is not None and ip.profile.is_lathe:
                (t.radius if L == 10 else t.radius_wear)[P] = ip.distance(r)
            elif r is not None:  # mill: R is the length (G91: an increment, N§3.8.3)
                z = "Z" if "Z" in ip.axes else ip.axes[-1]
                v = ip.distance(r)
                table[(z, P)] = v if ip.state.absolute else table.get((z, P), 0.0) + v
            q = block.get("Q")
            if q is not None and ip.profile.is_lathe:
                t.tip[P] = q.value
        elif L in (12, 13):
            if ip.profile.is_lathe:
                raise NcAlarm(0x021D, f"G10 L{L} is for milling only")
            if r is None:
                raise NcAlarm(0x0222, f"G10 L{L} needs R")
            (t.radius if L == 12 else t.radius_wear)[P] = ip.distance(r)
        elif L == 14:
            z = "Z" if "Z" in ip.axes else ip.axes[-1]
            if r is not None:
                t.tolerance[(z, P)] = ip.distance(r)
            else:
                for a, (w, _inc) in words.items():
                    t.tolerance[(a, P)] = ip.distance(w)
        elif L == 15:
            d = block.get("D")
            val = r.value if r is not None else next((w.value for w, _ in words.values()), 0.0)
            key = ("life", P)
            t.life[key] = t.life.get(key, 0.0) + val if d is not None and d.value == 1 else val
        if ip.profile.is_lathe:
            ip._apply_tool_offset()
        return
    if L == 30:
        if P is None:
            raise NcAlarm(0x0222, "G10 L30 needs P (0.01 deg)")
        ip.profile.params["spindle positioning offset"] = P * 0.01
        return
    if L == 1100:
        r, s = block.get("R"), block.get("S")
        if r is not None:
            ip.state.spindle_max = r.value
        if s is not None:
            ip.state.spindle_speed = s.value
            yield Aux("S", s.value, block.line, block.text, program=ip.program_name)
        return
    if L in (3100, 4100):
        if P is None or not 2080 <= P <= 2111:
            raise NcAlarm(0x0243, f"G10 L{L} P must be 2080-2111 (M2080-M2111)")
        ip.vars.mlc.write(1864 + P - 2080, 1.0 if L == 3100 else 0.0)
        return


def _set_axes(ip: "InterpHost", target: dict[str, float], words) -> None:
    for a, (w, inc) in words.items():
        v = ip.distance(w, a)
        if a in ip.profile.diameter_axes:
            v /= 2.0
        target[a] = target.get(a, 0.0) + v if inc else v


def g11(ip: "InterpHost", block: "Block") -> Iterator[Event]:
    L = _int(block, "L")
    if L == 30:
        ip.profile.params["spindle positioning offset"] = ip.profile.param("P405", 0.0)
    return iter(())
