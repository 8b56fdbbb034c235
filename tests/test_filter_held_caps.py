"""The filter corners' tolerance evaluation in C loops (decision bench B133): `_kernel_matrix` must give the numpy
form's matrix (`KernelDeviation.weights` times np.minimum) bit for bit, and with it the same deviations, for the
planner's setpoints to stay the same on every program (tests/test_planner_compiled.py compares whole runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hil.bench_file import load_bench_file
from nc.motion.block import Block
from nc.motion.blending import FilterCorners, _kernel_matrix

BENCH = Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml"


def _corners() -> FilterCorners:
    cfg = load_bench_file(BENCH).motion_config()
    acc = [cfg.limit(a).max_acceleration for a in cfg.axes]
    jerk = [cfg.limit(a).max_jerk for a in cfg.axes]
    return FilterCorners(cfg, acc, jerk)


def _numpy_form(fc: FilterCorners, s_rows: np.ndarray, s_all: np.ndarray, vb: np.ndarray, c: float) -> np.ndarray:
    """KernelDeviation.deviation's matrix before the product with the steps, as it is written there."""
    cc = np.full(len(s_rows), c)
    w = fc.kd.weights((s_all[None, :] - s_rows[:, None]) / cc[:, None])
    return w * np.minimum(vb[None, :], cc[:, None])


def _cases(fc: FilterCorners) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, float]]:
    rng = np.random.default_rng(17)
    half, y = fc.kd.half, fc.kd._y
    out = []
    for c in (0.5, 33.3, 250.0):
        # path positions around a junction: random, on G's table points (time offsets y·c), at and past the half
        # window, and equal to the rows' own (x = 0, and -0.0 from the subtraction's sign)
        s_rows = np.sort(rng.uniform(0.0, 2.0 * half * c, 7))
        offs = np.concatenate([rng.uniform(-1.5, 1.5, 40) * half * c, y[::7] * c, -y[::11] * c,
                               [half * c, -half * c, 1.0000001 * half * c, 0.0]])
        s_all = np.sort(s_rows[3] + offs)
        s_all = np.concatenate([s_all, s_rows[:2]])
        vb = rng.uniform(0.2, 2.0, len(s_all)) * c
        vb[::5] = np.inf
        vb[1::9] = c  # np.minimum of equal values
        out.append((s_rows, s_all, vb, c))
    return out


def test_kernel_matrix_is_the_numpy_forms_bit_for_bit():
    fc = _corners()
    for s_rows, s_all, vb, c in _cases(fc):
        w = np.empty((len(s_rows), len(s_all)))
        _kernel_matrix(w, s_rows, s_all, vb, c, fc._gy, fc._gg, fc._gs)
        ref = _numpy_form(fc, s_rows, s_all, vb, c)
        assert (w > 0.0).any() and (w == 0.0).any()  # inside and beyond the half window both tried
        assert np.array_equal(w.view(np.uint64), ref.view(np.uint64))


def test_deviation_from_the_kernel_matrix_is_kernel_deviations():
    fc = _corners()
    rng = np.random.default_rng(18)
    for s_rows, s_all, vb, c in _cases(fc):
        du = rng.uniform(-0.3, 0.3, (len(s_all), 3))
        w = np.empty((len(s_rows), len(s_all)))
        _kernel_matrix(w, s_rows, s_all, vb, c, fc._gy, fc._gg, fc._gs)
        got = np.linalg.norm(w @ du, axis=1)
        ref = fc.kd.deviation(np.full(len(s_rows), c), s_rows, s_all, du, vb)
        assert got.min() > 0.0
        assert np.array_equal(got, ref)


def _refine_numpy(fc: FilterCorners, hist: list[Block], h0: int, last: int, c: float, top: float,
                  budget_a: tuple[float, ...], budget_j: tuple[float, ...]) -> tuple[float, float]:
    """FilterCorners._refine as numpy had it before decision bench B133 (session 25's main), the reference."""
    t1, t2 = fc.t_a, fc.t_j - fc.t_a
    s_j = hist[last].s_end
    lo = last
    reach = top * fc.t_j * 2.0
    while lo > h0 and s_j - hist[lo - 1].s_end <= reach:
        lo -= 1
    seg = hist[lo:last + 1]
    s = np.fromiter((b.s_end for b in seg), float, len(seg))
    du = np.array([b.dv for b in seg], dtype=float)
    vb = np.fromiter((b.vbase for b in seg), float, len(seg))
    ba, bj = np.array(budget_a), np.array(budget_j)
    between = seg[1:]
    al = np.fromiter((b.a * b.length for b in between), float, len(between))
    vt = np.fromiter((b.vtop for b in between), float, len(between))

    def sums(v: float) -> tuple[np.ndarray, np.ndarray]:
        pre = np.vstack([np.zeros((1, du.shape[1])), np.cumsum(np.minimum(vb, v)[:, None] * du, axis=0)])

        def windows(vw: float) -> tuple[np.ndarray, np.ndarray]:
            w1, w2 = vw * t1, vw * t2
            ev = np.concatenate(([s_j], s + w1, s + w1 - 1e-9, s + w1 + w2, s + w1 + w2 - 1e-9))
            ev = ev[(ev >= s_j) & (ev <= s_j + w1 + w2)]

            def at(x: np.ndarray) -> np.ndarray:
                return pre[np.searchsorted(s, x, side="right")]
            mid = at(ev - w1)
            a = at(ev) - mid
            b = mid - at(ev - w1 - w2)
            return np.abs(a).max(axis=0), np.abs(a - b).max(axis=0)

        sa, sd = windows(v)
        peak = float(np.max(np.minimum(vt, np.sqrt(v * v + al)))) if len(al) else v
        if peak > v * (1.0 + 1e-9):
            for vw in (0.5 * (v + peak), peak):
                xa, xd = windows(vw)
                sa, sd = np.maximum(sa, xa), np.maximum(sd, xd)
        return sa, sd

    def cap_at(v: float) -> float:
        sa, sd = sums(v)
        with np.errstate(divide="ignore", over="ignore"):
            return v * min(float(np.min(np.where(sa > 1e-12, ba / sa, np.inf))),
                           float(np.min(np.where(sd > 1e-12, bj / sd, np.inf))))

    best = c
    bud = nxt = cap_at(c)
    v = min(nxt, top)
    for _ in range(3):
        if v <= best * (1.0 + 1e-6):
            break
        nxt = cap_at(v)
        if nxt >= v * (1.0 - 1e-9):
            best, bud = v, nxt
            v = min(nxt, top)
        else:
            v = 0.5 * (best + v)
    return best, max(bud, best)


