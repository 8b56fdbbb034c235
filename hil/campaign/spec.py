"""Campaign files (TOML): which programs, benches, buses, overrides, parameter sweeps, fault
injections and checks make up a matrix of lock-step runs, and the cases that matrix expands to.

Every error names the file and the field (`campaign.overrides[2]`, `case[3].bench`), as bench files
do; all problems in a file are reported at once. Relative paths are relative to the campaign file.
See docs/guide/campaigns.md for the format.
"""

from __future__ import annotations

import glob
import itertools
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hil.toml_fields import BenchFileError, FieldReader, read_text_file  # one field reader for every TOML input we take
from hil.session import InputError

BUSES = ("sim", "canopen:virtual")  # lock-step, in-process: what a worker can run with no hardware
NO_FAULT = "none"
_TOP = {"campaign", "params", "faults", "checks", "case"}
_CAMPAIGN = {"name", "programs", "benches", "buses", "overrides", "rapid_overrides", "spindle_overrides",
             "faults", "lib", "max_time", "trace", "mlc", "retries", "cross"}
_CASE = {"program", "bench", "bus", "override", "rapid_override", "spindle_override", "fault", "params"}


class CampaignFileError(BenchFileError):
    """A campaign file that cannot be used; one `field: message` per problem."""


@dataclass(frozen=True)
class Case:
    """One run of the matrix: what it runs and under which variant (paths as the user wrote them
    resolved against the campaign file; `params` and `events` as sorted tuples so a case hashes)."""

    program: Path
    bench: Path
    bus: str = "sim"
    override: float = 100.0
    rapid_override: float = 100.0
    spindle_override: float = 100.0
    params: tuple[tuple[str, float], ...] = ()
    fault: str = NO_FAULT
    events: tuple[str, ...] = ()

    def key(self, root: Path) -> dict[str, Any]:
        """The case's identity as a team reads it (names relative to the campaign file), the columns
        a diff joins on: a changed bench or program keeps its key and changes its input hash."""
        return {"program": _rel(self.program, root), "bench": _rel(self.bench, root), "bus": self.bus,
                "override": self.override, "rapid_override": self.rapid_override,
                "spindle_override": self.spindle_override,
                "params": ",".join(f"{k}={v:g}" for k, v in self.params), "fault": self.fault}


@dataclass
class Campaign:
    source: Path
    name: str = "campaign"
    cases: list[Case] = field(default_factory=list)
    lib: list[Path] = field(default_factory=list)
    checks: dict[str, Any] | None = None  # a [checks] table that replaces each bench's own
    max_time: float | None = None
    trace: bool = False
    mlc: str | None = None
    retries: int = 3

    @property
    def root(self) -> Path:
        return self.source.parent


def _rel(p: Path, root: Path) -> str:
    try:
        return p.relative_to(root).as_posix()
    except ValueError:
        return p.as_posix()


def load_campaign(path: str | Path) -> Campaign:
    text = read_text_file(path, CampaignFileError)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CampaignFileError(str(path), [f"not valid TOML: {exc}"]) from None
    return parse_campaign(data, Path(path).resolve())


