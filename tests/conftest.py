"""Shared test helpers: run the `hil` CLI in-process and capture what a user would see."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest

from hil.cli import main as hil_main

ROOT = Path(__file__).resolve().parent.parent


@dataclass
class CliResult:
    code: int
    out: str
    err: str

    def json_lines(self) -> list[dict]:
        return [json.loads(line) for line in self.out.splitlines() if line.strip()]


@pytest.fixture
def hil(capsys):
    """Call `hil ARGS...` in-process; returns exit code, stdout and stderr."""

    def run(*args: str) -> CliResult:
        capsys.readouterr()
        code = hil_main([str(a) for a in args])
        captured = capsys.readouterr()
        return CliResult(code, captured.out, captured.err)

    return run


@pytest.fixture
def program(tmp_path):
    """Write a program text to a file and return its path."""

    def make(text: str, name: str = "prog.nc") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return make


def run_counting_queue(bench, text: str):
    """Run a program text on a bench (lock-step) and record the look-ahead queue length each cycle:
    (runner, result, lengths)."""
    from hil.runner import BenchRunner
    from hil.session import make_link
    from nc.program import parse_program

    lengths: list[int] = []
    runner = BenchRunner(bench, make_link(bench), None,
                         on_cycle=lambda r: lengths.append(len(r.channel.planner.queue)) if r.channel else None)
    result = runner.run_program(parse_program(text, name="p.nc"))
    return runner, result, lengths
