"""Dense programs through `hil run` and through headless LinuxCNC 2.9, side by side (issue 18).

Prints, per program: the feed-limited bound, hil's and LinuxCNC's program time (simulated 1 ms
cycles), their ratio, the largest deviation from the programmed polyline, and the peak
velocity/acceleration/jerk share of the axis limits (finite differences of the commanded
positions, as a drive sees them). Asserts nothing.

    python benchmarks/bench_vs_linuxcnc.py [--only NAME] [--keep DIR] [--no-linuxcnc] [--filter-off]

--filter-off runs hil on the bench with N1.036 = N1.037 = 0 (no position filter): line-line corners
then get clothoid blends within N1.053 (decision motion 42).

LinuxCNC is run through the reference runner in ../shared/tools/linuxcnc-time (or $LCNC_TIME_DIR);
its G64 P<tol> matches N1.053 (benches/mill-3axis.toml: 0.02 mm). Where LinuxCNC or the runner is
absent only the hil column is printed. Both runs use the same axis limits (X/Y 500 mm/s,
5,000 mm/s²; Z 300 mm/s, 3,000 mm/s²); LinuxCNC has no jerk limit, hil holds the bench's.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benches" / "mill-3axis.toml"
sys.path.insert(0, str(ROOT))
from tests.motion_helpers import polyline_deviation  # noqa: E402

LCNC_DIR = Path(os.environ.get("LCNC_TIME_DIR", ROOT.parent / "shared" / "tools" / "linuxcnc-time"))
TOL = 0.02  # N1.053 of the bench = G64 P of the LinuxCNC run
START = (0.0, 0.0, 100.0)  # where both machines stand when the program starts
LIMITS = np.array([[500.0, 5000.0, 250_000.0], [500.0, 5000.0, 250_000.0], [300.0, 3000.0, 150_000.0]])


@dataclass
class Program:
    name: str
    feed: float  # mm/min
    points: list[tuple[float, float, float]]  # the G1 polyline after START

    def length(self) -> float:
        p = np.array([START] + self.points)
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())

    def feed_limited(self) -> float:
        return self.length() / (self.feed / 60.0)

    def text(self, lcnc: bool) -> str:
        head = ["G21 G17 G90 G94", f"G64 P{TOL}"] if lcnc else ["G21 G17 G90 G94"]
        body = [f"G1 X{x:.3f} Y{y:.3f} Z{z:.3f} F{self.feed:g}" if k == 0 else f"X{x:.3f} Y{y:.3f} Z{z:.3f}"
                for k, (x, y, z) in enumerate(self.points)]
        return "\n".join(head + body + ["M30", ""])


def chord_circle(radius: float, chord: float = 0.05, feed: float = 3000.0) -> Program:
    """A lead-in from the centre to (r, 0), then a full circle of `chord` mm chords (3 decimals)."""
    n = int(2 * math.pi * radius / chord)
    pts = [(radius * math.cos(2 * math.pi * k / n), radius * math.sin(2 * math.pi * k / n), 100.0)
           for k in range(n + 1)]
    return Program(f"circle r{radius:g} chords {chord:g}", feed, [tuple(round(c, 3) for c in p) for p in pts])


def cam_polyline(n: int = 2000, seg: float = 0.775, turn_deg: float = 15.0, seed: int = 18,
                 feed: float = 2500.0) -> Program:
    """A 3-D CAM polyline: segments of about `seg` mm whose direction turns by about `turn_deg`
    at every corner (half-normal jitter), Z kept within a few mm; 3-decimal coordinates."""
    rng = np.random.default_rng(seed)
    p = np.array(START)
    d = np.array([1.0, 0.0, 0.0])
    pts = []
    for _ in range(n):
        ang = math.radians(turn_deg) * abs(rng.normal(1.0, 0.3))
        axis = rng.normal(0.0, 1.0, 3) * [0.3, 0.3, 1.0]
        axis -= axis.dot(d) * d
        axis /= np.linalg.norm(axis)
        d = d * math.cos(ang) + np.cross(axis, d) * math.sin(ang)
        d[2] -= 0.3 * (p[2] - 98.0) / 5.0 * abs(d[2]) + 0.02 * (p[2] - 98.0)  # keep Z near 98
        d[:2] -= 0.002 * p[:2]  # and X/Y within the bench's soft limits
        d /= np.linalg.norm(d)
        p = p + d * seg * rng.uniform(0.7, 1.3)
        pts.append(tuple(round(float(c), 3) for c in p))
    return Program(f"CAM 3-D random corners {n} segments", feed, pts)


def cam_surface(n: int = 2000, seg: float = 0.775, feed: float = 2500.0) -> Program:
    """A 3-D CAM finishing path as a CAM system samples it: a smooth space curve (curvature radius
    2–6 mm, the turning plane drifting slowly, Z waving within a few mm), cut into chords of
    about `seg` mm (±30 %) and written with 3 decimals, so the tangent steps carry rounding jitter."""
    rng = np.random.default_rng(7)
    d = np.array([1.0, 0.0, 0.0])
    nrm = np.array([0.0, 0.0, 1.0])
    p = np.array(START)
    pts = []
    for k in range(n):
        nrm = nrm + rng.normal(0.0, 0.15, 3)
        nrm -= nrm.dot(d) * d
        nrm /= np.linalg.norm(nrm)
        step = seg * rng.uniform(0.7, 1.3)
        radius = 4.0 + 2.0 * math.sin(k / 37.0)
        ang = step / radius
        d = d * math.cos(ang) + np.cross(nrm, d) * math.sin(ang)
        d[2] -= 0.05 * (p[2] - 98.0)  # keep Z near 98
        d /= np.linalg.norm(d)
        p = p + d * step
        pts.append(tuple(round(float(c), 3) for c in p))
    return Program(f"CAM 3-D curve {n} chords", feed, pts)


def contour_90(side: float = 200.0, feed: float = 6000.0) -> Program:
    pts = [(side, 0.0, 100.0), (side, side, 100.0), (0.0, side, 100.0), (0.0, 0.0, 100.0)]
    return Program("90 deg contour 800 mm", feed, pts)


def mixed(feed: float = 3000.0) -> Program:
    """Lines and chord arcs of several radii (R3, R8, R25), 0.05 mm chords."""
    pts: list[tuple[float, float, float]] = [(20.0, 0.0, 100.0)]
    x = 20.0
    for r in (3.0, 8.0, 25.0):
        n = int(math.pi * r / 0.05)
        cx = x + r
        pts += [(cx - r * math.cos(math.pi * k / n), r * math.sin(math.pi * k / n), 100.0) for k in range(1, n + 1)]
        x = cx + r
        pts.append((x + 10.0, 0.0, 100.0))
        x += 10.0
    return Program("mixed lines + chord arcs", feed, [tuple(round(c, 3) for c in p) for p in pts])


def programs() -> list[Program]:
    return [contour_90(), chord_circle(10.0), chord_circle(5.0), chord_circle(2.0), chord_circle(50.0),
            cam_surface(), cam_polyline(), mixed()]


# ---- measuring ---------------------------------------------------------------------------------
def motion_window(P: np.ndarray) -> tuple[int, int]:
    mv = np.nonzero(np.any(np.abs(np.diff(P, axis=0)) > 1e-9, axis=1))[0]
    return int(mv[0]), int(mv[-1]) + 1


def shares(P: np.ndarray, T: float = 0.001) -> tuple[float, float, float]:
    """Peak |v|, |a|, |j| per axis over its limit (largest over the axes), padded at rest."""
    p = np.vstack([P[:1]] * 3 + [P] + [P[-1:]] * 3)
    v = np.diff(p, axis=0) / T
    a = np.diff(v, axis=0) / T
    j = np.diff(a, axis=0) / T
    return tuple(float((np.abs(x).max(axis=0) / LIMITS[:, k]).max()) for k, x in enumerate((v, a, j)))


@dataclass
class Result:
    time: float
    deviation: float
    v: float
    a: float
    j: float
    note: str = ""


def measure(P: np.ndarray, prog: Program, note: str = "") -> Result:
    i0, i1 = motion_window(P)
    S = P[i0:i1 + 1]
    return Result((i1 - i0) * 0.001, polyline_deviation(S, [START] + prog.points), *shares(S), note)


def filter_off_bench(work: Path) -> Path:
    """benches/mill-3axis.toml with N1.036 = N1.037 = 0 (the filter off, N1.053 kept)."""
    text = BENCH.read_text()
    head, sep, rest = text.partition("[[axes]]")
    out = work / "mill-3axis-nofilter.toml"
    out.write_text(head + '[params]\n"N1.036" = 0\n"N1.037" = 0\n\n' + sep + rest)
    return out


def hil_trace(src: Path, bench: Path = BENCH, extra: tuple[str, ...] = ()) -> tuple[subprocess.CompletedProcess, np.ndarray]:
    """`hil run --trace` of the program file `src` on `bench`: the finished process and the commanded X/Y/Z
    of every cycle."""
    trace = src.with_suffix(".csv")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-m", "hil.cli", "run", "--bench", str(bench), "--trace", str(trace),
                        "--no-progress", *extra, str(src)], capture_output=True, text=True, env=env, cwd=ROOT)
    if not trace.exists():
        return r, np.empty((0, 3))
    with open(trace) as f:
        rows = list(csv.DictReader(f))
    return r, np.array([[float(r_["X_cmd"]), float(r_["Y_cmd"]), float(r_["Z_cmd"])] for r_ in rows]).reshape(-1, 3)


def run_hil(prog: Program, work: Path, bench: Path = BENCH) -> Result:
    src = work / (re.sub(r"\W+", "_", prog.name) + ".nc")
    src.write_text(prog.text(lcnc=False))
    r, P = hil_trace(src, bench)
    P = np.vstack([np.array(START)[None, :], P])
    failed = [ln.strip() for ln in r.stdout.splitlines() if "FAIL" in ln.upper()]
    note = f"exit {r.returncode}" + (f" ({'; '.join(failed)[:80]})" if failed else ", checks ok" if r.returncode == 0 else "")
    return measure(P, prog, note)


def run_lcnc(prog: Program, work: Path) -> Result | None:
    src = work / (re.sub(r"\W+", "_", prog.name) + ".ngc")
    src.write_text(prog.text(lcnc=True))
    subprocess.run(["bash", str(LCNC_DIR / "lcnc_run.sh"), str(src)], capture_output=True, text=True)
    samples = src.with_suffix(".samples.txt")
    if not samples.exists():
        return None
    rows = [ln.split() for ln in samples.read_text().splitlines() if ln.strip()]
    idx = np.array([int(r[0]) for r in rows])
    P = np.array([[float(v) for v in r[1:4]] for r in rows])
    line = np.array([int(r[4]) for r in rows])
    # From the cycle before the first motion of a program line (the runner's own rule).
    i0, i1 = motion_window(P)
    i0 = max(i0, int(np.nonzero(line > 0)[0][0]) - 1)
    S = P[i0:i1 + 1]
    gaps = int(np.sum(np.diff(idx[i0:i1 + 1]) != 1))  # halsampler overruns under load
    return Result((i1 - i0) * 0.001, polyline_deviation(S, [START] + prog.points), *shares(S),
                  f"LinuxCNC samples lost: {gaps}" if gaps else "")


def lcnc_available() -> str | None:
    if shutil.which("linuxcnc") is None:
        return "LinuxCNC is not installed (apt-get install linuxcnc-uspace)"
    if not (LCNC_DIR / "lcnc_run.sh").exists():
        return f"no LinuxCNC runner at {LCNC_DIR} (set LCNC_TIME_DIR)"
    return None


def arguments(doc: str, extra=None) -> argparse.Namespace:
    """--only, --keep, --no-linuxcnc (and what `extra(parser)` adds)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--only", help="run the programs whose name contains this")
    ap.add_argument("--keep", type=Path, help="keep programs, traces and samples in this folder")
    ap.add_argument("--no-linuxcnc", action="store_true")
    if extra is not None:
        extra(ap)
    return ap.parse_args()