def parse_campaign(data: dict[str, Any], source: Path) -> Campaign:
    r = FieldReader()
    root = source.parent
    c = Campaign(source=source, name=source.stem)
    top = r.table(data, "campaign", "campaign")
    if "campaign" not in data and not top:
        r.err("campaign", "missing: a campaign file needs a [campaign] table")
    c.name = r.string(top, "name", "campaign.name", c.name) or c.name
    programs = _paths(r, top, "programs", "campaign.programs", root, required=False)
    benches = _paths(r, top, "benches", "campaign.benches", root, required=False)
    buses = _strings(r, top, "buses", "campaign.buses", ["sim"], BUSES)
    overrides = _percents(r, top, "overrides", "campaign.overrides", 0, 150)
    rapid = _percents(r, top, "rapid_overrides", "campaign.rapid_overrides", 0, 100)
    spindle = _percents(r, top, "spindle_overrides", "campaign.spindle_overrides", 50, 120)
    c.lib = _paths(r, top, "lib", "campaign.lib", root, required=False, dirs=True)
    c.max_time = r.number(top, "max_time", "campaign.max_time", None, positive=True)
    c.trace = r.boolean(top, "trace", "campaign.trace", False)
    c.mlc = r.string(top, "mlc", "campaign.mlc", None)
    if c.mlc:
        _check_mlc(r, c.mlc, root)
    c.retries = r.integer(top, "retries", "campaign.retries", 3, minimum=1, maximum=20) or 3
    cross = r.boolean(top, "cross", "campaign.cross", True)

    sweeps = _sweeps(r, r.table(data, "params", "params"))
    faults = _faults(r, r.table(data, "faults", "faults"))
    chosen = _strings(r, top, "faults", "campaign.faults", [NO_FAULT, *faults], (NO_FAULT, *faults))
    if "checks" in data:
        checks = data.pop("checks")
        if not isinstance(checks, dict):
            r.err("checks", "must be a table like a bench's [checks]")
        else:
            c.checks = checks
    r.unknown(top, "campaign.", _CAMPAIGN)

    if cross and (programs or benches):
        if not programs:
            r.err("campaign.programs", "missing: the cross product needs programs (or set cross = false)")
        if not benches:
            r.err("campaign.benches", "missing: the cross product needs benches (or set cross = false)")
        names = sorted(sweeps)
        for prog, bench, bus, ov, ro, so, fault, *vals in itertools.product(
                programs, benches, buses, overrides, rapid, spindle, chosen, *(sweeps[n] for n in names)):
            c.cases.append(Case(prog, bench, bus, ov, ro, so, tuple(zip(names, vals)), fault,
                                faults.get(fault, ())))
    listed = data.pop("case", [])
    if not isinstance(listed, list) or not all(isinstance(x, dict) for x in listed):
        r.err("case", "must be an array of tables ([[case]])")
        listed = []
    for i, item in enumerate(listed):
        case = _case(r, dict(item), f"case[{i}]", root, faults)
        if case is not None:
            c.cases.append(case)
    r.unknown(data, "", _TOP)
    if not r.errors and not c.cases:
        r.err("campaign", "no cases: give programs and benches, or [[case]] tables")
    if not r.errors:
        _check_benches(r, c)
    if r.errors:
        raise CampaignFileError(str(source), r.errors)
    seen: set[Case] = set()  # a case listed twice (cross product and [[case]]) runs once
    c.cases = [x for x in c.cases if not (x in seen or seen.add(x))]
    return c


def _check_mlc(r: FieldReader, spec: str, root: Path) -> None:
    """The MLC every case runs, loaded once here: one that cannot load is the file's error (exit 2), as `hil run
    --mlc` refuses it, not an internal-error alarm in every case."""
    if spec in ("basic", "lathe", "default"):
        return
    from mlc.machine import MlcLoadError, load_program

    try:
        load_program(str((root / spec).resolve()) if spec.endswith(".py") else spec)
    except MlcLoadError as exc:
        r.err("campaign.mlc", str(exc))


def _paths(r: FieldReader, data: dict, key: str, path: str, root: Path, *, required: bool,
           dirs: bool = False) -> list[Path]:
    """A list of paths or globs, each of which must match something."""
    v = data.pop(key, None)
    if v is None:
        if required:
            r.err(path, "missing")
        return []
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not all(isinstance(x, str) and x.strip() for x in v):
        r.err(path, "must be an array of paths or globs")
        return []
    out: list[Path] = []
    for i, pattern in enumerate(v):
        full = pattern if Path(pattern).is_absolute() else str(root / pattern)
        hits = sorted(Path(h).resolve() for h in glob.glob(full, recursive=True))
        hits = [h for h in hits if h.is_dir() or h.is_file()] if dirs else [h for h in hits if h.is_file()]
        if not hits:
            r.err(f"{path}[{i}]", f"{pattern!r} matches no {'file or folder' if dirs else 'file'}")
        out += [h for h in hits if h not in out]
    return out


def _strings(r: FieldReader, data: dict, key: str, path: str, default: list[str], choices: tuple[str, ...]) -> list[str]:
    v = data.pop(key, None)
    if v is None:
        return default
    if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
        r.err(path, f"must be a non-empty array of strings from {', '.join(map(repr, choices))}")
        return default
    bad = [i for i, x in enumerate(v) if x not in choices]
    for i in bad:
        r.err(f"{path}[{i}]", f"must be one of {', '.join(map(repr, choices))}, got {v[i]!r}")
    return [x for x in v if x in choices]


def _percents(r: FieldReader, data: dict, key: str, path: str, low: float, high: float) -> list[float]:
    """Override percentages, within the range the MLC's override registers take."""
    v = data.pop(key, None)
    if v is None:
        return [100.0]
    if not isinstance(v, list) or not v:
        r.err(path, f"must be a non-empty array of percentages ({low:g} to {high:g})")
        return [100.0]
    out = []
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not low <= x <= high or (x == 0 and low == 0):
            r.err(f"{path}[{i}]", f"must be a percentage in ({low:g}, {high:g}], got {x!r}")
        else:
            out.append(float(x))
    return out or [100.0]


