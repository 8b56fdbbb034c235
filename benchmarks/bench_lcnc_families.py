"""Motion families beyond dense CAM through `hil run` and headless LinuxCNC 2.9, with a jerk-aware reference.

For each family (arcs, helices, rapids, G61/G64, corners, pocketing, arcs near the centripetal limit,
drilling, feed override) prints the program time of hil and of LinuxCNC (simulated 1 ms cycles, first to
last change of commanded position), and two reference times of our own for the same path at the
bench's limits: `ref_a` with the acceleration limit only (what a controller without a jerk limit, like
LinuxCNC 2.9, could reach) and `ref_j` with the jerk limit too. ref_j / ref_a is the share of the gap the
jerk limit explains; `ref_jf` adds what the bench's position filter (N1.036 + N1.037, as on an NC5) costs:
n1 + n2 - 2 cycles at every stop and an arc's speed within its radius shrink bound (decision motion 64), and `excess` = (hil / LinuxCNC) / (ref_jf / ref_a) - 1 is the part neither
explains. Asserts nothing (wall clock is not measured at all).

    python benchmarks/bench_lcnc_families.py [--only NAME] [--keep DIR] [--no-linuxcnc]

The references cut the path into pieces (see `Piece`): a line or an arc between two points where the
speed is capped (a stop, a corner, the arc's centripetal limit). Each piece is the 1-D time-optimal
profile (ruckig) between its end caps, from and to zero acceleration, with the piece's own speed cap:
- an arc of radius r at feed F: v <= min(F, sqrt(A r), (J r^2)^(1/3)) (axis acceleration v^2/r and axis
  jerk v^3/r^2 of a circle's components), tangential a, j up to sqrt(2) A, sqrt(2) J (the best XY direction);
- a line in direction d: v, a, j up to min over the axes of limit / |d_i|;
- a G64 corner of turn angle t with tolerance P: the arc tangent to both legs whose midpoint is P from
  them, radius r = P / (1 - cos(t/2)), capped as an arc; a G61 corner, a rapid's end, a hole's bottom: v = 0.
The corner arcs' own (short) length is not taken off the legs, and a piece starts at a = 0: the figures are
references to read the gap by, not strict lower bounds.
LinuxCNC's G83 retracts to R after every peck and re-enters rapid to 0.254 mm above the last depth (its
manual); NC5's G83 (N§ G83, d = N-parameter clearance) does the same with its own clearance: both are
listed, and compared only on the total.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from ruckig import InputParameter, Result as RResult, Ruckig, Trajectory

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from benchmarks.bench_vs_linuxcnc import (BENCH, LCNC_DIR, TOL, arguments, hil_trace, motion_window,  # noqa: E402
                                          workplace)

A_XY, J_XY, V_XY = 5000.0, 250_000.0, 500.0  # benches/mill-3axis.toml (X and Y alike)
A_Z, J_Z, V_Z = 3000.0, 150_000.0, 300.0
LIM = np.array([[V_XY, A_XY, J_XY], [V_XY, A_XY, J_XY], [V_Z, A_Z, J_Z]])
START = np.array([0.0, 0.0, 100.0])


@dataclass
class Piece:
    length: float
    vmax: float  # mm/s, the piece's cap (feed, axis or curvature)
    amax: float
    jmax: float
    v0: float = 0.0  # speed caps at the piece's ends
    v1: float = 0.0
    vmax_a: float | None = None  # the cap without a jerk limit (arcs: sqrt(A r) only), default vmax
    v0_a: float | None = None
    v1_a: float | None = None
    radius: float = 0.0  # an arc's: the position filter caps its speed (ref_jf)


def profile_time(length: float, vmax: float, amax: float, jmax: float, v0: float, v1: float) -> float:
    """Time-optimal 1-D profile over `length` from v0 to v1 (a = 0 at both ends), |v| <= vmax."""
    if length <= 1e-9:
        return 0.0
    v0, v1 = min(v0, vmax), min(v1, vmax)
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [v0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [length], [v1], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vmax], [amax], [jmax]
    traj = Trajectory(1)
    if Ruckig(1).calculate(inp, traj) not in (RResult.Working, RResult.Finished):
        raise ValueError(f"ruckig: no profile for {length, vmax, amax, jmax, v0, v1}")
    return float(traj.duration)


FILTER_S = 0.030  # N1.036 + N1.037 of the bench (16 + 16 ms): its moving averages lengthen a move by n1 + n2 - 2 cycles


def filter_ref(pieces: list[Piece]) -> float:
    """ref_j with what the bench's position filter costs: n1 + n2 - 2 cycles at every stop (a piece ending at
    rest), and an arc's speed within its radius shrink bound (decision motion 64: n = 16, N1.053 = TOL)."""
    t = 0.0
    for p in pieces:
        cap = p.vmax if p.radius <= 0.0 else min(p.vmax, math.sqrt(24.0 * TOL * p.radius / (2 * 255 * 1e-6)))
        t += profile_time(p.length, cap, p.amax, p.jmax, min(p.v0, cap), min(p.v1, cap))
    return t + FILTER_S * sum(1 for p in pieces if p.v1 <= 0.0)


