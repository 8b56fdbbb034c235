"""No import circle inside nc/ (issue 16): the modules of nc/ import each other without any circle,
counting every import that runs (at module level or deferred inside a function; an import for type
hints under `if TYPE_CHECKING` never runs), and no module imports the orchestrator
nc.interp.interpreter back (only the package nc.interp re-exports it)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NC = ROOT / "nc"


def _modules() -> dict[str, Path]:
    out = {}
    for path in NC.rglob("*.py"):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """nc modules that `name` imports at run time: at module level or inside a function, not under
    `if TYPE_CHECKING:` (imports for type hints never run)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    typing_only = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
                   for part in node.body for n in ast.walk(part)}
    nodes = [n for n in ast.walk(tree) if id(n) not in typing_only]
    out: set[str] = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name in modules}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            for a in node.names:
                sub = f"{base}.{a.name}"
                if sub in modules:
                    out.add(sub)
                elif base in modules:
                    out.add(base)
    out.discard(name)
    return out


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circle_in_nc() -> None:
    modules = _modules()
    graph = {m: _imports(m, p, modules) - {m.rpartition(".")[0]} for m, p in modules.items()}
    assert "nc.interp.execute" in graph and graph["nc.interp.interpreter"]  # the graph is read
    assert _circles(graph) == []


def test_no_module_imports_the_orchestrator() -> None:
    modules = _modules()
    importers = sorted(m for m, p in modules.items() if "nc.interp.interpreter" in _imports(m, p, modules))
    assert importers == ["nc.interp"]


def test_the_circle_finder_finds_a_circle() -> None:
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
