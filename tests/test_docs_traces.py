"""docs/guide/traces-in-tools.md: every Python block of the page, run in order in one namespace,
in a folder holding the shipped examples, as a reader would paste them (issue 22)."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "guide" / "traces-in-tools.md"


def test_every_code_block_of_the_traces_page_runs(tmp_path, capsys):
    for lib in ("pandas", "polars", "duckdb"):
        pytest.importorskip(lib)
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    shutil.copytree(ROOT / "benches", tmp_path / "benches")
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), re.S)
    assert len(blocks) >= 6
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        namespace: dict = {}
        for i, code in enumerate(blocks):
            exec(compile(code, f"{PAGE.name} block {i + 1}", "exec"), namespace)
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert "mm/s rpm" in out and "lathe-2axis" in out
    assert (tmp_path / "ferr.png").stat().st_size > 1000
