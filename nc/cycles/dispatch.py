"""Entry point the interpreter calls for every cycle block: `run_cycle(host, code, block)`.

`code` is the cycle's function name from `nc.interp.context` (type-A lathe numbers "G70".."G94",
"G32", "G34", lathe hole cycles "G83".."G89", milling "MG73".."MG89"); `host` is the running
interpreter (`nc.interp.context.CycleHost`). Handlers read the block's words, compute the path with
the pure geometry modules and return the events; they leave `host.position` at the cycle's end.
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable, Iterator
from typing import Any

from nc.alarms import NcAlarm
from nc.cycles import holes, lathe_single, threading, turning
from nc.cycles.builder import PathBuilder
from nc.cycles.codes import lathe_hole_clamp
from nc.cycles.profile import segs_from_moves
from nc.moves import Event
from nc.program.blocks import Block

LATHE_CODES = ("G70", "G71", "G72", "G73", "G74", "G75", "G76", "G90", "G92", "G94", "G32", "G34",
               "G83", "G84", "G85", "G87", "G88", "G89")
MILL_CODES = tuple(f"MG{n}" for n in (73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89))
CYCLE_CODES = frozenset(LATHE_CODES + MILL_CODES)
LATHE_PLANE = ("Z", "X")

_memory: "weakref.WeakKeyDictionary[Any, dict]" = weakref.WeakKeyDictionary()


def _mem(host: Any) -> dict:
    own = getattr(host, "cycle_memory", None)
    if isinstance(own, dict):  # the interpreter's own store, so G80 can clear it (`Interpreter._set_modal`)
        return own
    try:
        return _memory.setdefault(host, {})
    except TypeError:  # not weak-referenceable: keep the memory on the host itself
        if not hasattr(host, "_cycle_memory"):
            host._cycle_memory = {}
        return host._cycle_memory


def _d(host: Any, block: Block, letter: str, default: float | None = None) -> float | None:
    w = block.get(letter)
    return host.distance(w) if w is not None else default


def _raw(block: Block, letter: str, default: float | None = None) -> float | None:
    w = block.get(letter)
    return w.value if w is not None else default


def _is_diameter(host: Any, axis: str = "X") -> bool:
    return axis in host.profile.diameter_axes


def _builder(host: Any, block: Block, plane: tuple[str, str] = LATHE_PLANE) -> PathBuilder:
    convert = getattr(host, "work_converter", None)  # the offsets hold through a cycle: precomputed
    return PathBuilder(dict(host.position), plane, block.line, block.text,
                       convert() if convert is not None else host.to_work,
                       getattr(host, "program_name", None), per_rev=bool(host.state.per_rev),
                       css=host.state.surface_speed if host.state.css else None)  # G96 holds in cycles


def _finish(host: Any, b: PathBuilder) -> list[Event]:
    host.position = dict(b.position)
    return b.events


def _stream(host: Any, b: PathBuilder, steps: Iterable[object]) -> Iterator[Event]:
    """Hand the builder's events on as the cycle makes them, one step (hole, peck, pass) at a time:
    K999999999 or P1 Q1 pecks keep memory flat and the run can be stopped meanwhile (decisions B1).
    `host.position` moves to the cycle's end once it is done, as `_finish` does."""
    for _ in steps:
        if b.events:
            yield from b.events
            b.events.clear()
    host.position = dict(b.position)
    yield from b.events
    b.events.clear()


def _has_any(block: Block, letters: str) -> bool:
    return any(block.has(c) for c in letters)


def _target(host: Any, block: Block) -> dict[str, float]:
    return host.to_machine(host.target(block))


def _modal_target(host: Any, block: Block, code: str, axes_letters: dict[str, str]) -> dict[str, float]:
    """End point of a modal lathe cycle: axes not written keep the cycle's previous end point."""
    mem = _mem(host).setdefault("single", {})
    tgt = _target(host, block)
    prev = mem.get(code)
    if prev is not None and _explicit(host, block, code) is False:
        for axis, inc in axes_letters.items():
            if not block.has(axis) and not block.has(inc):
                tgt[axis] = prev[axis]
    mem[code] = dict(tgt)
    return tgt


def _modal_taper(host: Any, block: Block, code: str) -> float:
    """R of G90/G92/G94 is modal like X and Z (Fanuc): a repeat block without R keeps it."""
    mem = _mem(host).setdefault("taper", {})
    if block.has("R"):
        mem[code] = host.distance(block.get("R"))
    elif _explicit(host, block, code):
        mem[code] = 0.0
    return mem.get(code, 0.0)


