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
    "_lam",)
COUNTS = (
    "_buf_i", "_buf_popped", "_pushes", "_pushed", "_need", "threads_queued", "solves", "_started", "held",
    "_stopping", "dry_run", "_closed", "_filling", "_integrate_angle",)
CORE = frozenset(DOUBLES + COUNTS + (
    "plan", "blocks", "lim", "cfg", "axes", "position", "output", "_buf_pos", "_buf_vel", "_buf_line", "_buf_state",
    "_buf_blk", "_buf_carry", "_zones", "filter", "_fs_tail", "_fr_plan", "_cont", "_runs", "_held", "line", "depth",
    "_batch", "_seg_hist", "_axis_v",))


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

    def _fields(self) -> dict:
        return {"s": self.s, "v": self.v, "a": self.a, "_carry": self._carry, "_path_s": self._path_s,
                "_jf": self._jf, "_end_cap": self._end_cap, "_feed_ovr": self._feed_ovr,
                "_rapid_ovr": self._rapid_ovr, "dry_run_feed": self.dry_run_feed, "_t_step": self._t_step,
                "_lam": self._lam, "_buf_i": self._buf_i, "_buf_popped": self._buf_popped, "_pushes": self._pushes,
                "_pushed": self._pushed, "_need": self._need, "threads_queued": self.threads_queued,
                "solves": self.solves, "_started": self._started, "held": self.held, "_stopping": self._stopping,
                "dry_run": self.dry_run, "_closed": self._closed, "_filling": self._filling,
                "_integrate_angle": self._integrate_angle, "plan": self.plan, "blocks": self.blocks, "lim": self.lim,
                "cfg": self.cfg, "axes": self.axes, "position": self.position, "output": self.output,
                "_buf_pos": self._buf_pos, "_buf_vel": self._buf_vel, "_buf_line": self._buf_line,
                "_buf_state": self._buf_state, "_buf_blk": self._buf_blk, "_buf_carry": self._buf_carry,
                "_zones": self._zones, "filter": self.filter, "_fs_tail": self._fs_tail, "_fr_plan": self._fr_plan,
                "_cont": self._cont, "_runs": self._runs, "_held": self._held, "line": self.line,
                "depth": self.depth, "_batch": self._batch, "_seg_hist": self._seg_hist, "_axis_v": self._axis_v}

    def _set_fields(self, d: dict) -> None:
        self.s = d["s"]
        self.v = d["v"]
        self.a = d["a"]
        self._carry = d["_carry"]
        self._path_s = d["_path_s"]
        self._jf = d["_jf"]
        self._end_cap = d["_end_cap"]
        self._feed_ovr = d["_feed_ovr"]
        self._rapid_ovr = d["_rapid_ovr"]
        self.dry_run_feed = d["dry_run_feed"]
        self._t_step = d["_t_step"]
        self._lam = d["_lam"]
        self._buf_i = d["_buf_i"]
        self._buf_popped = d["_buf_popped"]
        self._pushes = d["_pushes"]
        self._pushed = d["_pushed"]
        self._need = d["_need"]
        self.threads_queued = d["threads_queued"]
        self.solves = d["solves"]
        self._started = d["_started"]
        self.held = d["held"]
        self._stopping = d["_stopping"]
        self.dry_run = d["dry_run"]
        self._closed = d["_closed"]
        self._filling = d["_filling"]
        self._integrate_angle = d["_integrate_angle"]
        self.plan = d["plan"]
        self.blocks = d["blocks"]
        self.lim = d["lim"]
        self.cfg = d["cfg"]
        self.axes = d["axes"]
        self.position = d["position"]
        self.output = d["output"]
        self._buf_pos = d["_buf_pos"]
        self._buf_vel = d["_buf_vel"]
        self._buf_line = d["_buf_line"]
        self._buf_state = d["_buf_state"]
        self._buf_blk = d["_buf_blk"]
        self._buf_carry = d["_buf_carry"]
        self._zones = d["_zones"]
        self.filter = d["filter"]
        self._fs_tail = d["_fs_tail"]
        self._fr_plan = d["_fr_plan"]
        self._cont = d["_cont"]
        self._runs = d["_runs"]
        self._held = d["_held"]
        self.line = d["line"]
        self.depth = d["depth"]
        self._batch = d["_batch"]
        self._seg_hist = d["_seg_hist"]
        self._axis_v = d["_axis_v"]

    def state(self) -> dict:
        """Every field of the planner (a shallow copy: the objects themselves), the C fields included."""
        d = dict(self.__dict__)
        d.update(self._fields())
        return d

    def restore(self, d: dict) -> None:
        """The planner's fields as `state()` gave them: the others dropped (a field set since goes away)."""
        own = self.__dict__
        own.clear()
        for k, v in d.items():
            if k not in CORE:
                own[k] = v
        self._set_fields(d)

    def update_state(self, d: dict) -> None:
        """The fields in `d` (some of `state()`'s) set, the others kept."""
        own = self.__dict__
        core = False
        for k, v in d.items():
            if k in CORE:
                core = True
            else:
                own[k] = v
        if core:
            for k in CORE.intersection(d):
                setattr(self, k, d[k])

    def same_state(self, before: dict) -> bool:
        """Each field is what `before` (a `state()`) holds and no field came or went: the very objects for the
        Python fields; a C field's number the same (`_same`: a C field is boxed afresh at each read)."""
        own = self.__dict__
        if len(own) + sum(1 for k in CORE if k not in own) != len(before):
            return False
        for k, v in before.items():
            if k in CORE:
                if not _same(getattr(self, k), v):
                    return False
            elif own.get(k, own) is not v:
                return False
        return True
