"""Bench files (TOML): read, validate every field, build a `Bench`.

Every error names the file and the field path (`axes[1].counts_per_rev`) with what was expected
and what was found; unknown keys are errors too, because a misspelt key silently ignored is how a
bench ends up running with a default nobody chose. All problems in a file are reported at once.
See docs/guide/bench-file.md for the format.
"""

from __future__ import annotations

import tomllib
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from fieldbus.factory import parse_bus
from fieldbus.pdo import ASDA_CSP, ASDA_CSP_CSV
from fieldbus.devices import DEFAULT_MODEL, MODELS
from fieldbus.units import AxisScaling
from hil.bench_groups import parse_groups
from hil.bench_params import check_param, check_together
from hil.bench import LIMIT_BOUNDS, LOCKSTEP_PLACEMENTS, AxisConfig, Bench, ChecksConfig, IoStationConfig, RealtimeConfig, SpindleConfig
from hil.drive_homing import DriveHoming
from hil.toml_fields import BenchFileError, FieldReader, kind_of, read_text_file
from nc.motion.limits import AxisLimits
from nc.profiles import PROFILE_NAMES
from virtual_bus.drive import DriveParams
from virtual_bus.drive_modes import HOMING_METHODS

AXIS_LETTERS = "XYZABCUVW"
CIA301_BITRATES = (10_000, 20_000, 50_000, 125_000, 250_000, 500_000, 800_000, 1_000_000)  # CiA 301 bit timing table
MODEL_ALIASES = {"asda-a3": "asda-a3-e"}  # the name benches used before the models were real (issue 23)
# DriveParams fields a bench may override, with whether they are integers (counts) or reals.
_DRIVE_INT = {"following_error_window", "negative_limit", "positive_limit", "home_switch", "index_pulse_every",
              "substeps", "probe_position"}
_DRIVE_KEYS = {f.name for f in fields(DriveParams)} - {"counts_per_rev", "units"}


def nc5(code: int) -> str:
    """The NC5 start-up alarm a bench error corresponds to, for the message (exit stays 2: bad input)."""
    from nc.alarm_table import ALARM_TABLE

    return f" (NC5 alarm 0x{code:04X}: {ALARM_TABLE[code][1].rstrip('.')})"


def load_bench_file(path: str | Path) -> Bench:
    return parse_bench(read_text_file(path), str(path))