def _explicit(host: Any, block: Block, code: str) -> bool:
    """Does the block itself carry the cycle's G code (a new cycle rather than a modal repeat)?"""
    from nc.cycles.codes import LATHE_CYCLES, MILL_CYCLES
    if host.profile.is_lathe:
        table = LATHE_CYCLES.get(host.profile.lathe_type or "A", {})
    else:
        table = MILL_CYCLES
    for w in block.all("G"):
        if table.get(int(round(w.value))) == code and abs(w.value - round(w.value)) < 1e-9:
            return True
    return False


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


# ---- hole cycles ----------------------------------------------------------------------------
MILL_KIND = {"MG73": "peck_chip", "MG74": "tap", "MG76": "fine_bore", "MG81": "drill", "MG82": "drill",
             "MG83": "peck_full", "MG84": "tap", "MG85": "bore_feed", "MG86": "bore_stop",
             "MG87": "back_bore", "MG88": "manual", "MG89": "bore_feed"}
MILL_DRILL_AXIS = {17: "Z", 18: "Y", 19: "X"}
PLANE_AXES = {17: ("X", "Y"), 18: ("Z", "X"), 19: ("Y", "Z")}


def _hole_state(host: Any, block: Block, code: str, axis: str) -> dict:
    """Modal words of the hole cycle (X Y Z R P Q F stay until G80) and its initial level."""
    mem = _mem(host)
    st = mem.get("hole")
    here = host.position[axis]
    # the initial level and the modal words (Z R Q P F) survive a change of hole cycle; a cycle
    # commanded again after the tool left the cycle's last level (G80, then a move) starts afresh
    fresh = st is None or (_explicit(host, block, code) and abs(here - st.get("last_level", here)) > 1e-9)
    if fresh:
        st = {"code": code, "initial": here}
        mem["hole"] = st
    st["code"] = code
    return st


def _mill_hole(host: Any, code: str, block: Block) -> Iterator[Event]:
    plane = int(host.state.plane)
    axis = MILL_DRILL_AXIS.get(plane, "Z")
    pos_axes = PLANE_AXES.get(plane, ("X", "Y"))
    if code in ("MG74", "MG84") and not block.has("F") and _explicit(host, block, code):
        # N§3.13.2 note 3: F is a required word of the tapping block (a modal F of a G01 is no lead)
        raise NcAlarm(0x1001, f"G{code[2:]} needs F in its block (tapping feed = lead x S)")
    st = _hole_state(host, block, code, axis)
    absolute = bool(host.state.absolute)
    for letter in ("R", "Q"):
        if block.has(letter):
            st[letter] = host.distance(block.get(letter))
    if block.has(axis):
        st["Z"] = host.distance(block.get(axis))
    if block.has("P"):
        st["P"] = block.get("P").value / 1000.0
    if block.has("F"):
        st["F"] = host.feed(block)
    feed = st.get("F") or host.feed(block)
    k_word = block.get("K")
    repeats = int(k_word.value) if k_word is not None else 1
    work_tgt = host.target(block)
    start_work = host.work_position()
    delta = {a: work_tgt[a] - start_work[a] for a in pos_axes if a in work_tgt}
    if repeats < 1 or "Z" not in st:
        # K0: the cycle is set, nothing is drilled; the tool only positions
        b = _builder(host, block, pos_axes)
        b.rapid_axes({a: host.to_machine(work_tgt)[a] for a in pos_axes})
        yield from _finish(host, b)
        return
    initial = st["initial"]

    def level(work_value: float) -> float:
        w = dict(host.work_position())
        w[axis] = work_value
        return host.to_machine(w)[axis]

    if absolute:
        r_level = level(st["R"]) if "R" in st else initial
        bottom = level(st["Z"])
    else:
        r_level = initial + st.get("R", 0.0)
        bottom = r_level + st["Z"]
    return_r = int(getattr(host.state, "cycle_return", 98)) == 99
    if code == "MG87":
        return_r = False  # back boring always returns to the initial level (decisions A51)
    shift = None
    if code in ("MG76", "MG87"):
        q = abs(st.get("Q", 0.0))
        bits = int(host.profile.param("N1.150", 0)) & 0b11
        a1, a2 = pos_axes
        shift = {0: {a1: q}, 1: {a1: -q}, 2: {a2: q}, 3: {a2: -q}}[bits]
    kind = MILL_KIND[code]
    b = _builder(host, block, pos_axes)
    b.feed = feed
    b.per_rev = bool(host.state.per_rev)
    dwell = st.get("P", 0.0) if code in ("MG82", "MG88", "MG89", "MG76", "MG87", "MG84", "MG74") else 0.0
    here_work = dict(start_work)
    here_machine = host.work_position()  # read once: `host.position` stays put until the cycle ends

    def each_hole() -> Iterator[None]:
        for n in range(repeats):  # lazy: K999999999 holes one at a time (decisions B1)
            for a in delta:
                here_work[a] = start_work[a] + delta[a] * (n + 1) if not absolute else work_tgt[a]
            pos_m = host.to_machine({**here_machine, **{a: here_work[a] for a in delta}})
            hole = holes.Hole(kind, code[1:], axis, {a: pos_m[a] for a in pos_axes}, r_level, bottom, initial,
                              return_r, peck=abs(st.get("Q", 0.0)) if code in ("MG73", "MG83", "MG84", "MG74") else 0.0,
                              clearance=host.profile.param("N1.151", 1.0), dwell=dwell, shift=shift,
                              spindle_dir=int(host.state.spindle_dir), reverse_tap=code == "MG74")
            yield from holes.drill_hole(b, hole)
            yield
        st["last_level"] = b.position[axis]
    yield from _stream(host, b, each_hole())


