"""The compiled kernels, or their Python source where no build of them is current (issue 17).

`setup.py` compiles virtual_bus/drive_kernel.py with Cython when the project is installed; the extension sits next
to its source and Python's import prefers it. In a checkout whose source is newer than its build (edited, or
checked out after `pip install -e .`; more than SLACK after it) the stale build would run code that is not the source's: the source is loaded
instead, and `BUILD` says so (`hil --version`, the benchmarks print it). Both give the same numbers bit for bit
(tests/test_drive_kernel.py); the build is only faster.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from types import ModuleType

NAME = "virtual_bus.drive_kernel"
SLACK = 5.0  # s: see build_of


def build_of(origin: str | None, source: str) -> str:
    """Which runs, given where the import finds the module and its source: "compiled", or why it is "python"."""
    if origin is None or origin.endswith(".py"):
        return "python (not compiled: no C compiler or Cython at install)"
    try:
        # An install writes both files within moments of each other, the source last as often as not (pip
        # extracting a wheel): only a source newer by more than SLACK was changed after the build.
        stale = os.path.getmtime(source) > os.path.getmtime(origin) + SLACK
    except OSError:  # an install without the source next to the build: the build is the module
        return "compiled"
    return "python (the compiled build is older than its source: pip install -e . rebuilds it)" if stale else "compiled"


def _load() -> tuple[ModuleType, str]:
    spec = importlib.util.find_spec(NAME)
    origin = spec.origin if spec is not None else None
    source = os.path.join(os.path.dirname(origin), "drive_kernel.py") if origin else ""
    build = build_of(origin, source)
    if build == "compiled" or origin is None or origin.endswith(".py"):
        return importlib.import_module(NAME), build
    spec = importlib.util.spec_from_file_location(NAME, source)  # the stale build's source, under its name
    mod = importlib.util.module_from_spec(spec)
    sys.modules[NAME] = mod
    spec.loader.exec_module(mod)
    return mod, build


drive_kernel, BUILD = _load()
