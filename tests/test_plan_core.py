"""The planner's state API (nc.motion.plan_core, decision bench B172): where compiled, the planner's hot fields are
C fields of its extension-type base and not in its `__dict__`, so the stretch runner saves and restores it through
`state()`/`restore()`/`update_state()`/`same_state()`. A restore must give back every field, the C ones included,
and the planner must then step exactly as it did from the saved state."""

from __future__ import annotations

import numpy as np

from hil.stretch_pass import _save
from hil.stretch_state import _restore_planner
from nc.motion.plan_core import CORE, FIELDS, state_field, state_fields
from nc.motion.planner import Planner
from tests.motion_helpers import AX, lines, mill_cfg


def _planner() -> Planner:
    pl = Planner(mill_cfg(filter_time=0.016, filter_scurve=0.016), dict(zip(AX, (0.0, 0.0, 0.0))))
    rng = np.random.default_rng(7)
    pts = np.cumsum(rng.uniform(-8, 12, (30, 3)) * [1, 1, 0.2], axis=0)
    for mv in lines([(0.0, 0.0, 0.0), *map(tuple, pts)], 3000.0):
        pl.push(mv)
    for _ in range(150):  # under way: a plan running, blocks finished, counters and speeds not at their start
        pl.step()
    return pl


def _steps(pl: Planner, n: int) -> list:
    return [(sp.positions.tolist(), sp.line, sp.path_velocity) for sp in (pl.step() for _ in range(n))]


def _equal(x: object, y: object) -> bool:
    """The very object, or (a C field is boxed afresh at each read) the same number."""
    return x is y or (type(x) is type(y) and type(x) in (int, float, bool) and x == y)


def test_restore_gives_back_every_field_and_the_same_setpoints():
    pl = _planner()
    whole = _save(pl)  # hil/stretch_pass.py's save: the planner's state(), its queue, its plan's fields, its filter
    saved = whole["pl"]
    before = state_fields(saved)
    assert CORE <= before.keys()  # the C fields are in a state, by name
    assert before["s"] == pl.s and before["_pushes"] == 30 and before["blocks"] is pl.blocks
    assert state_field(saved, "v") == pl.v and state_field(saved, "spindle_rpm") is pl.spindle_rpm
    first = _steps(pl, 200)  # blocks finished, new plans: s, v, a, the buffer, the counters all move
    after = state_fields(pl.state())
    assert not pl.same_state(saved)
    moved = [k for k in FIELDS if not _equal(after[k], before[k])]
    assert {"s", "_buf_i", "solves", "plan"} <= set(moved), moved
    _restore_planner(pl, whole)  # as the stretch pass does: pl.restore(saved), and the queue, plan and filter
    got = state_fields(pl.state())
    assert got.keys() == before.keys()
    assert all(_equal(got[k], v) for k, v in before.items()), [k for k, v in before.items() if not _equal(got[k], v)]
    assert pl.same_state(saved)
    assert _steps(pl, 200) == first


def test_update_state_sets_the_named_fields_and_keeps_the_others():
    pl = _planner()
    saved = pl.state()
    rpm = pl.spindle_rpm
    pl.update_state({"s": 0.25, "_buf_i": 3, "spindle_rpm": None})
    assert pl.s == 0.25 and pl._buf_i == 3 and pl.spindle_rpm is None
    assert not pl.same_state(saved)
    pl.update_state({"s": state_field(saved, "s"), "_buf_i": state_field(saved, "_buf_i"), "spindle_rpm": rpm})
    assert pl.same_state(saved)
    pl.extra = 1  # a field that came since: not the same state, and a restore drops it
    assert not pl.same_state(saved)
    pl.restore(saved)
    assert not hasattr(pl, "extra") and pl.same_state(saved)


def test_every_c_field_is_saved_in_its_place():
    """plan_core.pxd, FIELDS and `_fields`/`_set_fields` name the same fields in the same order: a field declared in
    the .pxd but missing from the state API would not be saved (a stretch's restore would leave it as the stretch
    left it), and two names swapped would restore one field's value into the other."""
    import re
    from pathlib import Path

    import nc.motion.plan_core as pc
    declared = re.findall(r"^\s+cdef public \w+ (\w+)\s*$", (Path(pc.__file__).parent / "plan_core.pxd").read_text(),
                          re.M)
    assert declared == list(FIELDS)
    pl = _planner()
    # each field a distinct value of its own type (the C types: double, count, flag, object)
    values = tuple(float(k) + 0.5 if k < len(pc.DOUBLES) else
                   (k if name not in ("_started", "held", "_stopping", "dry_run", "_closed", "_filling",
                                       "_integrate_angle") else bool(k % 2)) if k < len(pc.DOUBLES) + len(pc.COUNTS)
                   else object() for k, name in enumerate(FIELDS))
    pl._set_fields(values)
    got = {name: getattr(pl, name) for name in FIELDS}
    assert all(_equal(got[name], v) for name, v in zip(FIELDS, values))
    assert all(_equal(a, b) for a, b in zip(pl._fields(), values))
