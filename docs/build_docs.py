"""Assemble docs/decisions.md and docs/performance.md from the per-area files beside them.

Each area keeps its own file (docs/decisions/<area>.md, docs/performance/<area>.md) so the code
that a decision concerns can point at it; the assembled pages are what a reader opens.
Run `python docs/build_docs.py`; tests/test_docs_assembled.py fails when they are stale.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent

ORDER = ["foundation", "language", "interp", "cycles", "motion", "ethercat", "canopen", "mlc", "bench", "campaign",
         "bench-tools", "budgets", "program-input", "inputs", "reliability", "report"]

HEADERS = {
    "decisions": """# Decisions where the Delta manuals are ambiguous

The NC5 G command guide (`shared/seeds/003_…`) is normative; the older lathe guide (`000_…`) is a
selectable profile. Where they are silent or contradict each other, each decision below names the
manual reference (or the seed-catalog ambiguity id A1–A59, seed-mlc-interface §6 ids), the choice
made, and the test that pins it. Sections, by area: {toc}.

*Assembled by `python docs/build_docs.py` from `docs/decisions/<area>.md`.*
""",
    "performance": """# Performance

Figures printed by the scripts in `benchmarks/` (they measure, never assert). Unless a section says
otherwise they were measured on the project's CI-class machine: 2 vCPU (AMD EPYC VM), 24 GiB,
Debian 12, Python 3.11.7, ruckig 0.19.4, pysoem 1.1.13, python-can 4.6.1, canopen 2.4.1, often
shared with other jobs — treat them as CI numbers, not real-time numbers. Sections: {toc}.

*Assembled by `python docs/build_docs.py` from `docs/performance/<area>.md`.*
""",
}


def assemble(kind: str) -> str:
    folder = DOCS / kind
    files = sorted(folder.glob("*.md"), key=lambda p: (ORDER.index(p.stem) if p.stem in ORDER else 99, p.stem))
    toc = ", ".join(f"[{p.stem}](#{p.stem})" for p in files)
    parts = [HEADERS[kind].format(toc=toc)]
    for p in files:
        body = p.read_text().strip()
        parts.append(f'<a id="{p.stem}"></a>\n\n<!-- from docs/{kind}/{p.name} -->\n\n{body}\n')
    return "\n".join(parts)


def main() -> int:
    for kind in HEADERS:
        (DOCS / f"{kind}.md").write_text(assemble(kind))
    return 0


if __name__ == "__main__":
    sys.exit(main())
