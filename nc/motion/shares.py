"""How much of each axis' jerk the tangential profile may use, from what the filter's corners near
it really use (issue 18, decision motion 39).

The static split (MotionConfig shares: tangential 0.5, corner 0.25, curvature 0.25) keeps the
setpoint stream within the axis limits when all three act in the same cycle. Between lines the
curvature share goes to the filter's corners (decision 38), so tangential + corner = 1. A corner
J crossed at v_J ≤ vjunc uses no more than vjunc / vbud of its budget share: vbud is the least
cap the acceleration/jerk budgets gave J (its own corner and every filter window that held it),
and for any window W, Σ_W v·|Δu| ≤ v_m·Σ_W |Δu| ≤ (v_m / cap_W)·budget with m the fastest
junction of W and cap_W ≥ vbud_m the cap made from a sum that holds W. So while every junction
the filter can mix with a stretch of the tangential profile uses at most U of the corner share,
that stretch may plan with jerk (1 − U·(corner + curvature share)) of the axis limits instead of
the tangential share, up to MAX_FACTOR times it. Only the jerk is raised, not the acceleration.
A higher jerk reaches the full deceleration closer to a corner, so no junction within reach may
be one the tolerance slows, nor one whose tolerance cap would not survive the raised jerk's
larger braking term (`_tolerance_free`).

"Can mix with": the filter's output at one cycle averages T1 + T2 of input, so a tangential jerk
at path position p and a corner at q meet in some output cycle only if the path between them
is crossed within T1 + T2: |p − q| ≤ v_hi·(T1+T2), v_hi the fastest any block in between can
run (vtop: feed × the top override, or its geometric cap). The stretch a solve may use is the
current position to the end of its run. Arcs (the curvature share's centripetal terms) near the
stretch, or a queue that does not reach far enough past the run (the blocks still to come are
unknown, unless the channel said none come before a stop: `closed`), leave the share as it was.
"""

from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from collections.abc import Sequence
from itertools import islice
from typing import TYPE_CHECKING

from nc.motion.block import Block
from nc.motion.limits import MAX_FACTOR, MotionConfig  # MAX_FACTOR: the most a solve raises the tangential jerk
from nc.motion.profile import _at_or_above, _first_above  # bisect_left/right on C doubles (shared)

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

_INF = math.inf  # a C double where compiled (shares.pxd): math.inf is a module attribute lookup

if TYPE_CHECKING:
    from nc.motion.blending import FilterCorners


# (types in shares.pxd: a cpdef function, called in C from the planner; session 29)
def jerk_factor(cfg: MotionConfig, fc: "FilterCorners", blocks: Sequence["Block"], pos: float,
                run_end: float, closed: bool) -> tuple[float, bool]:
    """Factor (1 … MAX_FACTOR) on the tangential jerk of a solve over path positions
    [pos, run_end] (absolute path lengths, Block.s_end's scale) with the queue `blocks`; second:
    the queue did not reach far enough to tell (more blocks may raise the factor)."""
    st = cfg.share_tangential
    pool = cfg.share_corner + cfg.share_curvature
    if st <= 0.0 or st + pool > 1.0 + 1e-9 or not blocks:
        return 1.0, False
    head = blocks[0]
    tail = blocks[-1]
    if head.rapid and cfg.rapid_whole:  # a G00 on the axes' whole budget: no share to take (motion 93)
        return 1.0, False
    t_w = fc.t_j
    v_hi = head.vtop  # max() of the two, spelt out (no generator a scan, session 13)
    x = tail.vtop
    if x > v_hi:
        v_hi = x
    # Whether a junction using its whole share (use 1) already makes the factor 1: then _scan may stop at
    # the first such junction once no block faster than v_hi lies in the reach (every other outcome of
    # its scan, None included, gives 1.0 too).
    saturates = (1.0 - pool) / st <= 1.0
    check = CHECK
    for _ in range(4):  # the reach grows with the fastest block found inside it
        reach = v_hi * t_w
        v_stop = v_hi if saturates else -1.0
        got = _scan(fc, blocks, pos, run_end, reach, closed, v_stop) if check is None \
            else check(fc, blocks, pos, run_end, reach, closed, v_stop)
        if got is None:
            return 1.0, False
        if got is UNKNOWN:
            return 1.0, True
        use, seen = got
        if seen <= v_hi:
            f = (1.0 - use * pool) / st  # min(MAX_FACTOR, max(1.0, f)) spelt out (session 15)
            if not f > 1.0:
                f = 1.0
            return (f if f < MAX_FACTOR else MAX_FACTOR), False
        v_hi = seen
    return 1.0, False



