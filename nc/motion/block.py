"""The look-ahead's block: one queued move with its limits, junction speeds and the filter corners' per-junction
sums (nc.motion.lookahead, nc.motion.blending, nc.motion.shares read and write its fields).

Its own module so that nc/motion/block.pxd can make it a C struct where setup.py compiles the planner's hot
modules with Cython (issue 17, decision bench B115): the fields of a compiled class are read without a
dictionary lookup. As Python it is the same dataclass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

from nc.motion.path import Segment
from nc.moves import Move


@dataclass  # no slots=True: Cython's dataclass does not take it (compiled, the fields are a struct anyway)
class Block:
    move: Move
    kind: str  # "path" (line/arc/interpolated rapid), "indep" (independent rapid), "dwell", "thread"
    seg: Segment | None
    length: float
    cap_hard: float  # geometric cap: axis speeds, centripetal limits, minimum duration (mm/s)
    a: float  # tangential path acceleration limit (mm/s²)
    j: float  # tangential path jerk limit (mm/s³)
    feed: float | None  # programmed feed in mm/s (mm/rev when per_rev); None for rapids
    rapid: bool = False
    cap: float = 0.0  # effective cap with feed, override and spindle speed applied
    vjunc: float = 0.0  # speed allowed at the junction to the next block
    vend: float = 0.0  # planned end speed after the backward pass
    anchor_v: float = 0.0  # nearest binding speed downstream of this block's end ...
    anchor_d: float = 0.0  # ... and the path length to it
    anchor_a: float = 0.0  # least tangential acceleration and jerk over that stretch
    anchor_j: float = 0.0
    binding: bool = True  # vend is this junction's own limit, not a downstream one
    # Post-interpolation filter corners (nc.motion.blending): path length at this block's end,
    # |Δu| per axis and its norm at the junction to the next block (None = a stop there).
    s_end: float = 0.0
    du: tuple[float, ...] | None = None
    du_n: float = 0.0
    vtop: float = 0.0  # the fastest this block can ever run (feed × the top override, or its geometric cap)
    # Path tolerance under the filter (nc.motion.deviation): the signed tangent step at the end
    # junction, the junction speed without the tolerance, the speed the deviation model allows
    # when evaluated at this junction, and the least of those of the junctions whose window
    # holds this one (vjunc = min(vbase, vtol); vtol is replaced, not only lowered, as the
    # windows fill).
    dv: tuple[float, ...] = ()
    vbase: float = math.inf
    ctol: float = math.inf
    vtol: float = math.inf
    # The least cap the filter's acceleration/jerk budgets alone gave this junction (its corner and
    # every window that held it; not the tolerance): vjunc / vbud is the share of the corner budget
    # the junction can use (nc.motion.shares, decision motion 39).
    vbud: float = math.inf
    vctol: float = math.inf  # the tolerance's cap of this junction's corner alone (FilterCorners.corner_tolerance)
    # The proved cap of a line-line corner alone in its filter windows where it raised vctol (FilterCorners.isolated_cap,
    # decision motion 73), else 0: crossed at no more, any raw profile within the raised jerk keeps N1.053.
    viso: float = 0.0
    # nc.motion.shares._tolerance_free's verdict, kept between solves with the inputs it was found
    # for (the caps beside the junction and min(vtol, vctol)): it is found again only when one changed.
    tf_cap: float = math.nan
    tf_tcap: float = math.nan
    tf_ok: bool = False
    trim0: float = 0.0  # path its start gave to a corner blend before it (nc.motion.corner_blends)
    # A path block that is not an arc (the jerk-factor scan's walk reads this one field for the three it
    # tests, session 13): set as the block joins the queue; False means "test them" (nc.motion.shares._scan).
    scan_plain: bool = False


_INF = math.inf  # C constants where compiled (block.pxd): no module attribute to look up a block
_NAN = math.nan


@cython.locals(b=Block)
def new_block(move: Move, kind: str, seg: Segment | None, length: float, cap_hard: float, a: float, j: float,
              feed: float | None, rapid: bool) -> Block:
    """`Block(move, kind, seg, length, cap_hard, a, j, feed, rapid)`. Compiled, a C call that fills the struct
    from the type's slot, no __init__'s arguments to parse (one a pushed line, session 29, decision bench B166): the
    fields not given are set to Block's defaults here too (tests/test_planner_feed.py compares every field)."""
    if not cython.compiled:
        return Block(move, kind, seg, length, cap_hard, a, j, feed, rapid)
    b = Block.__new__(Block)  # doubles 0.0, objects None, flags False: the defaults of most fields
    b.move = move
    b.kind = kind
    b.seg = seg
    b.length = length
    b.cap_hard = cap_hard
    b.a = a
    b.j = j
    b.feed = feed
    b.rapid = rapid
    b.binding = True
    b.dv = ()
    b.vbase = _INF
    b.ctol = _INF
    b.vtol = _INF
    b.vbud = _INF
    b.vctol = _INF
    b.tf_cap = _NAN
    b.tf_tcap = _NAN
    return b
