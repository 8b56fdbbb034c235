"""Hole cycles of both machine types (split from nc/cycles/dispatch.py, issue 16): the milling canned
cycles G73-G89 and the lathe guide's G83-G89, each hole streamed as the cycle makes it."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from nc.alarms import NcAlarm
from nc.cycles import holes
from nc.cycles.codes import lathe_hole_clamp
from nc.cycles.common import _builder, _explicit, _finish, _mem, _stream, _target
from nc.moves import Event
from nc.program.blocks import Block


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