def parse_bench(text: str, source: str = "bench.toml") -> Bench:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise BenchFileError(source, [f"not valid TOML: {exc}"]) from None
    r = FieldReader()
    r.base = Path(source).parent
    b = Bench(source=source)
    b.name = r.string(data, "name", "name", Path(source).stem) or b.name
    b.profile = r.string(data, "profile", "profile", b.profile, PROFILE_NAMES) or b.profile
    cycle_ms = r.number(data, "cycle_ms", "cycle_ms", b.cycle * 1000.0, minimum=0.125, maximum=100.0)
    b.cycle = (cycle_ms or 1.0) / 1000.0
    bus = r.string(data, "bus", "bus", b.bus)
    if bus is not None:
        try:
            parse_bus(bus)
            b.bus = bus
        except ValueError as exc:
            r.err("bus", str(exc))
    b.mlc = r.string(data, "mlc", "mlc", b.mlc) or b.mlc
    b.enable_timeout = r.number(data, "enable_timeout", "enable_timeout", b.enable_timeout, positive=True) or 0.5
    b.settle_time = r.number(data, "settle_time", "settle_time", b.settle_time, minimum=0.0)
    b.max_time = r.number(data, "max_time", "max_time", b.max_time, positive=True) or b.max_time
    b.lookahead = r.integer(data, "lookahead", "lookahead", None, positive=True)
    b.canopen_bitrate = r.integer(data, "canopen_bitrate", "canopen_bitrate", b.canopen_bitrate,
                                  choices=CIA301_BITRATES) or b.canopen_bitrate

    params = r.table(data, "params", "params")
    for k, v in params.items():
        where = f"params.{k!r}" if " " in k else f"params.{k}"
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            r.err(where, f"must be a number, got {kind_of(v)}")
        elif (problem := check_param(k, v)) is not None:
            r.err(where, problem)
        else:
            b.params[k] = float(v)

    axes = data.pop("axes", None)
    if axes is None:
        r.err("axes", "missing: a bench needs at least one [[axes]] table")
        axes = []
    elif not isinstance(axes, list) or not all(isinstance(a, dict) for a in axes):
        r.err("axes", f"must be an array of tables ([[axes]]), got {kind_of(axes)}")
        axes = []
    elif not axes:
        r.err("axes", "must list at least one axis")
    for i, a in enumerate(axes):
        ax = _axis(r, dict(a), f"axes[{i}]")
        if ax is not None:
            if ax.name in b.axis_names:
                r.err(f"axes[{i}].name", f"duplicate axis name {ax.name!r}" + nc5(0x1419))
            else:
                b.axes.append(ax)

    spindles = data.pop("spindles", [])
    if not isinstance(spindles, list) or not all(isinstance(s, dict) for s in spindles):
        r.err("spindles", f"must be an array of tables ([[spindles]]), got {kind_of(spindles)}")
        spindles = []
    for i, s in enumerate(spindles):
        sp = _spindle(r, dict(s), f"spindles[{i}]")
        if sp is not None:
            if any(o.name == sp.name for o in b.spindles):
                r.err(f"spindles[{i}].name", f"duplicate spindle name {sp.name!r}" + nc5(0x141A))
            else:
                b.spindles.append(sp)

    b.realtime = _realtime(r, r.table(data, "realtime", "realtime"))
    b.checks = _checks(r, r.table(data, "checks", "checks"), b.axis_names)
    b.io = _io_stations(r, data.pop("io", []), len(b.axes) + len(b.spindles))
    for k, problem in check_together(b.params, b.axis_names):
        r.err(f"params.{k!r}" if " " in k else f"params.{k}", problem)
    b.param_groups = parse_groups(r, data.pop("param_groups", {}), b.axes, b.params)
    r.unknown(data, "", {"name", "profile", "cycle_ms", "bus", "mlc", "enable_timeout", "settle_time", "max_time",
                         "lookahead", "params", "axes", "spindles", "realtime", "checks", "io", "canopen_bitrate",
                         "param_groups"})

    names = b.axis_names
    if b.axes and b.profile != "nc5-mill" and "X" not in names:
        r.err("axes", f"a lathe profile ({b.profile}) needs an X axis, got {', '.join(names)}")
    if b.axes and b.profile == "nc5-mill" and not {"X", "Y", "Z"} <= set(names):
        r.err("axes", f"profile nc5-mill needs X, Y and Z axes, got {', '.join(names)}")
    if r.errors:
        raise BenchFileError(source, r.errors)
    return b


def _scaling(r: FieldReader, d: dict, p: str, default_lead: float) -> AxisScaling:
    base = AxisScaling()
    cpr = r.integer(d, "counts_per_rev", f"{p}.counts_per_rev", base.counts_per_rev, positive=True,
                    maximum=2**31 - 1)  # CiA 402 position is a signed 32-bit count
    ratio = r.pair(d, "ratio", f"{p}.ratio", integers=True, positive=True) or (1, 1)
    lead = r.number(d, "lead", f"{p}.lead", default_lead, positive=True, minimum=1e-6, maximum=1e4)
    direction = r.integer(d, "direction", f"{p}.direction", 1, choices=(1, -1))
    return AxisScaling(counts_per_rev=cpr or base.counts_per_rev, gear_motor=int(ratio[0]), gear_load=int(ratio[1]),
                       lead=lead or default_lead, direction=direction or 1)


def _for_model(scaling: AxisScaling, model: str, cpr_given: bool, model_named: bool) -> AxisScaling:
    """The drive model's units, and its default resolution where the bench names the model but gives no
    `counts_per_rev` (decisions E17; a bench naming neither keeps the generic 1 280 000 PUU/rev)."""
    m = MODELS[model]
    cpr = m.counts_per_rev if model_named and not cpr_given else scaling.counts_per_rev
    return replace(scaling, counts_per_rev=cpr, units=m.units)


# Drive defaults held in counts are physical quantities (rev/s², motor revs) written at the generic
# 1 280 000 counts/rev; at another resolution the same physics is more counts (decisions E17).
_COUNT_FIELDS = ("csv_accel", "quick_stop_decel", "following_error_window")


