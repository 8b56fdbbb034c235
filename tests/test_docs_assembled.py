"""docs/decisions.md and docs/performance.md are the assembled per-area files, never stale."""

from __future__ import annotations

import importlib.util

from tests.conftest import ROOT


def _builder():
    spec = importlib.util.spec_from_file_location("build_docs", ROOT / "docs" / "build_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_assembled_pages_are_up_to_date():
    b = _builder()
    for kind in ("decisions", "performance"):
        assert (ROOT / "docs" / f"{kind}.md").read_text() == b.assemble(kind), \
            f"docs/{kind}.md is stale: run python docs/build_docs.py"


def test_every_catalogued_ambiguity_has_a_recorded_decision():
    import re

    text = (ROOT / "docs" / "decisions.md").read_text()
    missing = [f"A{i}" for i in range(1, 60) if not re.search(rf"\bA{i}\b", text)]
    assert not missing, missing
