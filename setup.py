"""Compiles with Cython, where a C compiler is at hand (issue 17): virtual_bus/drive_kernel.py (the simulated drive's
arithmetic, B113) and the planner's hot modules (B115); pyproject.toml holds the rest of the build. The extensions are
optional: without a compiler (or without Cython, in a build without isolation) the install goes on and the same
modules run as Python (virtual_bus/kernels.py and nc/motion/compiled.py say which runs). nc/motion/ruckig_direct.pyx
(C++) calls ruckig's own C++ for the planner's 1-DoF solves where the ruckig at hand ships its headers and library
(B162)."""

import importlib.metadata
import shutil
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

# The planner's hot modules (decision bench B115): one unit, nc/motion/compiled.py's MODULES, in the same order.
PLANNER = ["block", "blending", "lookahead", "shares", "planner",
           "profile", "sample_rows", "planner_cruise", "planner_runs", "smoothing", "planner_corners",
           "spline_feed", "path", "share_zones", "plan_core"]
KERNELS = ["virtual_bus/drive_kernel.py"] + [f"nc/motion/{name}.py" for name in PLANNER]


def _ruckig_direct() -> list[Extension]:
    """nc/motion/ruckig_direct (decision bench B162), compiled against the ruckig installed here (the build
    requirement in an isolated build): its headers and libruckig.a, from the distribution's own file list. Its
    version is compiled in: nc/motion/compiled.py takes the extension only where the ruckig imported at run time is
    the same, so the answers are the Python module's bits. None where that ruckig ships no headers or library."""
    try:
        dist = importlib.metadata.distribution("ruckig")
    except importlib.metadata.PackageNotFoundError:
        return []
    files = [str(f) for f in dist.files or ()]
    header = next((f for f in files if f.endswith("include/ruckig/calculator_target.hpp")), None)
    library = next((f for f in files if f.endswith("/libruckig.a")), None)
    if header is None or library is None:
        return []
    include = Path(str(dist.locate_file(header))).parents[1]
    return [Extension("nc.motion.ruckig_direct", ["nc/motion/ruckig_direct.pyx"], language="c++",
                      include_dirs=["nc/motion", str(include)], extra_objects=[str(dist.locate_file(library))],
                      define_macros=[("RUCKIG_BUILT_VERSION", f'"{dist.version}"'), ("WITH_CLOUD_CLIENT", None)],
                      # as the kernels: each operation rounds as IEEE says (no contraction, no fast-math, no -march)
                      extra_compile_args=["-std=c++20", "-O2", "-ffp-contract=off", "-fno-fast-math"],
                      depends=["nc/motion/ruckig_direct.hpp"])]


def _extensions() -> list[Extension]:
    try:
        from Cython.Build import cythonize
    except ImportError:  # a build without isolation in an environment without Cython: pure Python
        return []
    exts = [Extension(path[:-3].replace("/", "."), [path],
                      # each operation rounds as Python's does: no fused multiply-add, no fast-math
                      extra_compile_args=["-O2", "-ffp-contract=off", "-fno-fast-math"]) for path in KERNELS]
    exts += _ruckig_direct()
    built = cythonize(exts, language_level=3, quiet=True, build_dir="build/cython",
                      compiler_directives={"annotation_typing": False, "cdivision": False, "boundscheck": True,
                                           "wraparound": True, "embedsignature": True})
    for ext in built:  # cythonize makes new Extensions and drops the flag: a failed compile must not fail the install
        ext.optional = True
    return built


class _BuildExt(build_ext):
    """Takes a module's build already beside its source where it is newer than its C file and the files that C was
    made from: the README's second command (`pip install -e '.[test]'`) compiled the same C again, ≈ 1.5 min of CI's
    20. Cython regenerates a C file whose .py or .pxd changed, so an edited module is compiled as before."""

    def build_extension(self, ext: Extension) -> None:
        built = Path(self.get_ext_filename(ext.name))  # where an editable install leaves it, from the project root
        target = Path(self.get_ext_fullpath(ext.name))
        inputs = [Path(f) for f in [*ext.sources, *ext.depends]]
        if (not self.force and built.is_file() and built.resolve() != target.resolve()
                and all(f.is_file() and f.stat().st_mtime < built.stat().st_mtime for f in inputs)):
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(built, target)
            return
        super().build_extension(ext)


setup(ext_modules=_extensions(), cmdclass={"build_ext": _BuildExt})