def _drive_at_resolution(drive: DriveParams, given: set[str], cpr: int) -> DriveParams:
    """`drive` with the counts-valued defaults the bench did not set rescaled to `cpr` counts/rev."""
    ratio = cpr / DriveParams.counts_per_rev
    if ratio == 1.0:
        return drive
    return replace(drive, **{k: type(getattr(drive, k))(getattr(drive, k) * ratio)
                             for k in _COUNT_FIELDS if k not in given})


def _given(d: dict) -> set[str]:
    table = d.get("drive")
    return set(table) if isinstance(table, dict) else set()


def _drive(r: FieldReader, d: Any, p: str, base: DriveParams) -> tuple[DriveParams, str, str, int | None]:
    """The drive table: tuning, `model` (fieldbus.devices.MODELS), `esi` (a vendor ESI file the
    virtual EtherCAT slave is built from instead of the packaged one; the model's product code picks
    the device in it) and `alias` (the EtherCAT station alias the slave must have, App. A 0x1416)."""
    if not isinstance(d, dict):
        r.err(p, f"must be a table, got {kind_of(d)}")
        return base, DEFAULT_MODEL, "", None
    d = dict(d)
    alias = r.integer(d, "alias", f"{p}.alias", None, minimum=0, maximum=0xFFFF)
    model = r.string(d, "model", f"{p}.model", DEFAULT_MODEL) or DEFAULT_MODEL
    model = MODEL_ALIASES.get(model, model)
    if model not in MODELS:
        r.err(f"{p}.model", f"unknown drive model {model!r}; choose one of {', '.join(MODELS)}")
        model = DEFAULT_MODEL
    esi = r.string(d, "esi", f"{p}.esi", None) or ""
    if esi:
        from virtual_bus.ethercat.device import parse_device

        esi = str((r.base / Path(esi).expanduser()).resolve())
        try:
            parse_device(esi, MODELS[model].product_code)
        except (OSError, ValueError, KeyError, SyntaxError) as exc:  # ET.ParseError is a SyntaxError
            r.err(f"{p}.esi", f"cannot use {esi}: {exc}")
            esi = ""
    values: dict[str, Any] = {}
    for key in sorted(_DRIVE_KEYS & set(d)):
        if key in _DRIVE_INT:
            v = r.integer(d, key, f"{p}.{key}", None, positive=key in ("substeps", "index_pulse_every",
                                                                       "following_error_window"))
        else:
            v = r.number(d, key, f"{p}.{key}", None, positive=True)
        if v is not None:
            values[key] = v
    r.unknown(d, f"{p}.", _DRIVE_KEYS | {"model", "esi", "alias"})
    kw = {f.name: getattr(base, f.name) for f in fields(DriveParams)}
    kw.update(values)
    return DriveParams(**kw), model, esi, alias


def _axis(r: FieldReader, d: dict, p: str) -> AxisConfig | None:
    if "name" not in d:
        r.err(f"{p}.name", "missing: every axis needs a name (X, Y, Z, C ...)")
    name = r.string(d, "name", f"{p}.name", None)
    if name is not None and (len(name) != 1 or name not in AXIS_LETTERS):
        r.err(f"{p}.name", f"must be one axis letter of {AXIS_LETTERS}, got {name!r}")
        name = None
    units = r.string(d, "units", f"{p}.units", "mm", ("mm", "deg")) or "mm"
    if name is not None and name in "ABC" and units != "deg":  # the NC treats A/B/C as rotary (degrees)
        r.err(f"{p}.units", f"{name} is a rotary axis: units must be \"deg\", got {units!r}"
                            + nc5(0x0C05 if name == "C" else 0x141C))
    cpr_given, model_named = "counts_per_rev" in d, isinstance(d.get("drive"), dict) and "model" in d["drive"]
    scaling = _scaling(r, d, p, 360.0 if units == "deg" else 10.0)
    start = r.number(d, "start", f"{p}.start", 0.0, minimum=-1e6, maximum=1e6) or 0.0
    soft = r.pair(d, "soft_limits", f"{p}.soft_limits", integers=False, positive=False)
    if soft is not None:
        if soft[0] >= soft[1]:
            r.err(f"{p}.soft_limits", f"lower limit must be below the upper, got [{soft[0]:g}, {soft[1]:g}]")
            soft = None
        elif not soft[0] <= start <= soft[1]:
            r.err(f"{p}.start", f"{start:g} lies outside soft_limits [{soft[0]:g}, {soft[1]:g}]")
    lim = r.table(d, "limits", f"{p}.limits")
    base = AxisLimits()
    # Physically plausible bounds (decisions inputs.md I4): 1e-50 or 1e200 is a typo, not a machine.
    limits = AxisLimits(*(r.number(lim, k, f"{p}.limits.{k}", dflt, positive=True, minimum=LIMIT_BOUNDS[k][0],
                                   maximum=LIMIT_BOUNDS[k][1])
                          for k, dflt in (("velocity", base.max_velocity), ("acceleration", base.max_acceleration),
                                          ("jerk", base.max_jerk))))
    r.unknown(lim, f"{p}.limits.", {"velocity", "acceleration", "jerk"})
    given = _given(d)
    drive, model, esi, alias = _drive(r, d.pop("drive", {}), f"{p}.drive", DriveParams())
    scaling = _for_model(scaling, model, cpr_given, model_named)
    drive = _drive_at_resolution(drive, given, scaling.counts_per_rev)
    eds = r.eds(d, f"{p}.canopen_eds", ASDA_CSP)
    homing = _homing(r, d, f"{p}.homing")
    r.unknown(d, f"{p}.", {"name", "units", "counts_per_rev", "ratio", "lead", "direction", "start", "soft_limits",
                           "limits", "drive", "canopen_eds", "homing"})
    if name is None:
        return None
    return AxisConfig(name, scaling, limits, drive, start=start, units=units,
                      soft_limits=(float(soft[0]), float(soft[1])) if soft else None, drive_model=model,
                      canopen_eds=eds, drive_esi=esi, homing=homing, station_alias=alias)


