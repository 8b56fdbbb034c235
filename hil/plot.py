"""Tool path pictures for `hil path PROGRAM --plot FILE.png`.

Draws the moves in the active plane (the plane of the first arc or of the profile: Z–X on a lathe,
X–Y on a mill): rapids dashed, cutting moves solid, threads in their own colour, and — when
compensation is on — the programmed contour (thin, grey) next to the compensated tool path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from hil.figures import subplots
from nc.moves import Move

STYLE = {
    "rapid": dict(color="tab:red", linestyle="--", linewidth=0.8),
    "line": dict(color="tab:blue", linestyle="-", linewidth=1.2),
    "arc": dict(color="tab:blue", linestyle="-", linewidth=1.2),
    "thread": dict(color="tab:green", linestyle="-", linewidth=1.2),
}
LABEL = {"rapid": "rapid (G00)", "line": "cutting feed", "arc": "cutting feed", "thread": "thread"}


def move_points(m: Move, plane: tuple[str, str], n_arc: int = 48) -> list[tuple[float, float]]:
    a1, a2 = plane
    p0 = (m.start.get(a1, 0.0), m.start.get(a2, 0.0))
    p1 = (m.end.get(a1, 0.0), m.end.get(a2, 0.0))
    if m.kind != "arc" or m.center is None or tuple(m.plane) != tuple(plane):
        return [p0, p1]
    c = (m.center[a1], m.center[a2])
    r = math.hypot(p0[0] - c[0], p0[1] - c[1])
    a_s = math.atan2(p0[1] - c[1], p0[0] - c[0])
    a_e = math.atan2(p1[1] - c[1], p1[0] - c[0])
    ccw = (a_e - a_s) % (2 * math.pi)
    if math.hypot(p1[0] - p0[0], p1[1] - p0[1]) < 1e-9:
        ccw = 2 * math.pi
    sweep = ccw if m.dir == "ccw" else (ccw - 2 * math.pi if ccw > 0 else -2 * math.pi)
    sweep += 2 * math.pi * m.turns * (1 if sweep > 0 else -1)
    n = max(4, int(n_arc * abs(sweep) / (2 * math.pi)) + 1)
    return [(c[0] + r * math.cos(a_s + sweep * i / n), c[1] + r * math.sin(a_s + sweep * i / n)) for i in range(n + 1)]


def active_plane(moves: Sequence[Move], default: tuple[str, str]) -> tuple[str, str]:
    for m in moves:
        if m.kind == "arc":
            return tuple(m.plane)  # type: ignore[return-value]
    return default


def plot_path(moves: Sequence[Move], path: str, plane: tuple[str, str], programmed: Sequence[Move] | None = None,
              title: str = "", radius_axis: str | None = None) -> None:
    """Write a PNG of the path. `programmed` (optional) is the uncompensated path."""
    fig, ax = subplots(figsize=(10, 6.5), dpi=110)
    seen: set[str] = set()
    compensated = any("comp" in m.tags for m in moves)
    if programmed is not None and compensated:
        first = True
        for m in programmed:
            if m.kind not in STYLE or m.kind == "rapid":
                continue
            pts = move_points(m, plane)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], color="0.55", linewidth=2.4, alpha=0.6,
                    solid_capstyle="round", label="programmed contour" if first else None, zorder=1)
            first = False
    for m in moves:
        if m.kind not in STYLE:
            continue
        pts = move_points(m, plane)
        style = dict(STYLE[m.kind])
        label_key = m.kind if m.kind != "arc" else "line"
        label = LABEL[m.kind]
        if compensated and "comp" in m.tags and m.kind != "rapid":
            style["color"] = "tab:purple"
            label_key, label = "comp", "compensated tool path"
        ax.plot([p[0] for p in pts], [p[1] for p in pts], label=label if label_key not in seen else None,
                zorder=2, **style)
        seen.add(label_key)
    dwell = [m for m in moves if m.kind == "dwell"]
    if dwell:
        ax.scatter([m.start.get(plane[0], 0.0) for m in dwell], [m.start.get(plane[1], 0.0) for m in dwell],
                   marker="o", s=18, color="tab:orange", label="dwell", zorder=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, linewidth=0.3)
    a1, a2 = plane
    ax.set_xlabel(f"{a1} (mm, machine)")
    ax.set_ylabel(f"{a2} (mm, machine{', radius' if radius_axis == a2 else ''})")
    ax.set_title(title or f"tool path, plane {a1}-{a2}")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


def plot_program(moves: Sequence[Move], out: str, profile, make_interpreter, program) -> None:
    """`hil path --plot`: the path as interpreted, plus the programmed contour when compensation is on."""
    from nc.compensation.stream import disabled

    programmed = None
    if any("comp" in m.tags for m in moves):
        with disabled():
            programmed = [ev for ev in make_interpreter().run(program) if isinstance(ev, Move)]
    default = ("Z", "X") if profile.is_lathe else ("X", "Y")
    plane = active_plane(moves, default)
    radius_axis = "X" if "X" in getattr(profile, "diameter_axes", ()) else None
    plot_path(moves, out, plane, programmed, title=f"{program.name}: tool path ({plane[0]}-{plane[1]} plane)",
              radius_axis=radius_axis)