def _stretch(rng: np.random.Generator, n: int, curve: bool) -> list[Block]:
    """n junctions of short blocks: a gentle curve's small steps of one sign, or a zig-zag's of both; some slow
    blocks (vbase below the speeds tried), some short blocks with a high vtop (their peak above the junctions)."""
    out, s = [], 0.0
    for i in range(n):
        length = float(rng.uniform(0.05, 1.5))
        s += length
        b = Block(None, "path", None, length, 500.0, float(rng.uniform(500.0, 3000.0)), 5e4, None)
        b.s_end = s
        step = rng.uniform(0.0, 0.02, 3) if curve else rng.uniform(-0.2, 0.2, 3)
        b.dv = tuple(float(x) for x in step)
        b.vbase = float(rng.choice([np.inf, rng.uniform(5.0, 400.0)]))
        b.vtop = float(rng.uniform(50.0, 600.0))
        out.append(b)
    return out


def test_refine_is_the_numpy_forms_bit_for_bit():
    fc = _corners()
    rng = np.random.default_rng(19)
    seen = set()
    for case in range(40):
        hist = _stretch(rng, int(rng.integers(2, 120)), curve=case % 2 == 0)
        last = len(hist) - 1
        h0 = int(rng.integers(0, last + 1))
        top = float(rng.uniform(20.0, 500.0))
        c = float(rng.uniform(0.1, 1.0)) * top
        for budgets in ((fc.budget_a, fc.budget_j), (fc.budget_al, fc.budget_jl)):
            got = fc._refine(hist, h0, last, c, top, *budgets)
            ref = _refine_numpy(fc, hist, h0, last, c, top, *budgets)
            assert got == ref
            seen.add("raised" if got[0] > c else "kept")
    assert seen == {"raised", "kept"}  # both outcomes of the search compared


def test_kernel_matrix_rows_in_any_order_and_a_band_of_zeros():
    """Rows out of order (and equal) give the numpy form's matrix bit for bit, zeros beyond half a window included
    (B202 measured carrying that band from one row to the next while the rows' positions do not fall)."""
    fc = _corners()
    for s_rows, s_all, vb, c in _cases(fc):
        for rows in (s_rows[::-1].copy(), np.concatenate([s_rows[4:], s_rows[:4], s_rows[2:3]])):
            w = np.empty((len(rows), len(s_all)))
            _kernel_matrix(w, rows, s_all, vb, c, fc._gy, fc._gg, fc._gs)
            ref = _numpy_form(fc, rows, s_all, vb, c)
            assert (w == 0.0).any()
            assert np.array_equal(w.view(np.uint64), ref.view(np.uint64))


def test_least_held_is_the_least_cap_over_the_reaches_that_hold_each_junction():
    """Each result of `_least_held` is the least ct over the junctions k with |s[u] − s[k]| ≤ rc[k] (and ≤ far), inf
    where none, a nan kept (two junctions at one place; B202 measured stepping its first junction on instead)."""
    import importlib.util

    # a cdef function where compiled: its source run as Python (the same steps; the compiled run's setpoints are
    # tests/test_planner_compiled.py's)
    spec = importlib.util.spec_from_file_location("blending_source", Path(__file__).resolve().parent.parent / "nc"
                                                  / "motion" / "blending.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    _least_held = mod._least_held
    rng = np.random.default_rng(203)
    for n, far in ((40, 3.0), (60, 0.5), (25, 100.0)):
        s = np.sort(rng.uniform(0.0, 20.0, n))
        s[10] = s[9]  # two junctions at one place
        rc = rng.uniform(0.0, far, n)
        ct = rng.uniform(1.0, 9.0, n)
        ct[7] = np.nan
        n0 = n // 3
        held = np.full(n, -1.0)
        _least_held(s, ct, rc, n0, far, held)
        for u in range(n0, n):
            d = np.abs(s[u] - s)
            near = [ct[k] for k in range(n) if d[k] <= rc[k] and d[k] <= far]
            want = np.nan if any(np.isnan(near)) else min(near, default=np.inf)
            assert held[u] == want or (np.isnan(want) and np.isnan(held[u])), u