def references(pieces: list[Piece]) -> tuple[float, float]:
    """(ref_a, ref_j): the pieces' summed times with the acceleration limit only, and with jerk too."""
    ref_j = sum(profile_time(p.length, p.vmax, p.amax, p.jmax, p.v0, p.v1) for p in pieces)
    ref_a = sum(profile_time(p.length, p.vmax if p.vmax_a is None else p.vmax_a, p.amax, 1e9 * p.amax,
                             p.v0 if p.v0_a is None else p.v0_a, p.v1 if p.v1_a is None else p.v1_a)
                for p in pieces)
    return ref_a, ref_j


# ---- geometry caps -----------------------------------------------------------------------------
def line_caps(d: np.ndarray, feed: float | None) -> tuple[float, float, float]:
    u = np.abs(d) / np.linalg.norm(d)
    with np.errstate(divide="ignore"):
        v, a, j = (float(np.min(LIM[:, k] / np.where(u > 1e-12, u, np.nan), initial=np.inf, where=u > 1e-12))
                   for k in range(3))
    return (v if feed is None else min(v, feed / 60.0)), a, j


def arc_cap(r: float, feed: float) -> tuple[float, float]:
    """(with jerk, acceleration only) speed cap on an XY arc of radius r."""
    va = min(feed / 60.0, math.sqrt(A_XY * r))
    return min(va, (J_XY * r * r) ** (1.0 / 3.0)), va


def corner_cap(turn: float, feed: float, tol: float | None) -> tuple[float, float]:
    """(with jerk, acceleration only) speed cap through a corner turning by `turn` rad within `tol` mm."""
    if turn < 1e-9:
        return feed / 60.0, feed / 60.0
    if tol is None:  # no tolerance limit: LinuxCNC's bare G64; the filter's own corners in hil
        return feed / 60.0, feed / 60.0
    if tol <= 0.0 or turn >= math.pi - 1e-9:
        return 0.0, 0.0
    r = tol / (1.0 - math.cos(turn / 2.0))  # the arc's midpoint `tol` from the legs (not the vertex)
    return arc_cap(r, feed)


def line_piece(p: np.ndarray, q: np.ndarray, feed: float | None, c0=(0.0, 0.0), c1=(0.0, 0.0)) -> Piece:
    v, a, j = line_caps(q - p, feed)
    return Piece(float(np.linalg.norm(q - p)), v, a, j, c0[0], c1[0], None, c0[1], c1[1])


def arc_piece(r: float, sweep: float, feed: float, dz: float = 0.0, c0=(0.0, 0.0), c1=(0.0, 0.0)) -> Piece:
    vj, va = arc_cap(r, feed)
    length = math.hypot(r * sweep, dz)
    return Piece(length, vj, math.sqrt(2) * A_XY, math.sqrt(2) * J_XY, c0[0], c1[0], va, c0[1], c1[1], r)