UNKNOWN = (-1.0, -1.0)  # _scan: the queue ends before the reach does
# A test's stand-in for _scan, which jerk_factor calls instead where set (tests/test_motion_shares_kept.py: _scan and
# the helpers below are C functions where compiled, called in C; replacing the module's names reaches no call)
CHECK = None
# Above FilterCorners._boost_ratio's largest value (2: doubling the jerk at most doubles the speed-up) by
# far more than its rounding: _tolerance_free's bound.
RATIO_BOUND = 2.001


def _scan(fc: "FilterCorners", blocks: Sequence["Block"], pos: float, run_end: float, reach: float,
          closed: bool, v_stop: float = -1.0) -> tuple[float, float] | None:
    """(largest vjunc / vbud, fastest vtop) over the junctions within `reach` of [pos, run_end];
    None when an arc is there, UNKNOWN when the queue does not tell what is there. `v_stop` ≥ 0: the
    caller's factor is 1 for a use of 1, so once a junction uses 1 and no vtop in the reach exceeds
    v_stop (no wider scan follows) the rest only needs those vtops (issue 17: 722 of the CAM program's
    2,303 scans)."""
    hi = run_end + reach
    covered = False
    last = blocks[-1]
    # The queue up to the first block past hi: a junction within hi has its next block there, so that
    # prefix's s_end answer _tolerance_free as the whole queue's do (~45 of ~100 blocks; issue 17). Its
    # length, not the list: _verdicts makes the list when it finds a verdict again (1 scan in 6, session 13).
    n_pre = -1  # the whole queue
    # The fastest vtop of the blocks walked (up to the one the walk stops before, or at when it is an exact
    # stop), from 0.0 on. In the walk again (session 15): max() over map/islice of the deque, after it, cost
    # 2.5 µs more a scan than these two lines (fewer opcodes, but islice over a deque and attrgetter per block).
    seen = 0.0
    stop_s = run_end - 1e-9
    i = 0  # b's index (a C counter compiled, not enumerate's int objects: session 27)
    for b in blocks:  # each field read once (~50 blocks a scan, two scans a solve; issue 17)
        plain = b.scan_plain  # a path block, not an arc: the kind and segment tests below answer as they do here
        if not plain:
            seg = b.seg
            if seg is None or b.kind != "path":
                covered = True  # dwell, thread, independent rapid: a stop before it ends every window
                break
        s_end = b.s_end
        if s_end - b.length > hi:
            covered = True
            n_pre = i + 1
            break
        vt = b.vtop
        if vt > seen:
            seen = vt
        if not plain and seg.kind == "arc":
            return None  # the curvature share's centripetal terms
        if b.vjunc <= 0.0 and b is not last and s_end >= stop_s:
            covered = True  # an exact stop (G09/G61, G00): the filter settles there
            break
        i += 1
    if not covered and not (closed or last.s_end > hi):
        return UNKNOWN
    if WALK:
        return _walk(fc, blocks, pos - reach, hi, seen, None if n_pre < 0 else n_pre, v_stop)
    hist_s = fc._hist_s
    k_lo = _at_or_above(hist_s, pos - reach, 0, len(hist_s))  # bisect_left, bisect_right (session 27: on C doubles)
    k_hi = _first_above(hist_s, hi)
    use = 0.0
    if k_hi > k_lo:
        # _walk's outcome from the junctions' kept verdicts (module doc of _verdicts): the walk goes from the
        # newest junction back, so the newest NONE decides unless a use of 1 above it ends the walk first
        # (where v_stop allows: the vtops it then reads are all of the reach's, so the first use of 1 decides).
        sc = _verdicts(fc, blocks, k_lo, k_hi, n_pre)
        # max(fc._vt[k_lo:k_hi]) (the same value, session 15: `max` over ~90 floats was ~1.2 µs a scan): a sliding
        # maximum carried from the range the last scan read, when this one overlaps it and does not end before it
        # (the junctions' vtops are fixed at the push; FilterCorners drops it with the junctions); else the range's
        q = fc._vq
        q_lo, q_hi = fc._vq_at
        vts = fc._vt
        if k_hi < q_hi and q_lo < k_hi:  # a shorter reach between two of the same (_speed_up): the range's
            top = _largest(vts, k_lo, k_hi)
        else:
            if not (q_lo < k_hi and k_lo < q_hi):  # nothing kept of this range: from its start
                q.clear()
                q_lo = q_hi = k_lo
            for k in range(q_hi, k_hi):
                x = vts[k]
                while q:
                    y = q[-1][1]  # a C double compiled: compared with x without a float made of x each time
                    if not y <= x:  # (not `y > x`: the same for nan)
                        break
                    q.pop()
                q.append((k, x))
            if k_lo < q_lo:  # older junctions join: one is kept where it is above all after it
                for k in range(q_lo - 1, k_lo - 1, -1):
                    x = vts[k]
                    y = q[0][1]
                    if x > y:
                        q.appendleft((k, x))
            else:
                while q[0][0] < k_lo:
                    q.popleft()
            top = q[0][1]
            fc._vq_at = (k_lo, k_hi)
        if top > seen:
            seen = top
        # max(sc[k_lo:k_hi]) and the newest NONE in it, on C doubles (session 27: the builtins on the Python
        # floats were a third of a scan)
        m = _largest(sc, k_lo, k_hi)
        stop = v_stop >= 0.0 and seen <= v_stop
        none = NONE
        if m == none:
            k = k_hi - 1  # the newest NONE (m is one)
            x = sc[k]
            while x != none:
                k -= 1
                x = sc[k]
            if stop and k + 1 < k_hi and _largest(sc, k + 1, k_hi) >= 1.0:
                return 1.0, seen
            return None
        if m >= 1.0 and stop:
            return 1.0, seen
        if m > 0.0:
            use = m
    if fc._seq_v > 0 and k_lo <= fc._seq_v - fc._seq0:
        return None  # junctions within the reach were dropped already (by the bulk drop: FilterCorners._seq_v)
    return use, seen


