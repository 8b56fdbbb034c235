"""The deltahil version is the source's (bench decision B90): one string in hil/version.py that `hil --version`,
a trace's provenance and the package metadata (pyproject.toml reads it) all report, a bare checkout included,
and a run learns it without importing importlib.metadata."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _source_version() -> str:
    """The literal in hil/version.py, read as setuptools reads it (not by importing hil)."""
    import ast

    tree = ast.parse((ROOT / "hil" / "version.py").read_text())
    (value,) = [n.value.value for n in tree.body if isinstance(n, ast.Assign)
                and [t.id for t in n.targets if isinstance(t, ast.Name)] == ["__version__"]]
    return value


def test_the_package_metadata_takes_its_version_from_the_source():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "hil.version.__version__"}
    v = _source_version()
    assert v and all(p.isdigit() for p in v.split(".")[:2])


def test_a_bare_checkout_reports_the_source_version_everywhere(tmp_path):
    """From the source tree alone (no installed metadata in reach of the answer): `hil --version`, the trace's
    provenance, and no importlib.metadata imported by the run."""
    v = _source_version()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-m", "hil.cli", "--version"], capture_output=True, text=True,
                         cwd=tmp_path, env=env)
    assert (out.returncode, out.stdout, out.stderr) == (0, f"hil (deltahil) {v}\n", "")
    trace = tmp_path / "t.parquet"
    prog = tmp_path / "p.nc"
    prog.write_text("G00 X10\nM30\n")
    code = ("import sys; from hil.cli import main; "
            f"rc = main(['run', {str(prog)!r}, '--trace', {str(trace)!r}]); "
            "print(rc, 'importlib.metadata' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-2:] == ["0", "False"]
    from hil.trace_read import TraceFile

    assert TraceFile(trace).meta["deltahil_version"] == v