def polyline_pieces(pts: list[np.ndarray], feed: float | None, tol: float | None) -> list[Piece]:
    """Lines through `pts`, corners within `tol` (None: no limit, 0: stop), rest at both ends."""
    caps = [(0.0, 0.0)]
    for a, b, c in zip(pts, pts[1:], pts[2:]):
        u, w = b - a, c - b
        turn = math.acos(max(-1.0, min(1.0, float(u @ w / np.linalg.norm(u) / np.linalg.norm(w)))))
        caps.append(corner_cap(turn, feed if feed else 60.0 * V_XY, tol))
    caps.append((0.0, 0.0))
    return [line_piece(a, b, feed, caps[k], caps[k + 1]) for k, (a, b) in enumerate(zip(pts, pts[1:]))]


# ---- families ------------------------------------------------------------------------------------
@dataclass
class Family:
    name: str
    body: list[str]  # G-code after the header, decimal points written (NC5 reads X10 as 10 µm)
    pieces: list[Piece]
    lcnc_head: str = f"G64 P{TOL}"  # the path mode LinuxCNC runs with (hil: N1.053 = {TOL} mm)
    hil_head: str = ""
    override: float = 100.0  # feed override, % (both runs)
    note: str = ""

    def text(self, lcnc: bool) -> str:
        head = ["G21 G17 G90 G94", self.lcnc_head if lcnc else self.hil_head]
        return "\n".join([h for h in head if h] + self.body + ["M30", ""])


def f(x: float) -> str:
    """A word's value with its decimal point always written: NC5 reads X10 as 10 µm, X10. as 10 mm."""
    s = f"{x:.4f}".rstrip("0")
    return "0." if s == "-0." else s


def xyz(x=None, y=None, z=None) -> str:
    return " ".join(f"{a}{f(v)}" for a, v in (("X", x), ("Y", y), ("Z", z)) if v is not None)


def P(x, y, z=100.0) -> np.ndarray:
    return np.array([x, y, z], dtype=float)


def arc_family(name: str, r: float, turns: float, feed: float) -> Family:
    """A lead-in line from the origin to (r, 0), then `turns` full CCW circles (G3) centred at the origin."""
    body = [f"G1 {xyz(r, 0.0)} F{f(feed)}"]
    body += [f"G3 {xyz(r, 0.0)} I{f(-r)} J0." for _ in range(int(turns))]
    lead = line_piece(START, P(r, 0), feed, (0, 0), (0, 0))  # the arc starts at 90 deg to the lead-in
    return Family(name, body, [lead, arc_piece(r, 2 * math.pi * turns, feed)])


def half_arc(name: str, r: float, feed: float) -> Family:
    body = [f"G1 {xyz(r, 0.0)} F{f(feed)}", f"G3 {xyz(-r, 0.0)} I{f(-r)} J0."]
    return Family(name, body, [line_piece(START, P(r, 0), feed), arc_piece(r, math.pi, feed)])


def tangent_chain(r: float = 5.0, n: int = 8, feed: float = 6000.0) -> Family:
    """S-curve: half circles of radius r alternating G2/G3 along X (curvature flips at each joint)."""
    body = [f"{'G2' if k % 2 == 0 else 'G3'} {xyz(2 * r * (k + 1), 0.0)} I{f(r)} J0." + (f" F{f(feed)}" if k == 0 else "")
            for k in range(n)]
    # the flips (curvature -1/r to +1/r) are not capped here: see the section in docs/performance/motion.md
    return Family(f"tangent arcs R{r:g} x{n} S-chain", body, [arc_piece(r, math.pi * n, feed)])


