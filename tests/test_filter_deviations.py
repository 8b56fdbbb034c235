"""The filter corners' deviations in C (decision bench B163): compiled, `_deviations` sums the product of the kernel
matrix with the steps and its row norms in C loops, in the order numpy's matmul (OpenBLAS) and np.linalg.norm sum
them on this CPU (SkylakeX's or Haswell's kernels, probed at first use; elsewhere numpy itself). It must give np.linalg.norm(w @ du, axis=1) bit for bit on every shape `_held_caps` hands
it (one row, one step, fewer and more than 16 steps, rows in and past groups of four; 2 and 3 axes): a deviation
one ulp off could flip a junction's fit against its room, and the compiled planner's setpoints would leave its
source's (tests/test_planner_compiled.py compares whole runs)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import nc.motion.compiled as compiled
from nc.motion import blending
from nc.motion.blending import _deviations, _kernel_matrix

compiled_only = pytest.mark.skipif(compiled.BUILD != "compiled",
                                   reason=f"the C form runs compiled only ({compiled.BUILD}); as Python it is numpy's")


def _numpy_form(w: np.ndarray, du: np.ndarray) -> np.ndarray:
    """What `_held_caps` computed before B163 (and KernelDeviation.deviation computes): fresh C-contiguous arrays."""
    return np.linalg.norm(np.ascontiguousarray(w) @ np.ascontiguousarray(du), axis=1)


def _c_form(w: np.ndarray, du: np.ndarray) -> np.ndarray:
    e = np.full(w.shape[0], np.nan)
    _deviations(w, du, e)
    return e


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


@st.composite
def _inputs(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """A kernel matrix (weights ≥ 0, zeros past the half window) and the steps (signed, spread over magnitudes so that
    summing in another order changes the last bits)."""
    nl = draw(st.sampled_from([1, 1, 2, 3, 4, 5, 7, 8, 9, 13, 23, 40]))
    nn = draw(st.sampled_from([1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 23, 24, 31, 45, 64, 100, 257]))
    axes = draw(st.sampled_from([2, 3, 3]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    w = rng.uniform(0.0, 3.0, (nl, nn)) * 10.0 ** rng.integers(-3, 3, (nl, nn))
    w[rng.random((nl, nn)) < 0.25] = 0.0
    du = rng.uniform(-1.0, 1.0, (nn, axes)) * 10.0 ** rng.integers(-6, 1, (nn, axes))
    du[rng.random((nn, axes)) < 0.1] = 0.0
    return w, du


@compiled_only
@settings(max_examples=400, deadline=None)
@given(_inputs())
def test_deviations_are_numpys_bit_for_bit(case):
    w, du = case
    assert _same_bits(_c_form(w, du), _numpy_form(w, du))


@compiled_only
def test_differently_summed_forms_differ_here():
    """The inputs above tell summation orders apart: a plain loop over the steps, in order, misses numpy's bits."""
    rng = np.random.default_rng(5)
    differ = 0
    for _ in range(50):
        w = rng.uniform(0.0, 3.0, (23, 45))
        du = rng.uniform(-0.3, 0.3, (45, 3))
        plain = np.empty((23, 3))
        for r in range(23):
            for a in range(3):
                x = 0.0
                for k in range(45):
                    x += float(w[r, k]) * float(du[k, a])
                plain[r, a] = x
        differ += not _same_bits(np.linalg.norm(plain, axis=1), _numpy_form(w, du))
    assert differ > 25


@compiled_only
def test_kernel_matrix_then_deviations_as_held_caps_uses_them():
    """The matrix `_kernel_matrix` fills, then `_deviations` on it: KernelDeviation.deviation's bit for bit."""
    from tests.test_filter_held_caps import _cases, _corners

    fc = _corners()
    rng = np.random.default_rng(19)
    for s_rows, s_all, vb, c in _cases(fc):
        du = rng.uniform(-0.3, 0.3, (len(s_all), 3))
        w = np.empty((len(s_rows), len(s_all)))
        _kernel_matrix(w, s_rows, s_all, vb, c, fc._gy, fc._gg, fc._gs)
        ref = fc.kd.deviation(np.full(len(s_rows), c), s_rows, s_all, du, vb)
        assert ref.min() > 0.0
        assert _same_bits(_c_form(w, du), ref)


@compiled_only
def test_mismatched_sizes_are_refused():
    with pytest.raises(ValueError):
        _deviations(np.ones((2, 5)), np.ones((4, 3)), np.empty(2))
    with pytest.raises(ValueError):
        _deviations(np.ones((3, 5)), np.ones((5, 3)), np.empty(2))



# The summation order is probed at first use (B163): the C loops run only in an order whose probes all give numpy's
# bits; elsewhere `_deviations` calls numpy, as the Python build does.


def test_the_order_taken_is_one_the_probe_accepts():
    order = blending.deviation_order()
    if compiled.BUILD != "compiled":
        assert order == "numpy"
    assert order in blending._ORDERS
    for w, du in blending._probe_cases():
        assert _same_bits(_c_form(w, du), _numpy_form(w, du))


def _forced(order: str, w: np.ndarray, du: np.ndarray, monkeypatch: pytest.MonkeyPatch) -> np.ndarray:
    monkeypatch.setattr(blending, "_dev_order", blending._ORDERS.index(order))
    return _c_form(w, du)


