"""The deltahil pytest plugin (registered as `pytest11` entry point `deltahil`, so it is active
wherever deltahil is installed):

    def test_demo(hil_bench):
        r = hil_bench.run("lathe_demo.nc")
        assert r.ok and r.program_time > 10

`hil_bench.run(program, **options)` is `hil.run` in lock-step with a temporary Parquet trace and the
bench given by `--hil-bench FILE` (or `bench=` per call; default the built-in 2-axis lathe).
A program path is taken as given, else next to the test file, else among the shipped examples.
When a test fails, its report shows each run's alarms, check lines and trace path.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("deltahil")
    group.addoption("--hil-bench", metavar="FILE", default=None,
                    help="bench file for the hil_bench fixture (default: the built-in 2-axis lathe)")


class HilBench:
    def __init__(self, bench: str | None, test_dir: Path, tmp_path: Path) -> None:
        self.bench = bench
        self.test_dir = test_dir
        self.tmp_path = tmp_path
        self.runs: list[Any] = []

    def program(self, name: str | Path) -> Path:
        from hil.shipped import EXAMPLES

        p = Path(name)
        for candidate in (p, self.test_dir / p, EXAMPLES / p):
            if candidate.is_file():
                return candidate
        raise FileNotFoundError(f"program {name}: not found as given, next to the test ({self.test_dir}) "
                                f"or among the shipped examples")

    def run(self, program: str | Path, **options: Any) -> Any:
        import hil

        options.setdefault("bench", self.bench)
        options.setdefault("trace", self.tmp_path / f"run{len(self.runs) + 1}.parquet")
        result = hil.run(self.program(program), **options)
        self.runs.append(result)
        return result


@pytest.fixture
def hil_bench(request: pytest.FixtureRequest, tmp_path: Path) -> HilBench:
    bench = request.config.getoption("--hil-bench")
    if bench is not None:
        bench = str(Path(bench).resolve())
    hb = HilBench(bench, Path(str(request.path)).parent, tmp_path)
    request.node._hil_bench = hb
    return hb


def describe(result: Any) -> str:
    lines = [f"{result.program} on bench {result.bench.name}: "
             f"{'completed' if result.completed else 'STOPPED'}, program time {result.program_time:.3f} s"]
    lines += [f"  alarm {a}" for a in result.alarms]
    lines += [f"  {c}" for c in result.checks]
    lines += [f"  never fired: {e.spec}" for e in result.unfired]
    if result.trace is not None:
        lines.append(f"  trace {result.trace.path}")
    return "\n".join(lines)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo) -> Any:
    outcome = yield
    report = outcome.get_result()
    hb = getattr(item, "_hil_bench", None)
    if report.when == "call" and report.failed and hb is not None and hb.runs:
        report.sections.append(("deltahil runs", "\n".join(describe(r) for r in hb.runs)))
