"""Shared helper for the language tests: run `hil path --json` in-process and split its output."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from hil.cli import main


@dataclass
class PathResult:
    code: int
    moves: list[dict] = field(default_factory=list)
    vars: dict[str, float | None] = field(default_factory=dict)
    alarm: dict | None = None
    other: list[dict] = field(default_factory=list)

    def ends(self, *axes: str) -> list[tuple[float, ...]]:
        return [tuple(m["work"][a] for a in axes) for m in self.moves]

    def machine(self, *axes: str) -> list[tuple[float, ...]]:
        return [tuple(m["end"][a] for a in axes) for m in self.moves]


def run_path(capsys, tmp_path, text: str, *args: str, profile: str = "nc5-mill", name: str = "p.nc",
             files: dict[str, str] | None = None) -> PathResult:
    f = tmp_path / name
    f.write_text(text)
    for fname, body in (files or {}).items():
        (tmp_path / fname).write_text(body)
    argv = ["path", str(f), "--json", "--profile", profile, *args]
    capsys.readouterr()
    code = main(argv)
    out = capsys.readouterr().out
    r = PathResult(code)
    for line in out.splitlines():
        if not line.strip():
            continue
        d = json.loads(line)
        if d["kind"] in ("rapid", "line", "arc", "thread", "dwell"):
            r.moves.append(d)
        elif d["kind"] == "vars":
            r.vars = d["values"]
        elif d["kind"] == "alarm":
            r.alarm = d
        else:
            r.other.append(d)
    return r
