"""Helpers for the cycle / compensation tests: run `hil path --json` in-process and look at the
geometry a machinist checks (passes, depths, distances to the programmed contour)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

from hil.cli import main
from nc.cycles.geometry import Seg, point_seg_distance


@dataclass
class Path:
    code: int
    moves: list[dict] = field(default_factory=list)
    alarm: dict | None = None

    def tagged(self, *tags: str) -> list[dict]:
        return [m for m in self.moves if all(t in m.get("tags", []) for t in tags)]


def run(capsys, tmp_path, text: str, *args: str, profile: str = "nc5-lathe-a", name: str = "p.nc") -> Path:
    f = tmp_path / name
    f.write_text(text)
    capsys.readouterr()
    code = main(["path", str(f), "--json", "--profile", profile, *args])
    out = capsys.readouterr().out
    p = Path(code)
    for line in out.splitlines():
        if not line.strip():
            continue
        d = json.loads(line)
        if d.get("kind") == "alarm":
            p.alarm = d
        elif d.get("kind") in ("rapid", "line", "arc", "thread", "dwell"):
            p.moves.append(d)
    return p


def zx(d: dict) -> tuple[float, float]:
    """(Z, X radius) of a machine point dict."""
    return (d["Z"], d["X"])


def seg_of(m: dict, plane: tuple[str, str] = ("Z", "X")) -> Seg:
    a1, a2 = plane
    p0, p1 = (m["start"][a1], m["start"][a2]), (m["end"][a1], m["end"][a2])
    if m["kind"] == "arc":
        return Seg(p0, p1, (m["center"][a1], m["center"][a2]), m["dir"] == "cw")
    return Seg(p0, p1)


def polyline(points: list[tuple[float, float]]) -> list[Seg]:
    return [Seg(a, b) for a, b in zip(points, points[1:])]


def contour_x(segs: list[Seg], z: float) -> float:
    """Largest X of the contour at Z (the contour as a function of Z, vertical pieces ignored)."""
    best = -math.inf
    for s in segs:
        lo, hi = sorted((s.p0[0], s.p1[0]))
        if hi - lo < 1e-12 or not lo - 1e-9 <= z <= hi + 1e-9:
            continue
        if s.is_arc:
            c, r = s.center, s.radius
            for sign in (1, -1):
                x = c[1] + sign * math.sqrt(max(r * r - (z - c[0]) ** 2, 0.0))
                if point_seg_distance((z, x), s) < 1e-7:
                    best = max(best, x)
        else:
            t = (z - s.p0[0]) / (s.p1[0] - s.p0[0])
            best = max(best, s.p0[1] + t * (s.p1[1] - s.p0[1]))
    return best


def samples(m: dict, n: int = 12, plane: tuple[str, str] = ("Z", "X")) -> list[tuple[float, float]]:
    return seg_of(m, plane).samples(n)


def distance_to(segs: list[Seg], p: tuple[float, float]) -> float:
    return min(point_seg_distance(p, s) for s in segs)


def assert_outside(moves, contour, tol=1e-6, face=False):
    """No point of any move lies below the contour (X as a function of Z) inside its Z range.
    face=True (G72 contours with pockets in Z): no point lies below Z as a function of X."""
    if face:
        contour = [s.mapped(lambda p: (p[1], p[0]), True) for s in contour]
    zs = [p[0] for s in contour for p in (s.p0, s.p1)]
    lo, hi = min(zs), max(zs)
    for m in moves:
        for z, x in samples(m, 8):
            a, b = (x, z) if face else (z, x)
            if lo + 1e-9 < a < hi - 1e-9:
                c = contour_x(contour, a)
                assert b >= c - tol or distance_to(contour, (a, b)) < tol, f"line {m['line']} {m.get('tags')} cuts into the contour at Z{z:.4f}: X{x:.4f}"
