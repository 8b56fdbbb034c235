"""The `[params]` names a bench file may set, with each one's documented range.

Names are the NC5 manual's (App. B / ch. 1-3: N1.040, N2.001 Bit10 ...) plus the emulator's own guards
(decisions inputs.md I1-I3). A name outside this table is a typo as far as a bench is concerned: the
interpreter would silently read its default instead, which is the worst kind of wrong.
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class ParamSpec:
    minimum: float
    maximum: float
    integer: bool = False
    what: str = ""


_BIT = ParamSpec(0, 1, True, "bit switch")
ACC_MS, SCURVE_MS = 10_000.0, 1000.0  # acc. and dec. times and S-curve times (decision language L26-1)
_CODE = ParamSpec(0, 9999, True, "code number")
_ONUM = ParamSpec(0, 9999, True, "program number")

PARAMS: dict[str, ParamSpec] = {
    "N8.018 Bit10": _BIT, "N1.11 Bit4": _BIT, "N2.001 Bit10": _BIT, "N1.010 Bit22": _BIT,
    "N1.010 Bit28": _BIT, "N8.22 Bit5": _BIT, "M2x010": _BIT,
    "N1.010": ParamSpec(0, 1, True, "G43/G44/G49 without Z: 0 move, 1 internal only"),
    "N0.1025": ParamSpec(0, 600000, False, "ms, 1st spindle positioning check time (0x0C01), 0 off"),
    "N0.1000 Bit7": _BIT, "N0.1008": ParamSpec(0, 600000, False, "rpm, 1st spindle maximum speed (0x0C03)"),
    "N1.08": ParamSpec(0, 2, True, "lathe type A/B/C"),
    "P306": ParamSpec(0, 2, True, "lathe type A/B/C (lathe-2018)"),
    "N1.027": ParamSpec(0, 1e6, False, "mm/min"),
    "N1.033": ParamSpec(0, 1e6, False, "mm/min, cutting command maximum feed, 0: none"),
    # G00 and cutting acceleration (decision language L26-1; the manual gives no units or ranges): 0: none
    "N1.030": ParamSpec(0, 1e6, False, "mm/min, G00 rapid command maximum speed, 0: none"),
    "N1.031": ParamSpec(0, ACC_MS, False, "ms from rest to N1.030, 0: none"),
    "N1.032": ParamSpec(0, SCURVE_MS, False, "ms, G00 rapid command S curve time, 0: none"),
    "N1.034": ParamSpec(0, ACC_MS, False, "ms from rest to N1.033, 0: none"),
    "N1.035": ParamSpec(0, SCURVE_MS, False, "ms, cutting command S curve time, 0: none"),
    "N1.036": ParamSpec(0, 1000, False, "ms"), "N1.037": ParamSpec(0, 1000, False, "ms"),
    "N1.040": ParamSpec(0, 10, False, "mm"), "N1.042": ParamSpec(0, 1e6, False, "mm/min"),
    "N1.053": ParamSpec(0, 10, False, "mm"),
    "N1.118": _CODE, "N1.119": ParamSpec(0, 100, True), "N1.120": _CODE, "N1.121": _ONUM,
    "N1.122": ParamSpec(0, 100, True), "N1.123": _CODE, "N1.124": _ONUM, "N1.125": ParamSpec(0, 100, True),
    "N1.150": ParamSpec(0, 15, True, "cycle mode bits"), "N1.151": ParamSpec(0, 1000, False, "mm"),
    "P348": ParamSpec(0, 1000, False, "mm"), "P405": ParamSpec(-360, 360, False, "deg"),
    # The emulator's guards: 0 or a huge value would switch the endless-loop stop off (I2).
    "max blocks": ParamSpec(1, 100_000_000, True, "endless-loop guard"),
    "M99 main restarts": ParamSpec(0, 1_000_000, True, "endless-loop guard"),
    "preview depth": ParamSpec(1, 1000, True), "preview log": ParamSpec(-1, 1_000_000, True, "-1: all"),
    "macro statements per cycle": ParamSpec(1, 100_000, True, "endless-loop guard"),
    "servo param alarm": _BIT,
    # EtherCAT master (docs/decisions ethercat.md E8, E12)
    "ethercat_drift_limit_ns": ParamSpec(0, 1e9, True, "ns, 0: record only"),
    "ethercat_drift_check_every": ParamSpec(0, 1e6, True, "cycles"),
    "ethercat_complete_access": ParamSpec(0, 1, True, "1: map with complete access first"),
}
# Call tables: N1.200-N1.249 (G -> O9100+), N1.250-N1.299 (M -> O9150+), legacy O9010-O9029.
PARAMS.update({f"N1.{n}": _CODE for n in range(200, 300)})
PARAMS.update({f"O{n}": _CODE for n in range(9010, 9030)})
_SOFT = re.compile(r"soft limit ([1-9]\d?) ([A-Z])")  # G10 L21 values a bench may preset
_SOFT_SPEC = ParamSpec(-1e6, 1e6, False, "mm")
# An axis's G00 rapid parameters, "N2.020 X" (decision language L26-1); the axis must be on the bench.
AXIS_RAPID = re.compile(r"(N2\.02[012]) ([A-Z])")
_AXIS_RAPID_SPECS = {
    "N2.020": ParamSpec(0, 1e6, False, "mm/min (deg/min), axis G00 rapid command maximum speed, 0: none"),
    "N2.021": ParamSpec(0, ACC_MS, False, "ms from rest to the axis's N2.020, 0: none"),
    "N2.022": ParamSpec(0, SCURVE_MS, False, "ms, axis G00 rapid command S curve time, 0: none"),
}
# An acceleration time is relative to its maximum speed (acceleration = speed / time): the time needs it.
NEEDS = {"N1.031": "N1.030", "N1.034": "N1.033", "N2.021": "N2.020"}


def param_spec(name: str) -> ParamSpec | None:
    if _SOFT.fullmatch(name):
        return _SOFT_SPEC
    if (m := AXIS_RAPID.fullmatch(name)) is not None:
        return _AXIS_RAPID_SPECS[m.group(1)]
    return PARAMS.get(name)


def check_together(params: dict[str, float], axes: tuple[str, ...]) -> list[tuple[str, str]]:
    """(key, message) for each parameter that cannot stand with the others: an axis parameter of an axis the
    bench lacks, an acc. and dec. time > 0 without the maximum speed it is relative to (decision language L26-1)."""
    out = []
    for k, v in params.items():
        m = AXIS_RAPID.fullmatch(k)
        base, axis = (m.group(1), m.group(2)) if m else (k, "")
        if m and axis not in axes:
            out.append((k, f"no axis {axis!r} on this bench (axes: {', '.join(axes)})"))
            continue
        need = NEEDS.get(base)
        if need is None or not v:
            continue
        ref = f"{need} {axis}" if axis else need
        if not params.get(ref):
            out.append((k, f"needs {ref} > 0: the acceleration is {ref} / {base}; set {ref} or leave {base} out"))
    return out


def check_param(name: str, value: object) -> str | None:
    """None when `name = value` is acceptable, else the message for the bench error."""
    spec = param_spec(name)
    if spec is None and name in _AXIS_RAPID_SPECS:
        return f'an axis parameter: name the axis, "{name} X" (decision language L26-1)'
    if spec is None:
        # "N1.O40" is N1.040 typed with the letter O: read O as zero after the group dot first.
        zeroed = name[:3] + name[3:].replace("O", "0").replace("o", "0")
        close = [zeroed] if zeroed in PARAMS else difflib.get_close_matches(name, list(PARAMS), n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]}?)" if close else ""
        return f"unknown parameter{hint}; see docs/guide/bench-file.md for the parameter table"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"must be a number, got {type(value).__name__}"
    v = float(value)
    if v != v or v in (float("inf"), float("-inf")):
        return f"must be a finite number, got {v}"
    if not spec.minimum <= v <= spec.maximum:
        what = f" ({spec.what})" if spec.what else ""
        return f"must be within [{spec.minimum:g}, {spec.maximum:g}]{what}, got {v:g}"
    if spec.integer and v != int(v):
        return f"must be an integer, got {v:g}"
    return None