# _verdicts' codes beside a use in [0, 1]: the walk returns None there (an arc, no budget, not tolerance-free),
# or skips the junction (no corner, or no use: nan).
NONE = 2.0
SKIP = -1.0
WALK = False  # True: _scan walks every junction as before the kept verdicts (the reference tests compare with)


# The helpers below are C functions where compiled (their types in shares.pxd, session 27).
def _largest(xs: list[float], lo: int, hi: int) -> float:
    """max(xs[lo:hi]) of floats, lo < hi, as the builtin finds it: an item replaces the largest so far only where
    it is greater (the first of equal ones kept, nan as max leaves it)."""
    m = xs[lo]
    for k in range(lo + 1, hi):
        x = xs[k]
        if x > m:
            m = x
    return m


def _verdicts(fc: "FilterCorners", blocks: Sequence["Block"], k_lo: int, k_hi: int, n_pre: int) -> list:
    """Each junction hist[k_lo:k_hi]'s verdict for _scan: NONE, SKIP or its use min(1, vjunc / vbud), kept in
    fc._sc between scans (issue 17, session 11: consecutive scans cover nearly the same ~90 junctions, and a
    walk over them was the run's largest item); returns fc._sc, found over [k_lo, k_hi). A verdict reads the
    junction's vjunc, vbud, vtol, vctol and cap and its next block's cap; a push changes those only from
    fc._sc_dirty on (FilterCorners.window, _tolerance: the stretch and tolerance windows behind the new junction,
    and the junction before it, whose next block a corner blend trims), an override or dry run every cap
    (FilterCorners.touch), and a solve the head block's (feed per revolution): the junctions up to the head's,
    whose next block is the head or who are it, are found again when its cap is not the one they were found
    with. `n_pre`: the queue's blocks up to the first one past the reach (−1: the whole queue), whose s_end the
    tolerance verdict reads."""
    sc = fc._sc
    n = len(sc)
    d = fc._sc_dirty
    ok_lo, ok_hi = fc._sc_ok  # a range found already: no None in it (session 15: `None in` a list is slow)
    if d < n:
        sc[d:] = [None] * (n - d)
        fc._sc_dirty = n
        if ok_hi > d:
            ok_hi = d
    head = blocks[0]
    if head.cap != fc._sc_head:  # nan the first time
        h = _first_above(fc._hist_s, head.s_end)
        sc[:h] = [None] * h
        fc._sc_head = head.cap
        if ok_lo < h:
            ok_lo = h
    if ok_lo <= k_lo and k_hi <= ok_hi:
        fc._sc_ok = (ok_lo, ok_hi)
        return sc
    fc._sc_ok = _joined(ok_lo, ok_hi, k_lo, k_hi)  # found below where not yet
    k = k_lo  # the first verdict to find (a C walk compiled: `None in` and list.index on a slice were ~2.5k
    while k < k_hi and sc[k] is not None:  # instructions a call, session 27)
        k += 1
    if k == k_hi:
        return sc
    hist = fc._hist
    tol = fc.tol
    ends = []  # [b.s_end for b in islice(blocks, n_pre)], each s_end read as a C double (session 27)
    if n_pre != 0:
        for b in blocks:
            ends.append(b.s_end)
            if len(ends) == n_pre:
                break
    n_ends = len(ends)
    # the codes as the list's objects, stored as they are (compiled, a C double stored is a new float each time)
    none, skip = NONE, SKIP
    j = hist[k]
    i = _first_above(ends, j.s_end)
    for k in range(k, k_hi):
        j = hist[k]
        if not j.scan_plain and j.seg is not None and j.seg.kind == "arc":  # scan_plain: a path block, no arc
            sc[k] = none
            continue
        if j.du_n <= 1e-9:
            sc[k] = skip
            continue
        vbud = j.vbud
        if vbud <= 1e-12:
            sc[k] = none
            continue
        if tol is not None:
            # _tolerance_free, its kept verdict inline; the next block is blocks[i] (j walks on in path order)
            s_j = j.s_end
            while i < n_ends:
                x = ends[i]  # a C double compiled (`ends[i] <= s_j` made a float of s_j each time)
                if not x <= s_j:
                    break
                i += 1
            # _tolerance_free's kept verdict read first, inline (session 15: ~7 calls a scan that finds verdicts
            # again); blocks[i] is j's next block, i = bisect_right(ends, j.s_end) as _tolerance_free finds it
            if i < n_ends:
                cap = j.cap
                b = blocks[i]
                c2 = b.cap
                if c2 > cap:
                    cap = c2
            else:
                cap = j.vtop
            tcap = j.vtol if j.vtol < j.vctol else j.vctol
            if not (j.tf_ok if cap == j.tf_cap and tcap == j.tf_tcap else _tolerance_free(fc, j, blocks, ends)):
                sc[k] = none
                continue
        r = j.vjunc / vbud
        sc[k] = skip if r != r else r if r < 1.0 else 1.0
    return sc


