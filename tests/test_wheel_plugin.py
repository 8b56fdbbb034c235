"""deltahil installed from its wheel, used as a user would outside the repository (issue 22): the
pytest plugin's `hil_bench` fixture, `--hil-bench`, and `hil examples` giving the guide's files."""

from __future__ import annotations

import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

USER_TEST = '''
def test_demo(hil_bench):
    r = hil_bench.run("lathe_demo.nc")
    assert r.ok and r.program_time > 10


def test_own_program_against_the_copied_bench(hil_bench):
    r = hil_bench.run("examples/servo_params.nc", check=False)
    assert r.bench.name == "lathe-2axis" and r.trace.load().num_rows == r.cycles
'''


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A fresh virtual environment with the wheel installed (the dependencies come from the
    environment running the tests: no network)."""
    tmp = tmp_path_factory.mktemp("wheel")
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(tmp / "dist"), str(ROOT)], capture_output=True, text=True, timeout=300)
    if build.returncode != 0:
        pytest.skip(f"cannot build the wheel here: {build.stderr[-300:]}")
    wheel = next((tmp / "dist").glob("deltahil-*.whl"))
    from hil.version import __version__

    assert wheel.name.startswith(f"deltahil-{__version__}-")  # the metadata's version is the source's (B90)
    env_dir = tmp / "venv"
    venv.EnvBuilder(system_site_packages=True, with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    inst = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--ignore-installed", "-q",
                           str(wheel)], capture_output=True, text=True, timeout=300)
    assert inst.returncode == 0, inst.stderr
    return py


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # nothing from the repository
    env["PYTHONNOUSERSITE"] = "1"
    return env


def test_a_users_pytest_file_runs_against_the_installed_wheel(installed, tmp_path):
    user = tmp_path / "bench-tests"
    user.mkdir()
    hil = installed.parent / "hil"
    copied = subprocess.run([str(hil), "examples", str(user)], capture_output=True, text=True, env=_env(),
                            cwd=user, timeout=120)
    assert copied.returncode == 0, copied.stderr
    assert (user / "benches" / "lathe-2axis.toml").is_file() and (user / "examples" / "lathe_demo.nc").is_file()
    where = subprocess.run([str(installed), "-c", "import hil; print(hil.__file__)"], capture_output=True,
                           text=True, env=_env(), cwd=user)
    assert str(installed.parent.parent) in where.stdout  # the wheel's copy, not the repository's
    (user / "test_demo.py").write_text(USER_TEST)
    r = subprocess.run([str(installed), "-m", "pytest", "-q", "-p", "no:cacheprovider",
                        "--hil-bench", "benches/lathe-2axis.toml", "test_demo.py"],
                       capture_output=True, text=True, env=_env(), cwd=user, timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "2 passed" in r.stdout
