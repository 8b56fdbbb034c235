"""Bench tools a user meets on the first day: a closed stdout ends quietly, one spelling per flag
(old spellings still work, hidden from --help), bus captures read back by the tools that read them.

Decisions: docs/decisions/bench-tools.md.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from hil.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
LATHE = str(ROOT / "benches" / "lathe-2axis.toml")
PART = str(ROOT / "examples" / "lathe_part_g71_g70_g76.nc")


def _hil(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hil.cli", *args], capture_output=True, text=True, timeout=120, **kw)


@pytest.mark.parametrize("args", [("path", PART), ("path", "--json", PART)])
def test_closed_stdout_ends_quietly(args):
    """`hil path … | head -1`: the first line arrives, exit 0 (README), nothing on stderr."""
    cmd = f"{sys.executable} -m hil.cli {' '.join(args)} | head -1; exit ${{PIPESTATUS[0]}}"
    r = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    assert r.stdout.count("\n") == 1 and ("X45" in r.stdout or '"x"' in r.stdout.lower())


def _help(*path: str) -> str:
    parser = build_parser()
    sub = parser._subparsers._group_actions[0].choices[path[0]]
    for name in path[1:]:
        sub = sub._subparsers._group_actions[0].choices[name]
    return sub.format_help()


def test_one_spelling_per_flag_old_ones_hidden():
    """The servo's RS-485 port is --servo-modbus/--servo-baud in hil run and hil servo alike; the old
    --modbus/--baud still parse but are not offered in --help."""
    parser = build_parser()
    for cmd in (["servo", "get", "X", "P2-00"], ["run", "x.nc"]):
        a = parser.parse_args([*cmd, "--servo-modbus", "/dev/ttyUSB0", "--servo-baud", "9600"])
        assert (getattr(a, "modbus", None) or a.servo_modbus) == "/dev/ttyUSB0"
        assert (getattr(a, "baud", None) or a.servo_baud) == 9600
    old = parser.parse_args(["servo", "get", "X", "P2-00", "--modbus", "/dev/ttyS1", "--baud", "19200"])
    assert (old.modbus, old.baud) == ("/dev/ttyS1", 19200)
    assert parser.parse_args(["servo", "get", "X", "P2-00"]).baud == 38400
    text = _help("servo")
    assert "--servo-modbus" in text and "--servo-baud" in text
    assert "--modbus" not in text.replace("--servo-modbus", "") and "--baud" not in text.replace("--servo-baud", "")
    assert parser.parse_args(["sim", "ethercat", "--interface", "veth0"]).iface == "veth0"
    assert "--interface" not in _help("sim", "ethercat")


def test_sim_ethercat_without_iface_is_usage():
    r = _hil("sim", "ethercat")
    assert r.returncode == 2 and "--iface" in r.stderr and "Traceback" not in r.stderr
