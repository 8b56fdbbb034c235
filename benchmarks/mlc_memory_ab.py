"""A/B of the MLC exchange (issue 17): a CRC of the whole device memory (M, D, A, X, Y) after every scan, with
the spindle output, the NC link's alarm count and mode, over seven runs with stretches off; one tree saves, the
other compares cycle by cycle.

    PYTHONPATH=/path/to/main python benchmarks/mlc_memory_ab.py save /tmp/ref.pkl
    PYTHONPATH=$PWD python benchmarks/mlc_memory_ab.py cmp /tmp/ref.pkl     # exit 1 on any difference
"""

from __future__ import annotations

import os
import pickle
import sys
import zlib
from pathlib import Path
from typing import Any

os.environ["DELTAHIL_STRETCH"] = "0"  # every cycle stepped: every scan is compared
ROOT = Path(os.environ.get("PYTHONPATH", "").split(os.pathsep)[0] or Path(__file__).resolve().parent.parent)
sys.path.insert(0, str(ROOT))

import mlc.machine as machine  # noqa: E402
from hil import api  # noqa: E402

EX, BENCHES = ROOT / "examples", ROOT / "benches"
RUNS: list[tuple[str, Path, dict[str, Any]]] = [
    ("lathe demo", EX / "lathe_demo.nc", {}),
    ("hold/resume/override", EX / "lathe_demo.nc", {"events": ["t=2:feed-hold", "t=2.6:cycle-start", "t=4:set D21002=50"]}),
    ("E-stop", EX / "lathe_demo.nc", {"events": ["t=3:estop", "t=3.5:estop-off", "t=3.6:reset"]}),
    ("overrides 110/70 %", EX / "lathe_demo.nc", {"feed_override": 110.0, "spindle_override": 70.0, "rapid_override": 70.0}),
    ("C-axis drilling", EX / "lathe_face_drilling_c.nc", {"bench": BENCHES / "lathe-c-axis.toml"}),
    ("M96 interrupt", EX / "m96_interrupt.nc", {"bench": BENCHES / "mill-3axis.toml", "events": ["t=1.1:pulse M21019"]}),
    ("G71/G70/G76", EX / "lathe_part_g71_g70_g76.nc", {"spindle_override": 80.0}),
]


def crcs() -> dict[str, list[int]]:
    """Per run, one CRC per scan (taken even when the scan raises: an alarm's scan counts too)."""
    log: list[int] = []
    original = machine.Mlc.scan

    def scan(self: machine.Mlc, ch: Any) -> None:
        try:
            original(self, ch)
        finally:
            mem = self.mem
            crc = zlib.crc32(bytes(mem.a) + bytes(mem.x) + bytes(mem.y))
            crc = zlib.crc32(bytes(mem.m), zlib.crc32(mem.d.tobytes(), crc))
            rest = (self.spindle.rpm, self.spindle.direction, len(self.link.alarms), self.link.mode)
            log.append(crc ^ (hash(rest) & 0xFFFFFFFF))

    machine.Mlc.scan = scan  # type: ignore[method-assign]
    out = {}
    try:
        for name, program, kw in RUNS:
            log.clear()
            kw = dict(kw)
            bench = kw.pop("bench", None)
            api.run(str(program), str(bench) if bench else None, **kw)
            out[name] = list(log)
    finally:
        machine.Mlc.scan = original  # type: ignore[method-assign]
    return out


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] not in ("save", "cmp"):
        print(__doc__)
        return 2
    mode, path = argv
    got = crcs()
    if mode == "save":
        Path(path).write_bytes(pickle.dumps(got))
        print({k: len(v) for k, v in got.items()})
        return 0
    ref = pickle.loads(Path(path).read_bytes())
    bad = 0
    for name, now in got.items():
        before = ref.get(name, [])
        first = next((i for i, (a, b) in enumerate(zip(before, now)) if a != b), None)
        same = len(before) == len(now) and first is None
        bad += not same
        print(f"{name:22s} {len(before)} / {len(now)} scans: " + ("IDENTICAL" if same else f"DIFFERENT from scan {first}"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
