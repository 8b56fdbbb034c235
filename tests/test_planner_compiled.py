"""The planner's modules compiled by setup.py (decision bench B115) give the same setpoints bit for bit as their
sources: tests/planner_digests.py plans the same programs (a dense CAM run, random mill programs with arcs,
rapids, exact stops and dwells, the lathe demo) in a process that loads the builds and in one that loads the
sources (DELTAHIL_PYTHON_PLANNER=1), and the digests of every setpoint must agree. Also: which runs is decided
for the modules together, and a stale build gives way to its source."""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import nc.motion.compiled as compiled

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "tests" / "planner_digests.py"


def _digests(python_planner: bool) -> dict:
    env = dict(os.environ)
    env.pop(compiled.ENV, None)
    if python_planner:
        env[compiled.ENV] = "1"
    out = subprocess.run([sys.executable, str(SCRIPT)], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout)


@pytest.mark.skipif(compiled.BUILD != "compiled", reason=f"the planner is not compiled here ({compiled.BUILD})")
def test_compiled_planner_gives_the_setpoints_of_its_source():
    built, source = _digests(False), _digests(True)
    assert built["build"] == "compiled"
    assert all(not f.endswith(".py") for f in built["modules"].values()), built["modules"]
    assert source["build"].startswith("python")
    assert all(f.endswith(".py") for f in source["modules"].values()), source["modules"]
    assert built["digests"] == source["digests"]


def test_the_sources_run_when_asked_whatever_is_built():
    source = _digests(True)
    assert source["build"] == f"python ({compiled.ENV}=1)"
    assert sorted(source["modules"]) == sorted(compiled.MODULES)
    assert all(f.endswith(".py") for f in source["modules"].values())


def _module(folder: Path, name: str, source_age: float, build_age: float | None) -> None:
    now = time.time()
    src = folder / f"{name}.py"
    src.write_text("")
    os.utime(src, (now - source_age, now - source_age))
    if build_age is not None:
        so = folder / f"{name}.cpython-311-x86_64-linux-gnu.so"
        so.write_bytes(b"")
        os.utime(so, (now - build_age, now - build_age))


def test_one_stale_or_missing_build_makes_every_module_run_its_source(tmp_path, monkeypatch):
    monkeypatch.setattr("importlib.machinery.EXTENSION_SUFFIXES", [".cpython-311-x86_64-linux-gnu.so"])
    names = ("a", "b")
    _module(tmp_path, "a", 100.0, 100.0)
    _module(tmp_path, "b", 100.0, 103.0)  # built 3 s before its source was written: within SLACK (pip's order)
    assert compiled.build_state(tmp_path, names) == "compiled"
    assert compiled.build_state(tmp_path, names, forced=True) == f"python ({compiled.ENV}=1)"
    _module(tmp_path, "b", 10.0, 100.0)  # b edited after the build
    assert compiled.build_state(tmp_path, names).startswith("python (b.py is newer than its build")
    (tmp_path / "b.cpython-311-x86_64-linux-gnu.so").unlink()
    assert compiled.build_state(tmp_path, names).startswith("python (not compiled")


def test_setup_compiles_the_modules_the_loader_decides_for():
    tree = ast.parse((ROOT / "setup.py").read_text())
    planner = next(node.value for node in tree.body if isinstance(node, ast.Assign)
                   and any(isinstance(t, ast.Name) and t.id == "PLANNER" for t in node.targets))
    assert tuple(ast.literal_eval(planner)) == compiled.MODULES
    pxd = sorted(p.stem for p in (ROOT / "nc" / "motion").glob("*.pxd"))
    assert pxd == sorted(compiled.MODULES)
