"""A case's inputs carried by content, so a worker on another machine needs no shared file system:
the program with the subprograms beside it, the bench with the files it names, the campaign's
libraries and MLC module. `materialise` lays them out again in a scratch folder on the worker,
each at its original absolute path below that folder, so relative references still resolve.
"""

from __future__ import annotations

import hashlib
import json
import re
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from hil.campaign.spec import Campaign

# An O-numbered program file as NC5 names it (nc/store.py): O1, O0001, O0001.NC …
_O_FILE = re.compile(r"^O\d{1,5}(\.(nc|txt|ngc))?$", re.IGNORECASE)


@dataclass(frozen=True)
class CaseInputs:
    """Everything a worker needs for one run; `input_hash` covers all of it but `want_trace`."""

    key: dict[str, Any]
    files: tuple[tuple[str, bytes], ...]  # absolute source path → content
    program: str
    bench: str
    libs: tuple[str, ...] = ()
    mlc: str | None = None  # a module name, "basic"/"lathe", or a carried file's source path
    bus: str = "sim"
    override: float = 100.0
    rapid_override: float = 100.0
    spindle_override: float = 100.0
    params: tuple[tuple[str, float], ...] = ()
    events: tuple[str, ...] = ()
    checks: str = ""  # the campaign's [checks] table as JSON, "" = the bench's own
    max_time: float | None = None
    want_trace: bool = False
    input_hash: str = field(default="", compare=False)


def bench_files(bench: Path) -> list[Path]:
    """The files a bench file names (an MLC module path, CANopen EDS files), resolved against the
    bench's folder; ValueError for one that is absolute or missing, since it could not travel."""
    data = tomllib.loads(bench.read_text(encoding="utf-8"))
    names: list[str] = []
    mlc = data.get("mlc")
    if isinstance(mlc, str) and mlc.endswith(".py"):
        names.append(mlc)
    for group in ("axes", "spindles", "io"):
        for item in data.get(group, []) or []:
            if isinstance(item, dict) and isinstance(item.get("canopen_eds"), str):
                names.append(item["canopen_eds"])
    out = []
    for n in names:
        if Path(n).is_absolute():
            raise ValueError(f"{n}: a campaign bench must name its files relative to itself so runs carry them")
        p = (bench.parent / n).resolve()
        if not p.is_file():
            raise ValueError(f"{n}: no such file next to {bench.name}")
        out.append(p)
    return out


def program_files(program: Path) -> list[Path]:
    """The program and the O-numbered subprogram files of its folder (NC5 searches there first)."""
    folder = program.parent
    subs = sorted(p for p in folder.iterdir() if p.is_file() and _O_FILE.match(p.name) and p != program)
    return [program, *subs]


def lib_files(lib: Path) -> list[Path]:
    if lib.is_file():
        return [lib]
    return sorted(p for p in lib.rglob("*") if p.is_file() and (_O_FILE.match(p.name) or p.suffix.lower() == ".nc"))


def gather(campaign: Campaign) -> list[CaseInputs]:
    """Every case of the campaign with its inputs read once and hashed."""
    cache: dict[Path, bytes] = {}

    def read(p: Path) -> bytes:
        if p not in cache:
            cache[p] = p.read_bytes()
        return cache[p]

    libs = [f for lib in campaign.lib for f in lib_files(lib)]
    mlc_file = None
    if campaign.mlc and campaign.mlc.endswith(".py"):
        mlc_file = (campaign.root / campaign.mlc).resolve()
    checks = json.dumps(campaign.checks, sort_keys=True) if campaign.checks is not None else ""
    out = []
    for case in campaign.cases:
        paths = program_files(case.program) + [case.bench, *bench_files(case.bench)] + libs + ([mlc_file] if mlc_file else [])
        seen: list[Path] = []
        for p in paths:
            if p not in seen:
                seen.append(p)
        files = tuple((str(p), read(p)) for p in seen)
        mlc = str(mlc_file) if mlc_file else campaign.mlc
        inputs = CaseInputs(case.key(campaign.root), files, str(case.program), str(case.bench),
                            tuple(str(x) for x in campaign.lib), mlc, case.bus, case.override,
                            case.rapid_override, case.spindle_override, case.params, case.events, checks,
                            campaign.max_time, campaign.trace)
        out.append(_hashed(inputs))
    return out


def _hashed(inputs: CaseInputs) -> CaseInputs:
    """The content hash: file contents by their name relative to the program (not where the
    campaign happens to sit), and every variant field; not the trace wish, which changes no result."""
    h = hashlib.sha256()
    fields_ = asdict(inputs)
    for name in ("files", "key", "want_trace", "input_hash", "program", "bench", "libs", "mlc"):
        fields_.pop(name)
    anchor = Path(inputs.program).parent
    for path, content in inputs.files:
        h.update(_relative(path, anchor).encode() + b"\0" + hashlib.sha256(content).digest())
    h.update(json.dumps({"program": _relative(inputs.program, anchor), "bench": _relative(inputs.bench, anchor),
                         "libs": [_relative(x, anchor) for x in inputs.libs],
                         "mlc": _relative(inputs.mlc, anchor) if inputs.mlc and inputs.mlc.endswith(".py")
                         else inputs.mlc, **fields_}, sort_keys=True, default=list).encode())
    from dataclasses import replace

    return replace(inputs, input_hash=h.hexdigest()[:20])


def _relative(path: str, anchor: Path) -> str:
    import os

    return os.path.relpath(path, anchor)


def materialise(inputs: CaseInputs, scratch: Path) -> dict[str, str]:
    """Write the carried files below `scratch`; returns source path → path on this machine."""
    where: dict[str, str] = {}
    for path, content in inputs.files:
        local = scratch / path.lstrip("/")
        local.parent.mkdir(parents=True, exist_ok=True)
        local.write_bytes(content)
        where[path] = str(local)
    for lib in inputs.libs:
        where.setdefault(lib, str(scratch / lib.lstrip("/")))
        Path(where[lib]).parent.mkdir(parents=True, exist_ok=True)
    return where