def arc_line_arc(r: float = 10.0, side: float = 50.0, feed: float = 6000.0, laps: int = 2) -> Family:
    """An obround (slot) contour: two straight sides joined tangentially by half circles of radius r."""
    body = [f"G1 {xyz(0.0, -r)} F{f(feed)}"]
    for _ in range(laps):
        body += [f"G1 {xyz(side, -r)}", f"G3 {xyz(side, r)} I0. J{f(r)}", f"G1 {xyz(0.0, r)}",
                 f"G3 {xyz(0.0, -r)} I0. J{f(-r)}"]
    vj, va = arc_cap(r, feed)
    pieces = [line_piece(START, P(0, -r), feed)]
    for k in range(laps):
        first, last = k == 0, k == laps - 1
        pieces += [line_piece(P(0, -r), P(side, -r), feed, (0, 0) if first else (vj, va), (vj, va)),
                   arc_piece(r, math.pi, feed, 0, (vj, va), (vj, va)),
                   line_piece(P(side, r), P(0, r), feed, (vj, va), (vj, va)),
                   arc_piece(r, math.pi, feed, 0, (vj, va), (0, 0) if last else (vj, va))]
    return Family(f"arc-line-arc slot R{r:g} x{laps}", body, pieces)


def helix(r: float = 10.0, pitch: float = 2.0, turns: int = 3, feed: float = 3000.0) -> Family:
    body = [f"G1 {xyz(r, 0.0)} F{f(feed)}"]
    for k in range(turns):
        body.append(f"G3 {xyz(r, 0.0, 100.0 - pitch * (k + 1))} I{f(-r)} J0.")
    return Family(f"helix R{r:g} pitch {pitch:g} x{turns}", body,
                  [line_piece(START, P(r, 0), feed), arc_piece(r, 2 * math.pi * turns, feed, pitch * turns)])


def rapids() -> Family:
    pts = [START, P(100, 50, 80), P(-100, -50, 50), P(150, -80, 100), P(0, 0, 100)]
    body = [f"G0 {xyz(*p)}" for p in pts[1:]]
    return Family("G0 rapid chain 4 moves", body, [line_piece(a, b, None) for a, b in zip(pts, pts[1:])],
                  note="NC5 G0: each rapid ends at rest (no blending); LinuxCNC blends G0 under G64")


def square(mode: str, side: float = 50.0, feed: float = 6000.0, laps: int = 2) -> Family:
    pts = [START] + [P(x, y) for _ in range(laps) for x, y in ((side, 0), (side, side), (0, side), (0, 0))]
    body = [f"G1 {xyz(*pts[1])} F{f(feed)}"] + [f"{xyz(*p)}" for p in pts[2:]]
    tol = {"G61": 0.0, f"G64 P{TOL}": TOL, "G64": None}[mode]
    fam = Family(f"square 50 mm x{laps} {mode}", body, polyline_pieces(pts, feed, tol), lcnc_head=mode,
                 hil_head="G61" if mode == "G61" else "G64")
    if mode == "G64":
        fam.note = "LinuxCNC bare G64: no tolerance; hil keeps N1.053"
    return fam


def corners(turn_deg: float, seg: float = 2.0, n: int = 20, feed: float = 3000.0) -> Family:
    """A zig-zag of n lines of `seg` mm, turning by turn_deg at every corner (alternating sides)."""
    half = math.radians(turn_deg) / 2.0
    pts = [START]
    for k in range(n):
        ang = half if k % 2 == 0 else -half
        pts.append(pts[-1] + seg * np.array([math.cos(ang), math.sin(ang), 0.0]))
    body = [f"G1 {xyz(*pts[1])} F{f(feed)}"] + [xyz(*p) for p in pts[2:]]
    return Family(f"{n} lines {seg:g} mm, {turn_deg:g} deg corners", body, polyline_pieces(pts, feed, TOL))


def zigzag(width: float = 40.0, step: float = 1.0, passes: int = 20, feed: float = 3000.0) -> Family:
    pts = [START]
    for k in range(passes):
        y = k * step
        pts += [P(0, y), P(width, y)] if k % 2 == 0 else [P(width, y), P(0, y)]
    pts = [pts[0]] + [p for k, p in enumerate(pts[1:]) if not np.allclose(p, pts[k])]
    body = [f"G1 {xyz(*pts[1])} F{f(feed)}"] + [xyz(*p) for p in pts[2:]]
    return Family(f"zig-zag pocket {passes} passes {width:g}x{step:g} mm", body, polyline_pieces(pts, feed, TOL))


