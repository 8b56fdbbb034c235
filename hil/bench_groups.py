"""`[param_groups.N]` of a bench file: the G05 parameter groups ("recipes" 1-20, N§3.8.2; decision language L25-1).

A group names the parameters it switches as `[params]` spells them, and the axis limits as `[[axes]]` does:

    [param_groups.1]
    "N1.036" = 8.0                          # look-ahead filter time, ms
    limits.X = { acceleration = 2000.0 }    # an axis limit, at most the axis's own

What a group leaves out keeps the bench's value. Every problem is a bench error naming the key: a group number
outside 1-20, a parameter G05 does not switch (N§3.8.2's list), one G05 switches that this bench does not model,
a value out of its range, an axis limit above the axis's own.
"""

from __future__ import annotations

from typing import Any

from hil.bench import LIMIT_BOUNDS, LIMIT_FIELDS, AxisConfig, ParamGroup
from hil.bench_params import check_param, check_together, param_spec
from hil.toml_fields import FieldReader, kind_of

GROUPS = range(1, 21)  # G05 P1-P20
# N§3.8.2 "Supported parameters": channel and axis parameters a group may hold on an NC5.
G05_CHANNEL = frozenset([*(f"N1.{n:03d}" for n in range(30, 40)), "N1.041", *(f"N1.{n:03d}" for n in range(50, 55)),
                         *(f"N1.{n:03d}" for n in range(96, 100))])
G05_AXIS = frozenset([*(f"N2.{n:03d}" for n in range(20, 28)), "N2.029"])
# Those the bench's motion model has: the planner's settings (hil.bench.Bench.motion_config); the axis ones
# spelt with their axis, "N2.020 X" (decision language L26-1).
MODELLED = ("N1.030", "N1.031", "N1.032", "N1.033", "N1.034", "N1.035", "N1.036", "N1.037", "N1.053")
MODELLED_AXIS = ("N2.020", "N2.021", "N2.022")
# What the bench has instead of an NC5 parameter it does not model, for the message.
INSTEAD = {"N2.023": "limits.<axis>.velocity", "N2.024": "limits.<axis>.acceleration",
           "N2.025": "limits.<axis>.jerk"}
LISTED = "N1.030-N1.039, N1.041, N1.050-N1.054, N1.096-N1.099, N2.020-N2.027, N2.029"


def parse_groups(r: FieldReader, raw: Any, axes: list[AxisConfig],
                 params: dict[str, float] | None = None) -> dict[int, ParamGroup]:
    """The bench file's `param_groups` table (popped by the caller) as groups by number; errors go to `r`.
    `params`: the bench's `[params]`, which a group's values stand over (an acc. and dec. time needs its speed
    from either, decision language L26-1)."""
    if not isinstance(raw, dict):
        r.err("param_groups", f"must be a table of groups ([param_groups.1] ... [param_groups.20]), got {kind_of(raw)}")
        return {}
    out: dict[int, ParamGroup] = {}
    for key, body in raw.items():
        p = f"param_groups.{key}"
        n = int(key) if key.isdigit() else None
        if n is None or n not in GROUPS:
            zero = " (G05 P0 returns to the bench's own settings: they are [params] and [[axes]] limits)" \
                if n == 0 else ""
            r.err(p, f"a parameter group is numbered 1-20 (G05 P1-P20, N§3.8.2), got {key!r}{zero}")
            continue
        if not isinstance(body, dict):
            r.err(p, f"must be a table of parameters, got {kind_of(body)}")
            continue
        out[n] = _group(r, dict(body), p, axes)
        _check_over(r, out[n], p, axes, params or {})
    return out


def _check_over(r: FieldReader, g: ParamGroup, p: str, axes: list[AxisConfig], params: dict[str, float]) -> None:
    """What the group's values make of the bench's [params] (an N1.031 without N1.030 in either) that the bench's
    own did not already: the group's key, or the bench's parameter it leaves without its speed."""
    names = tuple(a.name for a in axes)
    known = {k for k, _ in check_together(params, names)}
    for k, problem in check_together({**params, **g.params}, names):
        if k in g.params:
            r.err(f"{p}.{k!r}" if " " in k else f"{p}.{k}", problem)
        elif k not in known:
            r.err(p, f"[params] {k} under this group: {problem}")


def _group(r: FieldReader, d: dict, p: str, axes: list[AxisConfig]) -> ParamGroup:
    g = ParamGroup()
    limits = d.pop("limits", {})
    for k, v in d.items():
        where = f"{p}.{k!r}" if " " in k else f"{p}.{k}"
        problem = _not_switched(k)
        if problem is None and (isinstance(v, bool) or not isinstance(v, (int, float))):
            problem = f"must be a number, got {kind_of(v)}"
        if problem is None:
            problem = check_param(k, v)
        if problem is not None:
            r.err(where, problem)
        else:
            g.params[k] = float(v)
    if not isinstance(limits, dict):
        r.err(f"{p}.limits", f"must be a table of axes (limits.X = {{ acceleration = ... }}), got {kind_of(limits)}")
        return g
    by_name = {a.name: a for a in axes}
    for name, lim in limits.items():
        lp = f"{p}.limits.{name}"
        ax = by_name.get(name)
        if ax is None:
            r.err(lp, f"no axis {name!r} on this bench (axes: {', '.join(by_name)})")
        elif not isinstance(lim, dict):
            r.err(lp, f"must be a table {{ velocity, acceleration, jerk }}, got {kind_of(lim)}")
        else:
            g.limits[name] = _axis_limits(r, dict(lim), lp, ax)
    return g


def _not_switched(k: str) -> str | None:
    """Why `k` cannot be in a group (None: it can)."""
    base = k.split(" ")[0]
    if k in MODELLED:
        return None
    if base in MODELLED_AXIS:  # its axis is checked by check_param and _check_over
        return None if k != base else check_param(k, 0.0)
    if base in G05_CHANNEL or base in G05_AXIS:
        instead = f"; set {INSTEAD[base]} in the group instead" if base in INSTEAD else ""
        return (f"G05 switches {base} on an NC5 (N§3.8.2), but this bench does not model it: a group sets "
                f"{', '.join(MODELLED)}, {', '.join(a + ' <axis>' for a in MODELLED_AXIS)} and "
                f"limits.<axis> {{ velocity, acceleration, jerk }}{instead}")
    if param_spec(k) is not None:
        return f"G05 does not switch {k} (N§3.8.2 lists {LISTED}); set it in [params]"
    return check_param(k, 0.0)  # unknown: its message, with the closest name


def _axis_limits(r: FieldReader, d: dict, p: str, ax: AxisConfig) -> dict[str, float]:
    out: dict[str, float] = {}
    for k, attr in LIMIT_FIELDS.items():
        v = r.number(d, k, f"{p}.{k}", None, positive=True, minimum=LIMIT_BOUNDS[k][0], maximum=LIMIT_BOUNDS[k][1])
        if v is None:
            continue
        own = getattr(ax.limits, attr)
        if v > own:
            # The axis's limits are the machine's: `[checks] limits` judges every setpoint by them.
            r.err(f"{p}.{k}", f"{v:g} is above the axis's own limit {own:g}: a group may lower an axis limit, "
                              "not raise it")
        else:
            out[k] = v
    r.unknown(d, f"{p}.", set(LIMIT_FIELDS))
    return out
