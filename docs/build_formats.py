"""Generate docs/formats.md: every G/M format row of chapters 2–3 of the NC5 G command guide
("Instruction format:" tables) and of the older lathe guide ("Format:" lines), written as the manual
writes it, with the test that runs it (tests/test_formats_manual.py cites rows by id) or "untested".

Row ids are `N<section>-<k>` (NC5) and `L<section>-<k>` (lathe guide): the k-th format row under that
section heading. Run `python docs/build_formats.py`; tests/test_formats_manual.py fails when the page is
stale or a test cites a row the manuals do not have.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
SEEDS = ROOT.parent / "shared" / "seeds"
NC5 = "003_d9b0b41321b8a5fc.txt"
LATHE = "000_120db1f5ca3d468f.txt"
HEADING = re.compile(r"^(\d+(?:\.\d+){1,3})\s+\S")
CODE = re.compile(r"(?<![A-Z])([GM]\d{1,3}(?:\.\d)?)(?![\d.])")
ROW_ID = re.compile(r"\b([NL]\d+(?:\.\d+)+-\d+)\b")


@dataclass(frozen=True)
class FormatRow:
    id: str
    section: str
    title: str
    text: str  # as the manual writes it (tabs and subscripts kept, whitespace folded)
    line: int = 0  # 1-based line of the manual's text (shared/seeds/<manual>.txt)


# A format row is made of codes and argument words only (prose, group tables and definitions are not rows).
TOKEN = re.compile(r"^(?:[GM]\d{1,3}(?:\.\d)?|[A-Z]{1,2}[_\d₁₂]*(?:_?[A-Z]_?)*|,|[₁₂])$")
NC5_BLOCK = re.compile(r"^(?:Instruction format|Command format|Milling instruction format)\s*:|^G10\s+L\d")


def _nc5_row(line: str) -> tuple[str, bool] | None:
    """(text, has a code) when the line is a row of an NC5 format table, else None."""
    text = " ".join(line.replace("\t", " ").split())
    bare = re.sub(r"\([^)]*\)", " ", re.sub(r"^Format \d+\s+", "", text))
    toks = bare.split()
    if not toks or not all(TOKEN.match(t) for t in toks):
        return None
    has_code = any(CODE.fullmatch(t) for t in toks)
    if has_code and not CODE.fullmatch(toks[0]):
        return None  # an ID table's line (G10 L02's "P1 G54"), not a format
    return text, has_code


def _nc5_rows(lines: list[str]) -> list[tuple[str, str, str, int]]:
    """(section, title, text) of every row of the NC5 guide's format tables. A line of a table that carries
    only argument words (G30's P3, G04's X_, M98's Q_) continues the row above and is shown as `[G30] P3`."""
    out: list[tuple[str, str, str]] = []
    section, title, in_fmt, last_code = "", "", False, ""
    for n, raw in enumerate(lines, start=1):
        line = raw.rstrip()
        h = HEADING.match(line)
        if h and h.group(1)[0] in "23" and "\t" not in line and len(line) < 90:
            section, title, in_fmt, last_code = h.group(1), line, False, ""
            continue
        if not section:
            continue
        if NC5_BLOCK.match(line.strip()):
            in_fmt, last_code = True, ""
            if not line.strip().startswith("G10"):
                continue
        if not in_fmt:
            continue
        if line.startswith(("Instruction description", "Notes", "Note:", "Example", "Description")):
            in_fmt, last_code = False, ""
            continue
        if not line.strip():
            continue
        row = _nc5_row(line)
        if row is None:
            last_code = ""
            continue
        text, has_code = row
        if has_code:
            last_code = CODE.search(text).group(1)
            out.append((section, title, text, n))
        elif last_code:
            out.append((section, title, f"[{last_code}] {text}", n))
    return out


def _lathe_rows(lines: list[str]) -> list[tuple[str, str, str, int]]:
    """(section, title, text) of every format of the lathe guide: the "Format…:" line and the code-led
    lines that follow it (the `or` alternatives, a cycle's second block), up to the first prose line."""
    out: list[tuple[str, str, str]] = []
    section, title, in_fmt = "", "", False
    for n, raw in enumerate(lines, start=1):
        line = raw.rstrip()
        h = HEADING.match(line)
        if h and h.group(1)[0] in "23" and "\t" not in line and len(line) < 90:
            section, title, in_fmt = h.group(1), line, False
            continue
        if not section:
            continue
        s = line.strip()
        if s.startswith("Format"):
            in_fmt, s = True, s.split(":", 1)[1].strip() if ":" in s else ""
        elif not in_fmt or not s:
            continue
        if re.match(r"^(?:[A-Z] - [A-Z] plane:\s*)?[GM]\d{1,3}(?:\.\d)?(?:/[GM]\d+)*(?!:)(?:\s|;|$)", s):
            out.append((section, title, " ".join(s.split()), n))
        elif not (s.endswith(":") or s.startswith("Input parameter") or line.startswith("Format")):
            in_fmt = False
    return out


def _rows(lines: list[str], manual: str) -> list[FormatRow]:
    out: list[FormatRow] = []
    counts: dict[str, int] = {}
    for section, title, text, n in (_nc5_rows(lines) if manual == "N" else _lathe_rows(lines)):
        k = counts[section] = counts.get(section, 0) + 1
        out.append(FormatRow(f"{manual}{section}-{k}", section, title, text, n))
    return out


def manual_rows() -> list[FormatRow]:
    rows: list[FormatRow] = []
    for manual, name in (("N", NC5), ("L", LATHE)):
        rows += _rows((SEEDS / name).read_text().splitlines(), manual)
    return rows


TEST_FILES = "test_formats*.py"
UNRUN = DOCS / "formats-unrun.toml"


def tested_rows(tests_dir: Path = ROOT / "tests") -> dict[str, list[str]]:
    """row id -> test names that run it (ids written in a test's name, docstring or case table), over
    tests/test_formats*.py."""
    out: dict[str, list[str]] = {}
    for f in sorted(tests_dir.glob(TEST_FILES)):
        for rid, names in _tested_in(f).items():
            out.setdefault(rid, []).extend(f"{f.stem}::{n}" for n in names)
    return out


def unrun_rows() -> dict[str, str]:
    """row id -> why no test runs it, or (beside a test) what of the row deltahil does not model
    (docs/formats-unrun.toml)."""
    import tomllib

    return {k: v["reason"] for k, v in tomllib.loads(UNRUN.read_text()).items()} if UNRUN.exists() else {}


def _tested_in(test_file: Path) -> dict[str, list[str]]:
    import ast

    src = test_file.read_text()
    tree = ast.parse(src)
    out: dict[str, list[str]] = {}
    tests = [n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name.startswith("test")]
    for node in tree.body:
        seg = ast.get_source_segment(src, node) or ""
        if isinstance(node, ast.FunctionDef) and node.name.startswith("test"):
            users = [node.name]
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            names = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
            users = [t.name for t in tests if names & {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}]
        else:
            continue
        for rid in ROW_ID.findall(seg):
            for u in users:
                out.setdefault(rid, []).append(u)
    return out


def build() -> str:
    rows, tested, unrun = manual_rows(), tested_rows(), unrun_rows()
    n_tested = sum(1 for r in rows if r.id in tested)
    n_unrun = sum(1 for r in rows if r.id in unrun and r.id not in tested)
    head = ["# Format coverage: G and M code formats of the manuals, chapters 2–3", "",
            "*Generated by `python docs/build_formats.py` from the manuals (`shared/seeds/`), "
            "`tests/test_formats*.py` and `docs/formats-unrun.toml`; tests/test_formats_manual.py fails when this "
            "page is stale.*", "",
            f"{len(rows)} format rows ({sum(r.id[0] == 'N' for r in rows)} in the NC5 G command guide's "
            f"format tables, {sum(r.id[0] == 'L' for r in rows)} in the lathe guide's \"Format…:\" "
            f"lines and the alternatives written under them); **{n_tested} are run by a test** as the manual "
            f"writes them, {n_unrun} are not emulated (reason given). Where a tested row has a part deltahil does "
            f"not model, the test column says so after the test.", "",
            "A row `[G30] P3` is a line of the manual's table that carries only arguments: it continues the row "
            "above it (here `G30 P3 CP`). Row ids: `N<section>-<k>` is the k-th row under that section of the "
            "NC5 guide, `L<section>-<k>` of the lathe guide; the last column is the file and line of the manual's "
            f"text (`shared/seeds/`, NC5 = `{NC5}`, lathe guide = `{LATHE}`).", "",
            "| row | section | format as the manual writes it | test | manual line |", "|---|---|---|---|---|"]
    body = []
    for r in rows:
        t = ", ".join(f"`{x}`" for x in sorted(set(tested.get(r.id, []))))
        if not t and r.id in unrun:
            t = "not emulated: " + unrun[r.id].replace("|", "/")
        elif r.id in unrun:
            t += "; not modelled: " + unrun[r.id].replace("|", "/")
        text = r.text.replace("|", "\\|")
        src = f"{NC5 if r.id[0] == 'N' else LATHE}:{r.line}"
        body.append(f"| {r.id} | {r.title.replace('|', '/')} | `{text}` | {t or 'untested'} | {src} |")
    return "\n".join(head + body) + "\n"


if __name__ == "__main__":
    (DOCS / "formats.md").write_text(build())
    rows = manual_rows()
    print(len(rows), "rows,", len({r for r in tested_rows() if r in {x.id for x in rows}}), "tested")