def _joined(lo: float, hi: float, k_lo: int, k_hi: int) -> tuple[int, int]:
    """The range of verdicts found after [k_lo, k_hi) was: joined with [lo, hi) where they meet."""
    if lo < hi and lo <= k_hi and k_lo <= hi:
        return (lo if lo < k_lo else k_lo, hi if hi > k_hi else k_hi)
    return k_lo, k_hi


def _walk(fc: "FilterCorners", blocks: Sequence["Block"], lo: float, hi: float, seen: float,
          n_pre: int | None, v_stop: float) -> tuple[float, float] | None:
    """_scan's junction part as a walk over every junction from the newest back (the reference of the kept
    verdicts, `WALK`)."""
    use = 0.0
    hist = fc._hist
    tol = fc.tol
    ends: list[float] | None = None  # the queue's s_end, built once a junction needs its next block
    # FilterCorners keeps every junction since the last stop (its _h0 is relative to the newest
    # push, not to the executing block) and drops those no scan reads any more, counted in _seq0.
    # hist is in path order: the junctions past hi are skipped by bisection, not one by one. The
    # loop runs over ~85 junctions per solve on dense CAM paths (issue 17): max()/min() spelt out.
    # The junctions before lo by bisection too (hist is in path order): the loop stops at k_lo, and when
    # k_lo is 0 no junction before lo is left, as when it ran off the front before.
    hist_s = fc._hist_s  # hist's s_end, a plain list: bisected without a key
    k_lo = bisect_left(hist_s, lo)
    for k in range(bisect_right(hist_s, hi) - 1, k_lo - 1, -1):
        j = hist[k]
        if j.vtop > seen:
            seen = j.vtop
        if j.seg is not None and j.seg.kind == "arc":
            return None
        if j.du_n <= 1e-9:
            continue
        vbud = j.vbud
        if vbud <= 1e-12:
            return None
        if tol is not None:
            if ends is None:
                ends = [b.s_end for b in islice(blocks, n_pre)]
            if not _tolerance_free(fc, j, blocks, ends):  # (the reference: the next block by bisection)
                return None
        r = j.vjunc / vbud
        if r > use:
            use = r if r < 1.0 else 1.0
            if use == 1.0 and v_stop >= 0.0 and seen <= v_stop:
                top = seen
                for q in range(k - 1, k_lo - 1, -1):
                    x = hist[q].vtop
                    if x > top:
                        top = x
                if top <= v_stop:
                    return use, top
    if fc._seq_v > 0 and k_lo <= fc._seq_v - fc._seq0:
        return None  # junctions within the reach were dropped already (by the bulk drop: FilterCorners._seq_v)
    return use, seen