def _homing(r: FieldReader, d: dict, p: str) -> DriveHoming | None:
    """An axis's `homing` table: drive homing (CiA 402 mode 6) before every program (hil/drive_homing.py)."""
    if "homing" not in d:
        return None
    h = r.table(d, "homing", p)
    method = r.integer(h, "method", f"{p}.method", None, choices=HOMING_METHODS)
    if method is None and not any(e.startswith(f"{p}.method") for e in r.errors):
        r.err(f"{p}.method", f"missing: a CiA 402 homing method ({', '.join(map(str, HOMING_METHODS))})")
    base = DriveHoming(0)
    out = DriveHoming(method or 0,
                      r.number(h, "position", f"{p}.position", base.position, minimum=-1e6, maximum=1e6) or 0.0,
                      r.number(h, "switch_rpm", f"{p}.switch_rpm", base.switch_rpm, positive=True, maximum=10000)
                      or base.switch_rpm,
                      r.number(h, "zero_rpm", f"{p}.zero_rpm", base.zero_rpm, positive=True, maximum=10000)
                      or base.zero_rpm,
                      r.integer(h, "accel_ms", f"{p}.accel_ms", base.accel_ms, positive=True, maximum=65500)
                      or base.accel_ms,
                      r.number(h, "timeout", f"{p}.timeout", base.timeout, positive=True, maximum=3600) or base.timeout)
    r.unknown(h, f"{p}.", {"method", "position", "switch_rpm", "zero_rpm", "accel_ms", "timeout"})
    return out if method is not None else None


def _spindle(r: FieldReader, d: dict, p: str) -> SpindleConfig | None:
    base = SpindleConfig()
    name = r.string(d, "name", f"{p}.name", "S1") or "S1"
    if not (name[0] == "S" and name[1:].isdigit()):
        r.err(f"{p}.name", f"must be S1, S2, ..., got {name!r}" + nc5(0x141A))
    cpr_given, model_named = "counts_per_rev" in d, isinstance(d.get("drive"), dict) and "model" in d["drive"]
    cpr = r.integer(d, "counts_per_rev", f"{p}.counts_per_rev", base.scaling.counts_per_rev, positive=True)
    ratio = r.pair(d, "ratio", f"{p}.ratio", integers=True, positive=True) or (1, 1)
    direction = r.integer(d, "direction", f"{p}.direction", 1, choices=(1, -1))
    max_rpm = r.number(d, "max_rpm", f"{p}.max_rpm", base.max_rpm, positive=True)
    given = _given(d)
    drive, model, esi, alias = _drive(r, d.pop("drive", {}), f"{p}.drive", base.drive)
    eds = r.eds(d, f"{p}.canopen_eds", ASDA_CSP_CSV)
    r.unknown(d, f"{p}.", {"name", "counts_per_rev", "ratio", "direction", "max_rpm", "drive", "canopen_eds"})
    scaling = AxisScaling(counts_per_rev=cpr or base.scaling.counts_per_rev, gear_motor=int(ratio[0]),
                          gear_load=int(ratio[1]), lead=360.0, direction=direction or 1)
    scaling = _for_model(scaling, model, cpr_given, model_named)
    drive = _drive_at_resolution(drive, given, scaling.counts_per_rev)
    return SpindleConfig(name, scaling, max_rpm or base.max_rpm, drive, canopen_eds=eds, drive_model=model,
                         drive_esi=esi, station_alias=alias)


