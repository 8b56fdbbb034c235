"""nc.motion.shares cimports blending's FilterCorners where compiled (decision bench B182), so blending must not import
shares: each of the planner's modules imports first in a fresh interpreter, and the jerk factor's bound MAX_FACTOR is
one constant (nc.motion.limits') wherever it is read."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("first", ["nc.motion.shares", "nc.motion.blending", "nc.motion.lookahead", "nc.motion.planner"])
def test_each_module_imports_first(first: str) -> None:
    code = (f"import sys; sys.path.insert(0, {str(ROOT)!r}); import {first}; "
            "import nc.motion.blending as b, nc.motion.limits as l, nc.motion.shares as s, nc.motion.planner as p; "
            "assert b.MAX_FACTOR is l.MAX_FACTOR is s.MAX_FACTOR is p.MAX_FACTOR == 2.0; print(s.jerk_factor.__module__)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "nc.motion.shares"