def workplace(args: argparse.Namespace, prefix: str) -> tuple[str | None, Path]:
    """Why the LinuxCNC column is skipped (None: it runs), printed, and the folder the runs write to."""
    skip = "skipped (--no-linuxcnc)" if args.no_linuxcnc else lcnc_available()
    if skip:
        print(f"LinuxCNC column: {skip}")
    work = args.keep or Path(tempfile.mkdtemp(prefix=prefix))
    work.mkdir(parents=True, exist_ok=True)
    return skip, work


def main() -> None:
    args = arguments(__doc__, lambda ap: ap.add_argument("--filter-off", action="store_true",
                                                         help="hil without the position filter (corner blends)"))
    skip, work = workplace(args, "bench-lcnc-")
    bench = filter_off_bench(work) if args.filter_off else BENCH
    print(f"bench {bench.name}, N1.053 = G64 P{TOL} mm; times in simulated 1 ms cycles; shares = peak v/a/j of the limits")
    print(f"{'program':32s} {'bound':>7s} | {'hil':>7s} {'dev mm':>7s} {'v/a/j':>15s} | {'LinuxCNC':>8s} {'dev mm':>7s} "
          f"{'v/a/j':>15s} | {'hil/LCNC':>8s} {'hil/bound':>9s}")
    try:
        for prog in programs():
            if args.only and args.only not in prog.name:
                continue
            h = run_hil(prog, work, bench)
            lc = None if skip else run_lcnc(prog, work)
            ratio = f"{h.time / lc.time:8.3f}" if lc else f"{'-':>8s}"
            lcs = (f"{lc.time:8.3f} {lc.deviation:7.4f} {lc.v:4.2f}/{lc.a:4.2f}/{lc.j:5.1f}" if lc
                   else f"{'-':>8s} {'-':>7s} {'-':>15s}")
            print(f"{prog.name:32s} {prog.feed_limited():7.3f} | {h.time:7.3f} {h.deviation:7.4f} "
                  f"{h.v:4.2f}/{h.a:4.2f}/{h.j:5.2f} | {lcs} | {ratio} {h.time / prog.feed_limited():9.3f}  {h.note}"
                  + (f"; {lc.note}" if lc and lc.note else ""),
                  flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
