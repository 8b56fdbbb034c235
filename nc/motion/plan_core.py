"""The planner's hot fields as C fields (issue 17, session 30, decision bench B172): `PlanCore` is the base of
`nc.motion.planner.Planner`, an extension type where compiled (plan_core.pxd: `double` for the fields that are
always floats, `Py_ssize_t`/`bint` for counts and flags, `object` otherwise), so the compiled planner reads
`self.s` as a struct field (≈ 2 instructions) instead of a generic attribute look-up (≈ 200). Run as Python it is
a plain class and every field lives in the instance's `__dict__`, as before.

The C fields are not in `__dict__`: whoever saves and restores the planner (hil/stretch_state.py,
hil/stretch_realtime.py, hil/stretch_pass.py) does it through `state()`, `restore()`, `update_state()` and
`same_state()`, which hold every field, the C ones included. A field a test monkeypatches on the class
(`Planner.per_block`, `Planner.push`) is not one of them: it stays a Python attribute.
"""

from __future__ import annotations

import math

try:
    import cython  # compiled: plan_core.pxd types the class (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython
    from nc.motion import cython_shadow as cython

# The C fields (plan_core.pxd declares each; `_fields` and `_set_fields` below spell out the same names)
DOUBLES = (
    "s", "v", "a", "_carry", "_path_s", "_jf", "_end_cap", "_feed_ovr", "_rapid_ovr", "dry_run_feed", "_t_step",
    "_lam")
COUNTS = (
    "_buf_i", "_buf_popped", "_pushes", "_pushed", "_need", "threads_queued", "solves", "_started", "held",
    "_stopping", "dry_run", "_closed", "_filling", "_integrate_angle")
OBJECTS = (
    "plan", "blocks", "lim", "cfg", "axes", "position", "output", "_buf_pos", "_buf_vel", "_buf_line", "_buf_state",
    "_buf_blk", "_buf_carry", "_zones", "filter", "_fs_tail", "_fr_plan", "_cont", "_runs", "_held", "line", "depth",
    "_batch", "_seg_hist", "_axis_v")
FIELDS = DOUBLES + COUNTS + OBJECTS  # `_fields`' order
CORE = frozenset(FIELDS)
KEY = "(C fields)"  # a state's entry of the C fields' values (no attribute has this name)


def _same(x: object, y: object) -> bool:
    """The same field: the very object, or (a C field, boxed afresh at each read) the same int, or the same float
    to the bit (-0.0 is not 0.0; NaN is never the same)."""
    if x is y:
        return True
    t = type(x)
    if t is not type(y):
        return False
    if t is int:
        return x == y
    return t is float and x == y and math.copysign(1.0, x) == math.copysign(1.0, y)


class PlanCore:
    """The planner's fields that its compiled methods read every cycle or block (plan_core.pxd), and the planner's
    state API over all of its fields (its `__dict__` and the C fields)."""

    def _fields(self) -> tuple:
        """The C fields' values in FIELDS' order (a tuple: a dict entry per field cost ≈ 5k instructions a save)."""
        return (self.s, self.v, self.a, self._carry, self._path_s, self._jf, self._end_cap, self._feed_ovr,
                self._rapid_ovr, self.dry_run_feed, self._t_step, self._lam, self._buf_i, self._buf_popped,
                self._pushes, self._pushed, self._need, self.threads_queued, self.solves, self._started, self.held,
                self._stopping, self.dry_run, self._closed, self._filling, self._integrate_angle, self.plan,
                self.blocks, self.lim, self.cfg, self.axes, self.position, self.output, self._buf_pos, self._buf_vel,
                self._buf_line, self._buf_state, self._buf_blk, self._buf_carry, self._zones, self.filter,
                self._fs_tail, self._fr_plan, self._cont, self._runs, self._held, self.line, self.depth, self._batch,
                self._seg_hist, self._axis_v)

    def _set_fields(self, t: tuple) -> None:
        (self.s, self.v, self.a, self._carry, self._path_s, self._jf, self._end_cap, self._feed_ovr, self._rapid_ovr,
         self.dry_run_feed, self._t_step, self._lam, self._buf_i, self._buf_popped, self._pushes, self._pushed,
         self._need, self.threads_queued, self.solves, self._started, self.held, self._stopping, self.dry_run,
         self._closed, self._filling, self._integrate_angle, self.plan, self.blocks, self.lim, self.cfg, self.axes,
         self.position, self.output, self._buf_pos, self._buf_vel, self._buf_line, self._buf_state, self._buf_blk,
         self._buf_carry, self._zones, self.filter, self._fs_tail, self._fr_plan, self._cont, self._runs, self._held,
         self.line, self.depth, self._batch, self._seg_hist, self._axis_v) = t

    def state(self) -> dict:
        """Every field of the planner (a shallow copy: the objects themselves): its `__dict__`'s, and the C fields'
        values as one tuple under KEY (`state_fields` names them)."""
        d = dict(self.__dict__)
        d[KEY] = self._fields()
        return d

    def restore(self, d: dict) -> None:
        """The planner's fields as `state()` gave them: the others dropped (a field set since goes away)."""
        own = self.__dict__
        own.clear()
        own.update(d)  # (run as Python the C fields' names are among them, with the same values as under KEY)
        del own[KEY]
        self._set_fields(d[KEY])

    def update_state(self, d: dict) -> None:
        """The fields in `d` set (a `state()`, or some fields by name), the others kept."""
        own = self.__dict__
        for k, v in d.items():
            if k == KEY:
                self._set_fields(v)
            elif k in CORE:
                setattr(self, k, v)
            else:
                own[k] = v

    def same_state(self, before: dict) -> bool:
        """Each field is what `before` (a `state()`) holds and no field came or went: the very objects in
        `__dict__`; a C field the same number (`_same`: it is boxed afresh at each read)."""
        own = self.__dict__
        if len(own) + 1 != len(before):
            return False
        for k, v in before.items():
            if k != KEY and own.get(k, own) is not v:
                return False
        return all(map(_same, self._fields(), before[KEY]))


_AT = {name: k for k, name in enumerate(FIELDS)}


def state_field(d: dict, name: str) -> object:
    """One field of a `state()` by its name (hil/stretch.py reads the saved position)."""
    k = _AT.get(name)
    return d[name] if k is None else d[KEY][k]


def state_fields(d: dict) -> dict:
    """A `state()` with every field by its name (for tests and reading)."""
    out = {k: v for k, v in d.items() if k != KEY}
    out.update(zip(FIELDS, d[KEY]))
    return out
