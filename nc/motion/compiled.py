"""The planner's compiled modules, or all of their sources where no build of them is current (issue 17, decision
bench B115).

`setup.py` compiles the modules named in MODULES with Cython when the project is installed, typed by the `.pxd`
beside each (`Block` becomes a C struct that the others read directly); the extensions sit next to their sources
and Python's import prefers them. They are one unit: a compiled module checks at import that `Block` is the
compiled type, so they run all compiled or all as Python. All as Python where one build is missing, where a
source is newer than its build by more than SLACK (edited, or checked out after `pip install -e .`: the stale
build would run code that is not the source's), or where DELTAHIL_PYTHON_PLANNER=1 asks for it (the tests compare
the two). Both give the same setpoints bit for bit (tests/test_planner_compiled.py); the build is only faster.
`BUILD` says which runs (the benchmarks print it).

DIRECT (nc/motion/ruckig_direct.pyx, C++, decision bench B162) is separate: ruckig's C++ called without pybind for
the planner's 1-DoF solves. nc/motion/profile.py asks `direct_ruckig` for it and solves through ruckig's Python
module where it says no (`profile.RUCKIG` says which).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys
from importlib.abc import MetaPathFinder
from importlib.machinery import ModuleSpec
from pathlib import Path

PACKAGE = "nc.motion"
MODULES = ("block", "blending", "lookahead", "shares", "planner",  # setup.py's PLANNER, in the same order
           "profile", "sample_rows", "planner_cruise", "planner_runs", "smoothing", "planner_corners",
           "spline_feed", "path", "share_zones", "plan_core")
ENV = "DELTAHIL_PYTHON_PLANNER"
SLACK = 5.0  # s: pip extracting a wheel writes a source a moment after its build (virtual_bus/kernels.py)
HERE = Path(__file__).resolve().parent


def build_state(folder: Path, names: tuple[str, ...] = MODULES, forced: bool = False) -> str:
    """"compiled" when every module in `folder` has a current build, else why the sources run ("python (…)")."""
    if forced:
        return f"python ({ENV}=1)"
    for name in names:
        source = folder / f"{name}.py"
        builds = [folder / f"{name}{suffix}" for suffix in importlib.machinery.EXTENSION_SUFFIXES]
        built = [b for b in builds if b.exists()]
        if not built:
            return "python (not compiled: no C compiler or Cython at install)"
        try:
            stale = source.stat().st_mtime > built[0].stat().st_mtime + SLACK
        except OSError:  # an install without the sources next to the builds: the builds are the modules
            continue
        if stale:
            return f"python ({name}.py is newer than its build: pip install -e . rebuilds it)"
    return "compiled"


DIRECT = "ruckig_direct"
DIRECT_SOURCES = ("ruckig_direct.pyx", "ruckig_direct.hpp")


def direct_state(folder: Path, forced: bool = False) -> str:
    """"direct" where `folder` holds a build of ruckig_direct not older than its sources, else why pybind solves."""
    if forced:
        return f"pybind ({ENV}=1)"
    built = [folder / f"{DIRECT}{suffix}" for suffix in importlib.machinery.EXTENSION_SUFFIXES]
    built = [b for b in built if b.exists()]
    if not built:
        return "pybind (ruckig_direct not compiled: no C++ compiler, or no ruckig headers and library at install)"
    for name in DIRECT_SOURCES:
        try:
            stale = (folder / name).stat().st_mtime > built[0].stat().st_mtime + SLACK
        except OSError:  # installed without its sources
            continue
        if stale:
            return f"pybind ({name} is newer than its build: pip install -e . rebuilds it)"
    return "direct"


def direct_ruckig(version: str) -> tuple[object | None, str]:
    """ruckig_direct's `solve` where it is built, current and compiled against ruckig `version` (the one imported:
    the same library, so the same bits as ruckig's Python module), else None; and which solves ("direct" or
    "pybind (why)"). Called by profile.py, which imports ruckig anyway (this module does not: start-up, issue 16)."""
    state = direct_state(HERE, forced=os.environ.get(ENV) == "1")
    if state != "direct":
        return None, state
    try:
        from nc.motion import ruckig_direct
    except ImportError as exc:  # e.g. a C++ runtime older than the one it was linked for
        return None, f"pybind (ruckig_direct does not load: {exc})"
    if ruckig_direct.RUCKIG_VERSION != version:
        return None, f"pybind (ruckig_direct is built for ruckig {ruckig_direct.RUCKIG_VERSION}, ruckig {version} runs)"
    return ruckig_direct.solve, state


class _Sources(MetaPathFinder):
    """Finds the compiled modules' sources ahead of the default finder, which would take their builds."""

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> ModuleSpec | None:
        pkg, _, name = fullname.rpartition(".")
        if pkg != PACKAGE or name not in MODULES:
            return None
        return importlib.util.spec_from_file_location(fullname, HERE / f"{name}.py")


def _install() -> str:
    state = build_state(HERE, forced=os.environ.get(ENV) == "1")
    if state != "compiled" and not any(isinstance(f, _Sources) for f in sys.meta_path):
        sys.meta_path.insert(0, _Sources())
    return state


BUILD = _install()
