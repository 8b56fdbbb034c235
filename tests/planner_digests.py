"""Setpoint digests of a few programs planned offline (nc.motion.offline: interpreter, channel, planner, filter; no
bus), printed as JSON with the modules' files: tests/test_planner_compiled.py runs it with the planner's builds
and with its sources (DELTAHIL_PYTHON_PLANNER=1, decision bench B115) and compares."""

from __future__ import annotations

import hashlib
import json
import math
import random
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_motion import cam_program  # noqa: E402
from hil.bench_file import load_bench_file  # noqa: E402
from nc.interp import Interpreter  # noqa: E402
from nc.motion.offline import run  # noqa: E402
from nc.profiles import make_profile  # noqa: E402
from nc.program.blocks import parse_program  # noqa: E402


def mill_program(seed: int) -> str:
    """Lines, arcs, rapids, exact stops, a dwell and feed changes on three axes: every kind of junction the
    compiled modules plan (filter corners, tolerance, jerk-factor scans, look-ahead)."""
    rng = random.Random(seed)
    out = ["G90 G17 G94 G64 G01 F2400", "G00 X0 Y0 Z5"]
    x = y = 0.0
    for _ in range(60):
        k = rng.random()
        f = rng.choice([600, 1500, 3000, 6000])
        nx, ny = round(x + rng.uniform(-8, 8), 3), round(y + rng.uniform(-8, 8), 3)
        if k < 0.45:
            out.append(f"G01 X{nx} Y{ny} Z{round(rng.uniform(-1, 1), 3)} F{f}")
        elif k < 0.7:
            r = round(math.hypot(nx - x, ny - y) * rng.uniform(0.55, 2.0) + 0.01, 3)
            out.append(f"G0{rng.choice([2, 3])} X{nx} Y{ny} R{r} F{f}")
        elif k < 0.8:
            out.append(f"G00 X{nx} Y{ny}")
        elif k < 0.87:
            out.append(f"G09 G01 X{nx} Y{ny} F{f}")
        elif k < 0.9:
            out.append("G04 X0.05")
            continue
        else:
            for _ in range(rng.randint(5, 25)):  # a dense CAM-like run
                nx, ny = round(nx + rng.uniform(0.01, 0.2), 4), round(ny + rng.uniform(-0.05, 0.05), 4)
                out.append(f"X{nx} Y{ny}")
        x, y = nx, ny
    out.append("M30")
    return "\n".join(out) + "\n"


def lathe_program() -> str:
    return (ROOT / "examples" / "lathe_demo.nc").read_text()


def digest(text: str, bench: str, profile: str, axes: tuple[str, ...], start: dict[str, float]) -> str:
    prog = parse_program(text, name="p.nc")
    motion = load_bench_file(ROOT / "benches" / bench).motion_config()
    st = run(Interpreter(make_profile(profile, axes)).run(prog), motion, start)
    return hashlib.sha1(st.positions.tobytes() + st.lines.tobytes()).hexdigest()


def main() -> None:
    mill = ("mill-3axis.toml", "nc5-mill", ("X", "Y", "Z"), {"X": 0.0, "Y": 0.0, "Z": 100.0})
    out = {"CAM 1500": digest(cam_program(1500), *mill)}
    for seed in (1, 2, 3):
        out[f"mill {seed}"] = digest(mill_program(seed), *mill)
    out["lathe demo"] = digest(lathe_program(), "lathe-2axis.toml", "nc5-lathe-a", ("X", "Z"), {"X": 50.0, "Z": 50.0})
    import nc.motion.compiled as compiled
    mods = {name: sys.modules[f"nc.motion.{name}"].__file__ for name in compiled.MODULES}
    print(json.dumps({"build": compiled.BUILD, "modules": mods, "digests": out}))


if __name__ == "__main__":
    main()
