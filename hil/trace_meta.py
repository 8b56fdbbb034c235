"""What a trace says about itself: the unit of every column and the run's provenance (program,
bench name, file and limits, cycle, deltahil version), stored in a Parquet trace's metadata so
`hil check`, `hil report`, notebooks and other tools need not be told which bench it came from."""

from __future__ import annotations

import datetime as _dt
from collections.abc import Sequence
from typing import Any

from hil.bench import Bench
from hil.version import version

# column suffix → unit (a rotary axis's positions are degrees: see column_units)
_SUFFIX_UNITS = (("_rpm_cmd", "rpm"), ("_rpm_act", "rpm"), ("_angle", "deg"), ("_cmd", "mm"), ("_act", "mm"),
                 ("_vel", "mm/s"), ("_torque", "% rated torque"), ("_ferr", "mm"), ("_sw", "CiA 402 statusword"))
_FIXED = {"t": "s", "period": "s", "late": "s", "line": "program line", "cycle": "bench cycle",
          "alarm": "Delta alarm code", "event": "--at action"}


def column_units(columns: Sequence[str], bench: Bench | None = None) -> dict[str, str]:
    rotary = {a.name for a in bench.axes if a.units == "deg"} if bench is not None else set()
    out: dict[str, str] = {}
    for c in columns:
        if c in _FIXED:
            out[c] = _FIXED[c]
            continue
        for suffix, unit in _SUFFIX_UNITS:
            if c.endswith(suffix):
                name = c[: -len(suffix)]
                if name in rotary and unit.startswith("mm"):
                    unit = "deg" + unit[2:]
                out[c] = unit
                break
    return out


def run_meta(bench: Bench, program: str) -> dict[str, Any]:
    return {
        "program": program, "deltahil_version": version(),
        "written": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "bench": {"name": bench.name, "source": bench.source, "profile": bench.profile, "bus": bench.bus,
                  "cycle_s": bench.cycle,
                  "axes": {a.name: {"units": a.units, "velocity": a.limits.max_velocity,
                                    "acceleration": a.limits.max_acceleration, "jerk": a.limits.max_jerk}
                           for a in bench.axes},
                  "spindles": {s.name: {"max_rpm": s.max_rpm} for s in bench.spindles}},
    }
