"""The filter corners' tolerance evaluation in C loops (decision bench B133): `_kernel_matrix` must give the numpy
form's matrix (`KernelDeviation.weights` times np.minimum) bit for bit, and with it the same deviations, for the
planner's setpoints to stay the same on every program (tests/test_planner_compiled.py compares whole runs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hil.bench_file import load_bench_file
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