def _realtime(r: FieldReader, d: dict) -> RealtimeConfig:
    base = RealtimeConfig()
    d = dict(d)
    rt = RealtimeConfig(
        priority=r.integer(d, "priority", "realtime.priority", base.priority, minimum=1, maximum=99) or base.priority,
        cpu=r.integer(d, "cpu", "realtime.cpu", None, minimum=0),
        busy_wait=(r.number(d, "busy_wait_us", "realtime.busy_wait_us", base.busy_wait * 1e6, minimum=0.0,
                            maximum=100_000.0) or 0.0) / 1e6,
        overrun=r.string(d, "overrun", "realtime.overrun", base.overrun, ("warn", "alarm")) or base.overrun,
        lock_memory=r.boolean(d, "lock_memory", "realtime.lock_memory", base.lock_memory),
        lockstep=r.string(d, "lockstep", "realtime.lockstep", base.lockstep, LOCKSTEP_PLACEMENTS) or base.lockstep)
    r.unknown(d, "realtime.", {"priority", "cpu", "busy_wait_us", "overrun", "lock_memory", "lockstep"})
    return rt


def _checks(r: FieldReader, d: dict, axes: tuple[str, ...]) -> ChecksConfig:
    d = dict(d)
    c = ChecksConfig()
    if "max_following_error" in d:
        v = d.pop("max_following_error")
        if isinstance(v, dict):
            for axis, lim in v.items():
                pth = f"checks.max_following_error.{axis}"
                if axis not in axes:
                    r.err(pth, f"no axis {axis!r} on this bench (axes: {', '.join(axes)})")
                elif isinstance(lim, bool) or not isinstance(lim, (int, float)) or lim <= 0:
                    r.err(pth, f"must be a positive number of mm, got {kind_of(lim)}")
                else:
                    c.max_following_error[axis] = float(lim)
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0:
            c.max_following_error = {a: float(v) for a in axes}
        else:
            r.err("checks.max_following_error", f"must be a positive number of mm or a table axis = mm, got {kind_of(v)}")
    c.contour_error = r.number(d, "contour_error", "checks.contour_error", None, positive=True)
    c.limits = r.boolean(d, "limits", "checks.limits", False)
    c.limit_tolerance = r.number(d, "limit_tolerance", "checks.limit_tolerance", c.limit_tolerance, minimum=0.0,
                                 maximum=1.0)
    c.thread_phase = r.number(d, "thread_phase", "checks.thread_phase", None, positive=True)
    for key in ("jitter_p99", "jitter_p999", "jitter_max"):
        us = r.number(d, f"{key}_us", f"checks.{key}_us", None, positive=True)
        setattr(c, key, us / 1e6 if us is not None else None)
    r.unknown(d, "checks.", {"max_following_error", "contour_error", "limits", "limit_tolerance", "thread_phase",
                             "jitter_p99_us", "jitter_p999_us", "jitter_max_us"})
    return c


_IO_KEYS = {"name", "inputs", "outputs", "x", "y", "canopen_node", "canopen_tpdo", "modules", "canopen_eds"}


