"""Running LinuxCNC's standalone interpreter `rs274` (Debian linuxcnc-uspace) and reading its canonical
calls back in our machine frame, for the tests that compare paths with it (tests/test_rs274_*.py)."""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass

import pytest

RS274 = shutil.which("rs274")
needs_rs274 = pytest.mark.skipif(RS274 is None, reason="LinuxCNC rs274 is not installed "
                                                       "(apt-get install linuxcnc-uspace)")
CALL = re.compile(r"^\s*\d+\s+N\S*\s+(STRAIGHT_TRAVERSE|STRAIGHT_FEED|ARC_FEED)\((.*)\)")
ANY = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)")
# ARC_FEED(first_end, second_end, first_centre, second_centre, rotation, axis_end, ...): axes per plane
PLANES = {"CANON_PLANE_XY": ("X", "Y", "Z"), "CANON_PLANE_XZ": ("Z", "X", "Y"), "CANON_PLANE_YZ": ("Y", "Z", "X")}


def rs274_output(tmp_path, text: str, tools: str | None = None) -> str:
    f = tmp_path / "lc.ngc"
    f.write_text(text)
    args = [RS274, "-g"]
    if tools is not None:
        # LinuxCNC reads tool lengths from a tool table file (`T1 P1 Z12.5`)
        (tmp_path / "lc.tbl").write_text(tools)
        args += ["-t", str(tmp_path / "lc.tbl")]
    return subprocess.run(args + [str(f)], capture_output=True, text=True, timeout=30).stdout


def rs274(tmp_path, text: str) -> list[tuple[str, list[float]]]:
    """The motion calls as printed (program coordinates, program units)."""
    out = rs274_output(tmp_path, text)
    calls = []
    for line in out.splitlines():
        m = CALL.match(line)
        if m:
            calls.append((m.group(1), [float(v) for v in m.group(2).split(",")]))
    assert calls, out
    return calls


def dedupe(points):
    out = []
    for p in points:
        # zero-length moves (a return to the level the tool is already at) are dropped
        if not out or any(abs(a - b) > 1e-6 for a, b in zip(p[1], out[-1][1])):
            out.append(p)
    return out


@dataclass
class Canon:
    """One canonical move of rs274 in machine millimetres, shaped like our `hil path --json` moves."""
    kind: str  # rapid, line, arc, dwell
    end: dict[str, float]
    center: dict[str, float] | None = None
    dir: str | None = None
    turns: int = 0  # full turns beyond the first (|rotation| - 1)
    duration: float | None = None


def canon(tmp_path, text: str, tools: str | None = None) -> list[Canon]:
    """rs274's moves with its work offsets (G5x, G92), tool length offset and inch units applied, so
    they compare with our machine coordinates (`start`/`end`/`center`) directly. rs274 prints 4 decimals:
    programs compared within 1e-6 mm must have geometry exact at that resolution."""
    out = rs274_output(tmp_path, text, tools)
    unit, plane = 1.0, PLANES["CANON_PLANE_XY"]
    g5x = {"X": 0.0, "Y": 0.0, "Z": 0.0}
    g92 = dict(g5x)
    tlo = dict(g5x)
    moves: list[Canon] = []
    pos = dict(g5x)

    def machine(axis: str, v: float) -> float:
        return v * unit + g5x[axis] + g92[axis] + tlo[axis]

    for line in out.splitlines():
        m = ANY.match(line)
        if not m:
            continue
        name, raw = m.groups()
        if name == "USE_LENGTH_UNITS":
            unit = 25.4 if "INCHES" in raw else 1.0
        elif name == "SELECT_PLANE":
            plane = PLANES[raw.strip()]
        elif name in ("SET_G5X_OFFSET", "SET_G92_OFFSET"):
            v = [float(x) * unit for x in raw.split(",")]
            v = v[1:] if name == "SET_G5X_OFFSET" else v
            (g5x if name == "SET_G5X_OFFSET" else g92).update(X=v[0], Y=v[1], Z=v[2])
        elif name == "USE_TOOL_LENGTH_OFFSET":
            x, y, z = (float(v) * unit for v in raw.split(",")[0].split())
            tlo.update(X=x, Y=y, Z=z)
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            v = [float(x) for x in raw.split(",")]
            pos = {a: machine(a, v[i]) for i, a in enumerate("XYZ")}
            moves.append(Canon("rapid" if name == "STRAIGHT_TRAVERSE" else "line", pos))
        elif name == "ARC_FEED":
            v = [float(x) for x in raw.split(",")]
            a1, a2, ax = plane
            pos = {a1: machine(a1, v[0]), a2: machine(a2, v[1]), ax: machine(ax, v[5])}
            centre = {a1: machine(a1, v[2]), a2: machine(a2, v[3]), ax: pos[ax]}
            rot = int(v[4])
            moves.append(Canon("arc", pos, centre, "ccw" if rot > 0 else "cw", abs(rot) - 1))
        elif name == "DWELL":
            moves.append(Canon("dwell", dict(pos), duration=float(raw)))
    assert moves, out
    return moves