def _tolerance_free(fc: "FilterCorners", j: "Block", blocks: Sequence["Block"], ends: list[float]) -> bool:
    """Whether junction j keeps N1.053 with the raised jerk at the fastest its blocks may pass it.

    Its tolerance caps (the kernel windows' vtol, its corner alone vctol) were found with the
    braking term of the blocks' own jerk: the deviation grows at least linearly with the speed
    (nc.motion.deviation), so at a speed c below the cap V it is at most (tol − braking)·c/V, and
    the raised jerk adds its larger braking term instead. A junction the tolerance slows below its
    blocks' caps (a real corner, the 15° CAM vertices) fails this: near it the speed changes inside
    the filter window, which the constant-speed kernel model does not see, and a raised jerk there
    took the CAM vertices 0.0002–0.0036 mm over N1.053."""
    if fc.tol is None:
        return True
    tol = fc.tol  # a C double compiled (session 27)
    # the next block (its cap is the feed's): one step, it follows j in the queue (`ends`: the queue's
    # s_end, increasing)
    k = _first_above(ends, j.s_end)
    if k < len(ends):
        cap = j.cap
        b = blocks[k]
        c2 = b.cap
        if c2 > cap:  # max(j.cap, c2) spelt out (session 15)
            cap = c2
    else:
        cap = j.vtop
    tcap = j.vtol if j.vtol < j.vctol else j.vctol
    # A queued junction's inputs rarely change between solves (issue 17): the verdict is kept with
    # the two it was found for; du_n, a, j and the tolerance are fixed once the junction is pushed.
    if cap == j.tf_cap and tcap == j.tf_tcap:
        return j.tf_ok
    if tcap == _INF or (j.viso > 0.0 and tcap <= j.viso):
        # (a corner alone in its windows crossed at no more than its proved cap keeps N1.053 with any jerk up to
        # MAX_FACTOR times the blocks': decision motion 73)
        ok = True
    elif tcap <= 0.0:
        ok = False
    else:
        # boosted = unb × the kernel's speed-up ratio for the doubled jerk, which lies in [1, 2] (a
        # jerk-limited speed change's acceleration min(2jt, a) ≤ 2·min(jt, a), so its path at most
        # doubles): the verdict is decided by those bounds for most junctions without the ratio's
        # kernel sums (a numpy call per new (a, j) pair, i.e. per junction of a curve; issue 17).
        # Rounding is monotone, so the bounds give the verdict the exact expression gives.
        unb = fc.braking(j.du_n, j.a)
        x = cap * (tol - unb) / tcap
        if x + unb > tol:
            ok = False
        elif x + unb * RATIO_BOUND <= tol:
            ok = True
        else:
            ok = x + fc.braking_pair(j.du_n, j.a, j.j)[1] <= tol
    j.tf_cap, j.tf_tcap, j.tf_ok = cap, tcap, ok
    return ok