def drilling(cycle: str) -> Family:
    holes = [(10.0, 10.0), (30.0, 10.0), (30.0, 30.0), (10.0, 30.0)]
    q = " Q3." if cycle == "G83" else ""
    body = [f"G0 {xyz(*holes[0])}", f"G98 {cycle} {xyz(*holes[0])} Z90. R98.{q} F600."]
    body += [xyz(*h) for h in holes[1:]] + ["G80"]
    feed = 600.0
    pieces = [line_piece(START, P(*holes[0]), None)]
    for k, h in enumerate(holes):
        top, r_, bot = P(*h, 100), P(*h, 98), P(*h, 90)
        if k:
            pieces.append(line_piece(P(*holes[k - 1], 100), top, None))
        pieces.append(line_piece(top, r_, None))
        if cycle == "G83":  # pecks of 3 mm, back to R after each, rapid to just above the last depth
            depth = 98.0
            while depth > 90.0 + 1e-9:
                nxt = max(90.0, depth - 3.0)
                if depth < 98.0:
                    pieces.append(line_piece(P(*h, 98), P(*h, depth), None))
                pieces.append(line_piece(P(*h, depth), P(*h, nxt), feed))
                pieces.append(line_piece(P(*h, nxt), P(*h, 98), None))
                depth = nxt
        else:
            pieces += [line_piece(r_, bot, feed), line_piece(bot, top, None)]
        if cycle == "G83":
            pieces.append(line_piece(P(*h, 98), top, None))
    return Family(f"{cycle} 4 holes 10 mm deep", body, pieces,
                  note="G83: re-approach clearance differs (LinuxCNC 0.254 mm, NC5 its parameter)"
                  if cycle == "G83" else "")


def overridden(fam: Family, pct: float) -> Family:
    scale = pct / 100.0
    pieces = [Piece(p.length, min(p.vmax * scale, V_XY), p.amax, p.jmax, p.v0 * scale, p.v1 * scale,
                    None if p.vmax_a is None else min(p.vmax_a * scale, V_XY),
                    None if p.v0_a is None else p.v0_a * scale, None if p.v1_a is None else p.v1_a * scale, p.radius)
              for p in fam.pieces]
    return Family(f"{fam.name} @{pct:g}%", fam.body, pieces, fam.lcnc_head, fam.hil_head, pct, fam.note)


def families() -> list[Family]:
    near = 60.0 * math.sqrt(A_XY * 10.0) * 0.97  # 97 % of the centripetal limit on R10
    base = arc_line_arc()
    return [half_arc("arc R100 half circle F15000", 100.0, 15000.0),
            arc_family("arc R5 full circle F3000", 5.0, 1, 3000.0),
            arc_family("arc R0.5 x3 circles F3000", 0.5, 3, 3000.0),
            arc_family("arc R10 x3 full circles F6000", 10.0, 3, 6000.0),
            tangent_chain(), base, helix(),
            arc_family(f"arc R10 x2 near a_c limit F{near:.0f}", 10.0, 2, near),
            rapids(), square("G61"), square("G64"), square(f"G64 P{TOL}"),
            corners(30.0), corners(60.0), corners(90.0), corners(120.0), corners(150.0),
            zigzag(), drilling("G81"), drilling("G83"),
            overridden(base, 50.0), overridden(base, 150.0)]


# ---- running -------------------------------------------------------------------------------------
def run_hil(fam: Family, work: Path) -> tuple[float, str]:
    src = work / (re.sub(r"\W+", "_", fam.name) + ".nc")
    src.write_text(fam.text(lcnc=False))
    r, pos = hil_trace(src, BENCH, ("--feed-override", f"{fam.override:g}") if fam.override != 100.0 else ())
    if not np.any(np.abs(np.diff(pos, axis=0)) > 1e-9):
        return float("nan"), f"exit {r.returncode}: no motion {(r.stdout + r.stderr).strip()[-120:]}"
    i0, i1 = motion_window(pos)
    failed = [ln.strip() for ln in r.stdout.splitlines() if ln.strip().upper().startswith("FAIL")]
    return (i1 - i0) * 0.001, ("checks ok" if r.returncode == 0 else f"exit {r.returncode} {'; '.join(failed)[:90]}")