def _io_modules(r: FieldReader, d: dict, p: str, points_max: int) -> tuple[str, ...] | None:
    """`modules`: an R1-EC station's modules in slot order (DI8/16/32, DO8/16/32); () when absent,
    None when the list is bad (errors recorded)."""
    from fieldbus.ethercat.r1ec_modules import MODULES, points

    if "modules" not in d:
        return ()
    raw = d.pop("modules")
    if not isinstance(raw, list) or not raw:
        r.err(f"{p}.modules", f"must be a non-empty list of module names like [\"DI16\", \"DO16\"], got {kind_of(raw)}")
        return None
    mods = []
    for i, m in enumerate(raw):
        name = m.strip().upper() if isinstance(m, str) else None
        if name not in MODULES:
            r.err(f"{p}.modules[{i}]", f"unknown module {m!r} (R1-EC modules: {', '.join(MODULES)})")
        else:
            mods.append(name)
    if len(mods) != len(raw):
        return None
    n_in, n_out = points(mods)
    if n_in > points_max or n_out > points_max:
        r.err(f"{p}.modules", f"{n_in} inputs / {n_out} outputs: a station has at most {points_max} of each")
        return None
    return tuple(mods)


def _io_stations(r: FieldReader, stations: Any, n_drives: int) -> list[IoStationConfig]:
    """[[io]]: remote I/O stations in EIO order (node 501, 502, …); see mlc/remote_io.py."""
    from mlc.remote_io import POINTS_MAX, STATIONS_MAX, IoMap, next_block, overlaps
    from mlc.memory import XY_SIZE

    if not isinstance(stations, list) or not all(isinstance(s, dict) for s in stations):
        r.err("io", f"must be an array of tables ([[io]]), got {kind_of(stations)}")
        return []
    if len(stations) > STATIONS_MAX:
        r.err("io", f"at most {STATIONS_MAX} stations (EIO nodes 501–520), got {len(stations)}")
        return []
    out: list[IoStationConfig] = []
    next_x = next_y = 0
    for k, raw in enumerate(stations):
        d, p = dict(raw), f"io[{k}]"
        name = r.string(d, "name", f"{p}.name", f"EIO-{501 + k}") or f"EIO-{501 + k}"
        if any(o.map.name == name for o in out):
            r.err(f"{p}.name", f"duplicate station name {name!r}")
        modules = _io_modules(r, d, p, POINTS_MAX)
        bad_modules, modules = modules is None, modules or ()
        if modules:  # the station's points are its modules' (inputs/outputs, if given too, must agree)
            from fieldbus.ethercat.r1ec_modules import points

            m_in, m_out = points(modules)
            for key, have in (("inputs", m_in), ("outputs", m_out)):
                given = d.get(key)
                if key in d and given != have:
                    r.err(f"{p}.{key}", f"{given!r}, but modules {' + '.join(modules)} have {have}")
                    d.pop(key)
            d.setdefault("inputs", m_in)
            d.setdefault("outputs", m_out)
        n_in = r.integer(d, "inputs", f"{p}.inputs", 16, minimum=0, maximum=POINTS_MAX)
        n_out = r.integer(d, "outputs", f"{p}.outputs", 16, minimum=0, maximum=POINTS_MAX)
        n_in, n_out = 16 if n_in is None else n_in, 16 if n_out is None else n_out
        if n_in == 0 and n_out == 0:
            r.err(p, "a station needs at least one input or output point")
        x = r.integer(d, "x", f"{p}.x", next_x, minimum=0, maximum=XY_SIZE - 1)
        y = r.integer(d, "y", f"{p}.y", next_y, minimum=0, maximum=XY_SIZE - 1)
        x, y = next_x if x is None else x, next_y if y is None else y
        node = r.integer(d, "canopen_node", f"{p}.canopen_node", 64 + k, minimum=1, maximum=127) or 64 + k
        if node <= n_drives:
            r.err(f"{p}.canopen_node", f"{node} is taken by a drive (drives are CANopen nodes 1–{n_drives})" + nc5(0x1417))
        elif any(o.canopen_node == node for o in out):
            r.err(f"{p}.canopen_node", f"duplicate CANopen node {node}" + nc5(0x1417))
        tpdo = r.string(d, "canopen_tpdo", f"{p}.canopen_tpdo", "sync", ("sync", "change")) or "sync"
        eds = r.eds(d, f"{p}.canopen_eds", io=(n_in, n_out))
        r.unknown(d, f"{p}.", _IO_KEYS)
        if not bad_modules:  # a bad module list leaves the station's X/Y span unknown: no range errors for it
            out.append(IoStationConfig(IoMap(name, n_in, n_out, x, y, k), node, tpdo, modules, canopen_eds=eds))
        next_x, next_y = next_block(max(next_x, x + n_in)), next_block(max(next_y, y + n_out))
    for msg in overlaps([o.map for o in out]):
        r.err("io", msg)
    return out
