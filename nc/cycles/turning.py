"""Lathe multiple repetitive cycles on a finishing contour: G71/G72 roughing, G73 pattern repeat,
G70 finishing (type A numbering; types B/C map onto these in `nc.cycles.dispatch`).

All geometry is in the lathe plane (Z, X radius) in machine coordinates. Decisions A45/A46
(docs/decisions/cycles.md) fix what the manuals leave open: Fanuc type I/II, H0 = layers with 45°
escape only, H1 = layers plus a final pass along the contour with allowance, the cycle ends at its
start point, ,C/,R inside P–Q arrive already expanded, G41/G42 is ignored in roughing.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from nc.alarms import NcAlarm
from nc.cycles.builder import PathBuilder
from nc.cycles.geometry import Pt, Seg
from nc.cycles.profile import Contour, Frame, shifted

MAX_PASSES = 5000


@dataclass
class RoughSpec:
    code: str  # "G71" (turning, layers in X) or "G72" (facing, layers in Z)
    depth: float  # depth of cut per layer (radius), > 0
    retract: float  # escape amount e (radius), ≥ 0
    u: float  # X allowance (radius, signed: + shifts the contour toward +X)
    w: float  # Z allowance (signed)
    h: int = 1  # 0: fast escaping (layers only), 1: layers + final pass along the profile


def split_contour(segs: list[Seg]) -> tuple[list[Seg], list[Seg], list[Seg]]:
    """(leading rapids = approach, cutting contour, trailing rapids = departure)."""
    i, j = 0, len(segs)
    while i < j and segs[i].rapid:
        i += 1
    while j > i and segs[j - 1].rapid:
        j -= 1
    return segs[:i], segs[i:j], segs[j:]


def _frame(code: str, start: Pt, contour: list[Seg]) -> Frame:
    """Pick the quadrant from the geometry: stock lies between the contour and the start point."""
    pts = [p for s in contour for p in (s.p0, s.p1)]
    first, last = contour[0].p0, contour[-1].p1
    if code == "G71":  # f along Z (first), d along X (second)
        mean_x = sum(p[1] for p in pts) / len(pts)
        sx = 1.0 if start[1] >= mean_x else -1.0
        sz = 1.0 if last[0] <= first[0] else -1.0
        return Frame(False, sz, sx)
    mean_z = sum(p[0] for p in pts) / len(pts)
    sz = 1.0 if start[0] >= mean_z else -1.0
    sx = 1.0 if last[1] <= first[1] else -1.0
    return Frame(True, sz, sx)


def rough(b: PathBuilder, contour_segs: list[Seg], spec: RoughSpec) -> None:
    """G71 / G72: layers parallel to the cutting axis down to the contour plus allowance."""
    if spec.depth <= 0:
        raise NcAlarm(0x0246, f"{spec.code} depth of cut must be positive (got {spec.depth:g})")
    if spec.retract < 0:
        raise NcAlarm(0x0246, f"{spec.code} escape amount must not be negative")
    start = b.here
    approach, cut, _ = split_contour(contour_segs)
    if not cut:
        raise NcAlarm(0x0246, f"{spec.code}: the P–Q contour has no cutting move")
    # allowance is a translation of the contour (Fanuc): +u toward +X, +w toward +Z
    cut = shifted(cut, spec.w, spec.u)
    frame = _frame(spec.code, start, cut)
    first_block_moves_f = (frame.to_fd(contour_segs[0].p0)[0] - frame.to_fd(contour_segs[0].p1)[0]) > 1e-9
    type_one = not first_block_moves_f
    fd = [frame.seg_to_fd(s) for s in cut]
    prof = Contour(fd, type_one)
    a_f, a_d = frame.to_fd(start)
    if a_d < prof.d_min - 1e-9:
        raise NcAlarm(0x0246, f"{spec.code}: the start point lies inside the finished contour")
    # a start point level with the contour start (the allowance may shift the contour past it) is
    # fine: the layers begin at the farther of the two
    e = spec.retract
    safe = max(a_d, prof.d_max) + max(e, 0.0)
    infeed_rapid = bool(approach) or contour_segs[0].rapid

    to_plane, emit = frame.from_fd, b._to  # the builder's lean path directly (a call less per move)

    def rapid(q: Pt, tags: tuple[str, ...]) -> None:
        emit("rapid", to_plane(q), tags, None, False)

    def feed(q: Pt, tags: tuple[str, ...]) -> None:
        emit("line", to_plane(q), tags, b.feed, b.per_rev)  # `b.feed_to` without its default feed

    def here() -> Pt:
        return frame.to_fd(b.here)

    def transfer(f: float, d: float, tags: tuple[str, ...]) -> None:
        """Rapid over everything: up to the safe level, across, down to d."""
        cf, cd = here()
        if abs(cf - f) > 1e-9:
            if cd < safe - 1e-12:
                rapid((cf, safe), tags)
            rapid((f, safe), tags)
        rapid((f, d), tags)

    levels: list[float] = []
    k = 1
    while True:
        lv = a_d - k * spec.depth
        if lv <= prof.d_min + 1e-9:
            if not levels or levels[-1] > prof.d_min + 1e-6:
                if a_d > prof.d_min + 1e-6:
                    levels.append(prof.d_min)
            break
        levels.append(lv)
        k += 1
        if k > MAX_PASSES:
            raise NcAlarm(0x0246, f"{spec.code}: more than {MAX_PASSES} roughing layers")

    code = spec.code
    prev_level = a_d
    simple = True  # the tool sits at a retract point from which a straight rapid back to the face is clear
    for n, lv in enumerate(levels, start=1):
        spans = prof.intervals(lv)
        for hi, lo in spans:
            tags = (code, "rough", str(n))
            if hi >= prof.f_start - 1e-7:  # the layer starts at the stock face
                tf = max(a_f, hi)
                cd = here()[1]
                if simple:
                    rapid((tf, cd), (code, "return"))
                else:
                    transfer(tf, prev_level, (code, "return"))
                if infeed_rapid:
                    rapid((tf, lv), (code, "infeed"))
                else:
                    feed((tf, lv), (code, "infeed"))
            else:  # a pocket: come down where the contour crosses this layer and plunge
                transfer(hi, prev_level, (code, "transfer"))
                feed((hi, lv), (code, "plunge", str(n)))
            feed((lo, lv), tags)
            r = min(e, hi - lo)
            rapid((lo + r, lv + e), (code, "retract"))
        simple = len(spans) == 1 and spans[0][0] >= prof.f_start - 1e-7
        prev_level = lv

    if spec.h == 1:
        transfer(a_f, a_d, (code, "return"))
        p0 = frame.to_fd(cut[0].p0)
        if infeed_rapid:
            rapid(p0, (code, "infeed"))
        else:
            feed(p0, (code, "infeed"))
        for s in cut:
            if frame.to_fd(s.p0) != here():
                rapid(frame.to_fd(s.p0), (code, "profile"))
            b.seg(s, (code, "profile"), rapid=False)
    transfer(a_f, a_d, (code, "return"))


def pattern(b: PathBuilder, contour_segs: list[Seg], total_x: float, total_z: float, count: int,
            u: float, w: float, code: str = "G73") -> Iterator[None]:
    """G73: the whole contour repeated `count` times, stepping from (i+u, k+w) to (u, w); yields
    after each pass so a huge R streams instead of filling memory (decisions B1)."""
    if count < 2 or count != int(count):
        raise NcAlarm(0x0246, f"{code} needs an integer number of cuts R ≥ 2 (got {count:g})")
    start = b.here
    n_cuts = int(count)
    for n in range(1, n_cuts + 1):
        frac = (n_cuts - n) / (n_cuts - 1)
        dz, dx = total_z * frac + w, total_x * frac + u
        path = shifted(contour_segs, dz, dx)
        tags = (code, "pass", str(n))
        for idx, s in enumerate(path):
            if idx == 0:
                # the P block runs from the start point to the shifted contour start
                if s.rapid:
                    b.rapid(s.p1, tags)
                else:
                    b.feed_to(s.p1, tags)
                continue
            if abs(s.p0[0] - b.here[0]) > 1e-9 or abs(s.p0[1] - b.here[1]) > 1e-9:
                b.rapid(s.p0, tags)
            b.seg(s, tags)
        b.rapid(start, (code, "return"))
        yield


def finish(b: PathBuilder, moves: list, code: str = "G70") -> None:
    """G70: the P–Q blocks as programmed (their own F, rapids, compensation), then back to the start."""
    start_pos = dict(b.position)
    last_comp = None
    for m in moves:
        m.tags = tuple(m.tags) + (code, "finish")
        b.events.append(m)
        if hasattr(m, "end"):
            b.position = dict(m.end)
            last_comp = (m.comp, m.comp_radius, m.tip)
    mv = b.rapid_axes(start_pos, (code, "return"))
    if mv is not None and last_comp is not None:
        mv.comp, mv.comp_radius, mv.tip = last_comp