def _lathe_hole(host: Any, code: str, block: Block) -> Iterator[Event]:
    face = code in ("G83", "G84", "G85")
    axis = "Z" if face else "X"
    st = _hole_state(host, block, code, axis)
    inc_letter = "W" if face else "U"
    if block.has(axis) or block.has(inc_letter):
        st["bottom"] = _target(host, block)[axis]
    for letter in ("R", "Q"):
        if block.has(letter):
            st[letter] = host.distance(block.get(letter))
    if block.has("P"):
        st["P"] = block.get("P").value / 1000.0
    if block.has("L"):
        st["L"] = int(block.get("L").value)
    if block.has("F"):
        st["F"] = host.feed(block)
    if "bottom" not in st:
        raise NcAlarm(0x0231, f"{code} needs the hole bottom ({axis}/{inc_letter})")
    feed = st.get("F") or host.feed(block)
    k_word = block.get("K")
    repeats = int(k_word.value) if k_word is not None else 1
    tgt = _target(host, block)
    if face and "C" not in host.profile.axes and abs(tgt.get("X", 0.0)) > 1e-6:
        # N§3.14 note (3), lathe guide G83/G84/G85: with no C axis the lathe never leaves turning mode, the
        # work spins under the drill and only the centre (X0) can be drilled or tapped
        raise NcAlarm(0xB6A5, f"{code} face hole off the centre (X not 0): drilling there needs the C axis "
                              "(turn-mill mode); without it the hole must be at X0")
    pos_axes = tuple(a for a in host.profile.axes if a != axis)
    initial = st["initial"]
    bottom = st["bottom"]
    sgn = 1.0 if bottom > initial else -1.0
    # R: distance from the initial point toward the hole (decisions A50)
    r_level = initial + sgn * abs(st.get("R", 0.0))
    lathe_type = host.profile.lathe_type or "A"
    return_r = lathe_type != "A" and int(getattr(host.state, "cycle_return", 98)) == 99
    kind = "drill"
    peck = 0.0
    if code in ("G83", "G87"):
        mode = st.get("L")
        if mode is None:
            mode = (int(host.profile.param("N1.150", 0)) >> 2) & 0b11
            if mode == 0 and st.get("Q"):
                mode = 1
        peck = abs(st.get("Q", 0.0)) if mode in (1, 2) else 0.0
        kind = {0: "drill", 1: "peck_full", 2: "peck_chip"}.get(mode, "drill")
        if peck <= 0:
            kind = "drill"
    elif code in ("G84", "G88"):
        kind = "tap"
        peck = abs(st.get("Q", 0.0)) if st.get("L", 1) else 0.0
    else:
        kind = "bore_feed"
    b = _builder(host, block)
    b.feed = feed
    clamp_m = lathe_hole_clamp(host.profile, code, block)

    def each_hole() -> Iterator[None]:
        for _ in range(max(repeats, 0)):  # lazy, as `_mill_hole`
            hole = holes.Hole(kind, code, axis, {a: tgt[a] for a in pos_axes}, r_level, bottom, initial, return_r,
                              peck=peck, clearance=host.profile.param("N1.151", 1.0), dwell=st.get("P", 0.0),
                              spindle_dir=int(host.state.spindle_dir), clamp_m=clamp_m)
            yield from holes.drill_hole(b, hole)
            yield
        st["last_level"] = b.position[axis]
    yield from _stream(host, b, each_hole())


# ---- entry ----------------------------------------------------------------------------------
def run_cycle(host: Any, code: str, block: Block) -> Iterator[Event]:
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
    return iter(events)  # the hole, G73 and G74/G75 cycles are generators: lazy for any K, R, P or Q
