"""Entry point the interpreter calls for every cycle block: `run_cycle(host, code, block)`.

`code` is the cycle's function name from `nc.interp.context` (type-A lathe numbers "G70".."G94",
"G32", "G34", lathe hole cycles "G83".."G89", milling "MG73".."MG89"); `host` is the running
interpreter (`nc.interp.context.CycleHost`). Handlers read the block's words, compute the path with
the pure geometry modules and return the events; they leave `host.position` at the cycle's end.
The helpers they share are in `nc.cycles.common`, the hole cycles in `nc.cycles.hole_cycles`.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from nc.alarms import NcAlarm
from nc.cycles import lathe_single, threading, turning
from nc.cycles.common import (LATHE_PLANE, _builder, _d, _explicit, _finish, _has_any, _is_diameter,
                              _mem, _modal_taper, _modal_target, _raw, _stream, _target)
from nc.cycles.hole_cycles import _lathe_hole, _mill_hole
from nc.cycles.profile import segs_from_moves
from nc.moves import Event
from nc.program.blocks import Block

LATHE_CODES = ("G70", "G71", "G72", "G73", "G74", "G75", "G76", "G90", "G92", "G94", "G32", "G34",
               "G83", "G84", "G85", "G87", "G88", "G89")
MILL_CODES = tuple(f"MG{n}" for n in (73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89))
CYCLE_CODES = frozenset(LATHE_CODES + MILL_CODES)


# ---- lathe multiple repetitive cycles --------------------------------------------------------
def _contour(host: Any, block: Block) -> list:
    p, q = block.get("P"), block.get("Q")
    if p is None or q is None:
        raise NcAlarm(0x0264, "the cycle needs P and Q (first and last N of the contour)")
    blocks = host.contour_blocks(int(p.value), int(q.value))
    return host.contour_moves(blocks)


def _g71_g72(host: Any, code: str, block: Block) -> list[Event]:
    mem = _mem(host)
    key = f"{code}_first"
    if not (block.has("P") and block.has("Q")):
        depth_letter = "U" if code == "G71" else "W"
        mem[key] = {"depth": _d(host, block, depth_letter), "retract": _d(host, block, "R"),
                    "h": _raw(block, "H"), "line": block.line}
        if block.has("P") or block.has("Q"):
            raise NcAlarm(0x0264, f"{code} needs both P and Q")
        if not host.profile.legacy:
            _check_second_block(host, code, block)
        return []
    first = mem.pop(key, {})
    prm = host.profile.param
    depth = first.get("depth")
    depth = prm("N1.170", 0.0) if depth is None else depth
    retract = first.get("retract")
    retract = prm("N1.171", 0.0) if retract is None else retract
    h = first.get("h")
    h = int(h) if h is not None else 1
    if depth is None or depth <= 0:
        raise NcAlarm(0x0246, f"{code}: no depth of cut (first block {'U' if code == 'G71' else 'W'} "
                              "or parameter N1.170)")
    u = _d(host, block, "U", 0.0) or 0.0
    if _is_diameter(host):
        u /= 2.0
    w = _d(host, block, "W", 0.0) or 0.0
    moves = _contour(host, block)
    b = _builder(host, block)
    b.feed = host.feed(block)
    turning.rough(b, segs_from_moves(moves, LATHE_PLANE),
                  turning.RoughSpec(code, depth, retract, u, w, h))
    return _finish(host, b)


def _check_second_block(host: Any, code: str, block: Block) -> None:
    """N§3.15.2 note (4): G71/G72 is two consecutive blocks; the first (U/W R H) must be followed by the
    second (P Q U W F): another block there is 0x0247, a second G71/G72 naming neither P nor Q is 0x0245
    (decisions language: the two App. A codes of the nested loop)."""
    frame = getattr(host, "frame", None)
    if frame is None:
        return
    blocks = frame.program.blocks
    # the block runs at pc - 1; looked for through the program only when it is not (a program's
    # blocks are parsed as they are reached, issue 16: a scan of all of them per cycle made long programs quadratic)
    pc = getattr(frame, "pc", 0) - 1
    if 0 <= pc < len(blocks) and blocks[pc].line == block.line:
        at: int | None = pc
    else:
        at = next((i for i, b in enumerate(blocks) if b.line == block.line), None)
    if at is None:
        return
    nxt = next((b for b in (blocks[k] for k in range(at + 1, len(blocks))) if b.words or b.stmt is not None), None)
    try:
        second = nxt is not None and nxt.stmt is None and _explicit(host, nxt, code)
    except (TypeError, ValueError):  # a G word given by an expression: judged when it runs
        return
    if not second:
        raise NcAlarm(0x0247, f"{code} (first block) must be followed by its second block {code} P_ Q_"
                              + (f"; line {nxt.line} is {nxt.text.strip()!r}" if nxt is not None else ""))
    if not (nxt.has("P") or nxt.has("Q")):
        raise NcAlarm(0x0245, f"the second {code} block (line {nxt.line}) names neither P nor Q "
                              "(the contour's first and last N)")


def _g73(host: Any, block: Block) -> Iterator[Event]:
    mem = _mem(host)
    if not (block.has("P") and block.has("Q")):
        mem["G73_first"] = {"i": _d(host, block, "U"), "k": _d(host, block, "W"), "d": _raw(block, "R")}
        return
    first = mem.pop("G73_first", {})
    prm = host.profile.param
    i = first.get("i")
    i = prm("P345", 0.0) if i is None else i
    k = first.get("k")
    k = prm("P346", 0.0) if k is None else k
    d = first.get("d")
    d = prm("P347", 0.0) if d is None else d
    u = _d(host, block, "U", 0.0) or 0.0
    if _is_diameter(host):
        u /= 2.0
    w = _d(host, block, "W", 0.0) or 0.0
    moves = _contour(host, block)
    b = _builder(host, block)
    b.feed = host.feed(block)
    yield from _stream(host, b, turning.pattern(b, segs_from_moves(moves, LATHE_PLANE), i, k, d, u, w))


def _g70(host: Any, block: Block) -> list[Event]:
    p, q = block.get("P"), block.get("Q")
    if p is None or q is None:
        raise NcAlarm(0x0233, "G70 needs P and Q")
    moves = host.contour_moves(host.contour_blocks(int(p.value), int(q.value)))
    b = _builder(host, block)
    turning.finish(b, moves)
    return _finish(host, b)


# ---- grooving -------------------------------------------------------------------------------
def _g74_g75(host: Any, code: str, block: Block) -> Iterator[Event]:
    mem = _mem(host)
    if not _has_any(block, "XZUWPQF"):
        mem[f"{code}_first"] = _d(host, block, "R", 0.0)
        return
    e = mem.pop(f"{code}_first", None)
    if e is None:
        e = host.profile.param("P348", 0.0)
    tgt = _target(host, block)
    p_amt = abs(_d(host, block, "P", 0.0) or 0.0)
    q_amt = abs(_d(host, block, "Q", 0.0) or 0.0)
    escape = abs(_d(host, block, "R", 0.0) or 0.0)
    b = _builder(host, block)
    b.feed = host.feed(block)
    end = (tgt["Z"], tgt["X"])
    if code == "G74":  # peck in Z by Q, shift in X by P
        steps = lathe_single.peck_groove(b, end, p_amt, q_amt, escape, e, True, code)
    else:  # peck in X by P, shift in Z by Q
        steps = lathe_single.peck_groove(b, end, q_amt, p_amt, escape, e, False, code)
    yield from _stream(host, b, steps)


# ---- threading ------------------------------------------------------------------------------
def _thread_chamfer(host: Any, lead: float) -> tuple[float, float]:
    prm = host.profile.param
    return 0.1 * prm("N1.178", 10.0) * lead, prm("N1.177", 45.0)


def _g76(host: Any, block: Block) -> list[Event]:
    mem = _mem(host)
    if not _has_any(block, "XZUW"):
        pw = block.get("P")
        first: dict[str, float] = {}
        if pw is not None:
            pv = int(round(pw.value))
            first.update(m=pv // 10000, r=(pv // 100) % 100, a=pv % 100)
        first["dmin"] = _d(host, block, "Q", 0.0) or 0.0
        first["d"] = _d(host, block, "R", 0.0) or 0.0
        mem["G76_first"] = first
        return []
    first = mem.pop("G76_first", {})
    prm = host.profile.param
    lead = host.feed(block)
    m = int(first.get("m", prm("P381", 1)))
    r = first.get("r", prm("N1.178", 10.0))
    a = first.get("a", prm("P382", 60.0))
    tgt = _target(host, block)
    height = _d(host, block, "P")
    dd = _d(host, block, "Q")
    if height is None or dd is None:
        raise NcAlarm(0x0232, "G76 second block needs P (thread height) and Q (first depth)")
    spec = threading.G76Spec(end=(tgt["Z"], tgt["X"]), taper=_d(host, block, "R", 0.0) or 0.0,
                             height=abs(height), first=abs(dd), min_step=abs(first.get("dmin", 0.0)),
                             allowance=abs(first.get("d", 0.0)), finish_passes=m,
                             chamfer=0.1 * r * lead, chamfer_angle=prm("N1.177", 45.0), tool_angle=a,
                             lead=lead, infeed=int(_raw(block, "L", 0) or 0))
    b = _builder(host, block)
    threading.g76(b, spec)
    return _finish(host, b)


def _g92(host: Any, block: Block) -> list[Event]:
    tgt = _modal_target(host, block, "G92", {"X": "U", "Z": "W"})
    taper = _modal_taper(host, block, "G92")
    mem = _mem(host).setdefault("g92", {})
    if block.has("F"):
        mem["lead"] = host.feed(block)
    lead = mem.get("lead") or host.feed(block)
    angle = (_raw(block, "Q", 0.0) or 0.0) / 1000.0
    chamfer, ch_angle = _thread_chamfer(host, lead)
    b = _builder(host, block)
    threading.g92(b, (tgt["Z"], tgt["X"]), taper, lead, angle, chamfer, ch_angle)
    return _finish(host, b)


def _g32_g34(host: Any, code: str, block: Block) -> list[Event]:
    tgt = _target(host, block)
    lead = host.feed(block)
    angle = (_raw(block, "Q", 0.0) or 0.0) / 1000.0
    b = _builder(host, block)
    k = 0.0
    if code == "G34":
        k = _d(host, block, "K", 0.0) or 0.0
        dz = abs(tgt["Z"] - b.here[0])
        dx = abs(tgt["X"] - b.here[1])
        threading.g34_check(max(dz, dx), lead, k)
    b.thread((tgt["Z"], tgt["X"]), lead, angle, (code, "thread"), k)
    return _finish(host, b)


# ---- single cycles --------------------------------------------------------------------------
def _g90_g94(host: Any, code: str, block: Block) -> list[Event]:
    tgt = _modal_target(host, block, code, {"X": "U", "Z": "W"})
    taper = _modal_taper(host, block, code)
    b = _builder(host, block)
    b.feed = host.feed(block)
    if code == "G90":
        lathe_single.g90(b, (tgt["Z"], tgt["X"]), taper)
    else:
        lathe_single.g94(b, (tgt["Z"], tgt["X"]), taper)
    return _finish(host, b)



# ---- entry ----------------------------------------------------------------------------------
def run_cycle(host: Any, code: str, block: Block) -> Iterator[Event] | list[Event]:
    if code not in CYCLE_CODES:
        raise NcAlarm(0x021D, f"cycle {code} is not supported")
    if code in ("G71", "G72"):
        events = _g71_g72(host, code, block)
    elif code == "G73":
        events = _g73(host, block)
    elif code == "G70":
        events = _g70(host, block)
    elif code in ("G74", "G75"):
        events = _g74_g75(host, code, block)
    elif code == "G76":
        events = _g76(host, block)
    elif code == "G92":
        events = _g92(host, block)
    elif code in ("G32", "G34"):
        events = _g32_g34(host, code, block)
    elif code in ("G90", "G94"):
        events = _g90_g94(host, code, block)
    elif code.startswith("MG"):
        events = _mill_hole(host, code, block)
    else:
        events = _lathe_hole(host, code, block)
    # the hole, G73 and G74/G75 cycles are generators: lazy for any K, R, P or Q; the others' list as it
    # is (the interpreter hands a computed list on as one event to a consumer that takes them)
    return events if type(events) is list else iter(events)