def runner_dir(work: Path) -> Path:
    """The reference runner, with a feed-override line added to a copy of its display program."""
    here = work / "lcnc-runner"
    if not here.exists():
        shutil.copytree(LCNC_DIR, here)
        src = (here / "headless_run.py").read_text()
        src = src.replace("c.auto(linuxcnc.AUTO_RUN, 0)",
                          "c.feedrate(float(os.environ.get('LCNC_FEED_OVERRIDE', '1'))); c.wait_complete()\n"
                          "c.auto(linuxcnc.AUTO_RUN, 0)")
        (here / "headless_run.py").write_text(src)
        ini = (here / "sim_mm.ini").read_text()
        (here / "sim_mm.ini").write_text(ini.replace("[DISPLAY]\n", "[DISPLAY]\nMAX_FEED_OVERRIDE = 2.0\n"))
    return here


def run_lcnc(fam: Family, work: Path) -> tuple[float, str]:
    src = work / (re.sub(r"\W+", "_", fam.name) + ".ngc")
    src.write_text(fam.text(lcnc=True))
    env = dict(os.environ, LCNC_FEED_OVERRIDE=f"{fam.override / 100.0:g}")
    subprocess.run(["bash", str(runner_dir(work) / "lcnc_run.sh"), str(src)], capture_output=True, text=True, env=env)
    samples = src.with_suffix(".samples.txt")
    if not samples.exists() or not samples.read_text().strip():
        return float("nan"), "no samples"
    rows = [ln.split() for ln in samples.read_text().splitlines() if ln.strip()]
    idx = np.array([int(r[0]) for r in rows])
    pos = np.array([[float(v) for v in r[1:4]] for r in rows])
    line = np.array([int(r[4]) for r in rows])
    i0, i1 = motion_window(pos)
    i0 = max(i0, int(np.nonzero(line > 0)[0][0]) - 1)
    gaps = int(np.sum(np.diff(idx[i0:i1 + 1]) != 1))
    err = [ln for ln in src.with_suffix(".report.txt").read_text().splitlines() if "error" in ln][:1]
    return (i1 - i0) * 0.001, "; ".join(([f"samples lost {gaps}"] if gaps else []) + err)


def main() -> None:
    args = arguments(__doc__)
    skip, work = workplace(args, "bench-lcnc-fam-")
    print(f"bench {BENCH.name}, N1.053 = G64 P{TOL} mm; times in simulated 1 ms cycles (s)")
    print(f"{'family':44s} {'ref_a':>7s} {'ref_j':>7s} {'ref_jf':>7s} | {'hil':>7s} {'LinuxCNC':>8s} | {'hil/LC':>6s} "
          f"{'jf/a':>5s} {'excess':>6s}  notes")
    try:
        for fam in families():
            if args.only and args.only not in fam.name:
                continue
            ref_a, ref_j = references(fam.pieces)
            h, hn = run_hil(fam, work)
            lc, ln = (float("nan"), "") if skip else run_lcnc(fam, work)
            ref_jf = filter_ref(fam.pieces)
            ratio = h / lc if lc == lc and lc > 0 else float("nan")
            excess = ratio / (ref_jf / ref_a) - 1.0
            notes = "; ".join(x for x in (hn, ln, fam.note) if x)
            print(f"{fam.name:44s} {ref_a:7.3f} {ref_j:7.3f} {ref_jf:7.3f} | {h:7.3f} {lc:8.3f} | {ratio:6.3f} "
                  f"{ref_jf / ref_a:5.3f} {excess:+6.1%}  {notes}", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