@compiled_only
def test_the_probe_tells_the_orders_apart(monkeypatch):
    """SkylakeX's and Haswell's orders differ somewhere on the probe set in each branch where they sum differently
    (one row; 16 steps and more), so the probe takes the right one on either CPU."""
    one_row, many_steps = 0, 0
    for w, du in blending._probe_cases():
        differ = not _same_bits(_forced("SkylakeX", w, du, monkeypatch), _forced("Haswell", w, du, monkeypatch))
        one_row += differ and w.shape[0] == 1
        many_steps += differ and w.shape[0] > 1 and w.shape[1] >= 16
    assert one_row >= 2 and many_steps >= 3


@compiled_only
def test_no_order_matching_numpy_calls_numpy(monkeypatch):
    """A BLAS that sums in neither order (here: a reference one ulp off on its first row): the probe keeps no C
    order, and `_deviations` gives numpy's bits."""
    real = blending._numpy_deviations

    def off_by_an_ulp(w, du):
        out = real(w, du)
        out[0] = np.nextafter(out[0], np.inf)
        return out

    monkeypatch.setattr(blending, "_numpy_deviations", off_by_an_ulp)
    monkeypatch.setattr(blending, "_dev_order", -1)
    assert blending.deviation_order() == "numpy"
    monkeypatch.setattr(blending, "_numpy_deviations", real)
    rng = np.random.default_rng(31)
    for nl, nn in ((1, 9), (4, 1), (5, 9), (6, 21), (9, 40)):
        w, du = rng.uniform(0.0, 3.0, (nl, nn)), rng.uniform(-1.0, 1.0, (nn, 3))
        assert _same_bits(_c_form(w, du), _numpy_form(w, du))


_HASWELL_RUN = """
import numpy as np
from nc.motion import blending
rng = np.random.default_rng(163)
same = 0
for i in range(600):
    nl = int(rng.choice([1, 1, 2, 3, 4, 5, 7, 9, 13, 23, 40]))
    nn = int(rng.choice([1, 2, 3, 5, 7, 9, 15, 16, 17, 23, 31, 45, 64, 100, 255, 256, 257, 300, 513, 700]))
    axes = int(rng.choice([2, 3]))
    w = rng.uniform(0.0, 3.0, (nl, nn)) * 10.0 ** rng.integers(-3, 3, (nl, nn))
    w[rng.random((nl, nn)) < 0.25] = 0.0
    du = rng.uniform(-1.0, 1.0, (nn, axes)) * 10.0 ** rng.integers(-6, 1, (nn, axes))
    e = np.full(nl, np.nan)
    blending._deviations(w, du, e)
    same += np.array_equal(e.view(np.uint64), np.linalg.norm(w @ du, axis=1).view(np.uint64))
print(blending.deviation_order(), same)
"""


def _haswell_forcible() -> str:
    """Why OPENBLAS_CORETYPE=Haswell would not pick OpenBLAS's Haswell kernels here ('' where it does)."""
    try:
        blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    except (KeyError, TypeError):
        return "numpy does not report its BLAS"
    if blas.get("name", "").find("openblas") < 0 or "DYNAMIC_ARCH" not in blas.get("openblas configuration", ""):
        return f"numpy's BLAS is no OpenBLAS built with DYNAMIC_ARCH ({blas.get('name')})"
    try:
        flags = next(line for line in open("/proc/cpuinfo") if line.startswith("flags")).split()
    except (OSError, StopIteration):
        return "no /proc/cpuinfo"
    return "" if {"avx2", "fma"} <= set(flags) else "the CPU has no AVX2 and FMA"


@compiled_only
def test_on_haswell_kernels_the_haswell_order_is_numpys():
    """With numpy's OpenBLAS forced onto its Haswell kernels (those Haswell, Zen and valgrind's CPU run), the probe
    takes the Haswell order and `_deviations` gives numpy's bits on 600 random shapes (one row, one step, K blocks
    past 256)."""
    why = _haswell_forcible()
    if why:
        pytest.skip(why)
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, OPENBLAS_CORETYPE="Haswell")
    out = subprocess.run([sys.executable, "-c", _HASWELL_RUN], cwd=root, env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["Haswell", "600"]


@compiled_only
def test_rows_with_a_leading_band_of_zeros_as_numpy():
    """Rows with leading zeros (the kernel's band behind half a window; B202 measured skipping it, which must keep
    this): bands that end before, at and past groups of eight steps, -0.0 in one, one that ends at the last step,
    and a step that is not finite inside a band (0·inf: the nan numpy gives) — numpy's deviations bit for bit."""
    rng = np.random.default_rng(202)
    for nn in (5, 15, 16, 17, 40, 300, 600):
        for axes in (2, 3):
            nl = 13
            w = rng.uniform(0.0, 3.0, (nl, nn)) * 10.0 ** rng.integers(-3, 3, (nl, nn))
            du = rng.uniform(-1.0, 1.0, (nn, axes)) * 10.0 ** rng.integers(-6, 1, (nn, axes))
            bands = [0, 1, 7, 8, 9, 15, 16, 17, nn // 2, nn - 1, nn, 3, 24]
            for r, kz in enumerate(bands):
                w[r, :min(kz, nn)] = 0.0
            w[2, :3] = -0.0
            assert _same_bits(_c_form(w, du), _numpy_form(w, du))
            du[min(5, nn - 1), axes - 1] = np.inf  # inside the bands of rows 2.. : their deviation is a nan
            with np.errstate(invalid="ignore"):
                ref = _numpy_form(w, du)
            assert np.isnan(ref[3]) and _same_bits(_c_form(w, du), ref)