def _sweeps(r: FieldReader, table: dict) -> dict[str, list[float]]:
    """[params]: NC parameter name → list of values (a single number is a one-value sweep)."""
    out: dict[str, list[float]] = {}
    for name, v in table.items():
        path = f"params.{name!r}" if " " in name or "." in name else f"params.{name}"
        values = v if isinstance(v, list) else [v]
        good = [x for x in values if isinstance(x, (int, float)) and not isinstance(x, bool)
                and x == x and abs(x) != float("inf")]
        if not values or len(good) != len(values):
            r.err(path, f"must be a finite number or an array of them, got {v!r}")
            continue
        bad = _param_error(name, good)
        if bad:
            r.err(path, bad)
            continue
        out[name] = [float(x) for x in good]
    return out


def _param_error(name: str, values: list) -> str | None:
    """The bench file's own check of a parameter (hil/bench_params.py, B89): its name and each value's range."""
    from hil.bench_params import check_param

    for x in values:
        bad = check_param(name, x)
        if bad:
            return bad
    return None


def _faults(r: FieldReader, table: dict) -> dict[str, tuple[str, ...]]:
    """[faults]: name → the events (`hil run --at` grammar) that inject it; each event is checked
    against every bench's axes and MLC when the cases are built (variant.apply_variant)."""
    out: dict[str, tuple[str, ...]] = {}
    for name, v in table.items():
        path = f"faults.{name}"
        if name == NO_FAULT:
            r.err(path, f"{NO_FAULT!r} is the name of the run with no fault; choose another")
            continue
        events = [v] if isinstance(v, str) else v
        if not isinstance(events, list) or not events or not all(isinstance(e, str) for e in events):
            r.err(path, "must be an event string or an array of them (the `hil run --at` grammar)")
            continue
        out[name] = tuple(events)
    return out


def _case(r: FieldReader, item: dict, path: str, root: Path, faults: dict[str, tuple[str, ...]]) -> Case | None:
    n_err = len(r.errors)
    prog = _one_path(r, item, "program", f"{path}.program", root)
    bench = _one_path(r, item, "bench", f"{path}.bench", root)
    bus = r.string(item, "bus", f"{path}.bus", "sim", BUSES) or "sim"
    ov = r.number(item, "override", f"{path}.override", 100.0, minimum=0.0, maximum=150.0)
    ro = r.number(item, "rapid_override", f"{path}.rapid_override", 100.0, minimum=0.0, maximum=100.0)
    so = r.number(item, "spindle_override", f"{path}.spindle_override", 100.0, minimum=50.0, maximum=120.0)
    fault = r.string(item, "fault", f"{path}.fault", NO_FAULT, (NO_FAULT, *faults)) or NO_FAULT
    params = r.table(item, "params", f"{path}.params")
    values = {}
    for k, v in params.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or v != v or abs(v) == float("inf"):
            r.err(f"{path}.params.{k}", f"must be a finite number, got {v!r}")
        elif bad := _param_error(k, [v]):
            r.err(f"{path}.params.{k}", bad)
        else:
            values[k] = float(v)
    r.unknown(item, f"{path}.", _CASE)
    if len(r.errors) != n_err or prog is None or bench is None:
        return None
    return Case(prog, bench, bus, ov or 0.0, ro or 0.0, so or 0.0, tuple(sorted(values.items())), fault,
                faults.get(fault, ()))


def _one_path(r: FieldReader, item: dict, key: str, path: str, root: Path) -> Path | None:
    v = r.string(item, key, path, None)
    if v is None:
        r.err(path, "missing")
        return None
    p = (root / v).resolve()
    if not p.is_file():
        r.err(path, f"{v!r} is not a file")
        return None
    return p


def _check_benches(r: FieldReader, c: Campaign) -> None:
    """Each bench must load, take the campaign's [checks] and [params], and carry its own files."""
    from hil.campaign.inputs import bench_files
    from hil.campaign.variant import apply_variant

    for bench in sorted({x.bench for x in c.cases}):
        name = _rel(bench, c.root)
        try:
            bench_files(bench)
            for case in (x for x in c.cases if x.bench == bench):
                apply_variant(bench.read_text(encoding="utf-8"), str(bench), case, c.checks, c.max_time)
        except (InputError, OSError, ValueError) as exc:
            for line in str(exc).splitlines():
                r.err(f"benches ({name})", line)
            continue
