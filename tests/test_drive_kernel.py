"""The sim drive's kernels (virtual_bus/drive_kernel.py) compiled by setup.py give the same bits as their Python
source (issue 17): a compiled build may only be faster. Random drives, targets and stretches through both."""

from __future__ import annotations

import importlib.util
import math
import os
import struct
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import virtual_bus.kernels as kernels
from virtual_bus.drive_stretch import Stretch

SOURCE = Path(kernels.__file__).with_name("drive_kernel.py")


def _source_module():
    spec = importlib.util.spec_from_file_location("drive_kernel_source", SOURCE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


PY = _source_module()
BUILT = kernels.drive_kernel
needs_build = pytest.mark.skipif(kernels.BUILD != "compiled",
                                 reason=f"the kernel is not compiled here ({kernels.BUILD})")


def _bits(x):
    """A value's exact bits: floats by their IEEE image (a zero's sign too), ints as they are, tuples item by item."""
    if isinstance(x, float):
        return ("f", struct.pack("<d", x))
    if isinstance(x, (tuple, list)):
        return tuple(_bits(v) for v in x)
    return x


finite = st.floats(min_value=-1e7, max_value=1e7, allow_nan=False, allow_infinity=False)


@needs_build
@settings(max_examples=300, deadline=None)
@given(n=st.integers(1, 8), prev=finite, span=st.floats(-5e4, 5e4), kff=st.floats(0.0, 1.0),
       kp=st.floats(0.0, 2000.0), pos=finite, vel=st.floats(-1e6, 1e6), max_cps=st.floats(1e3, 1e6),
       bw=st.floats(10.0, 5000.0), limited=st.booleans(), lo=finite)
def test_csp_substeps_compiled_equal_their_source(n, prev, span, kff, kp, pos, vel, max_cps, bw, limited, lo):
    h = 0.001 / n
    alpha = 1.0 - math.exp(-bw * h)
    args = (n, h, prev, span, kff * span / 0.001, kp, pos, vel, 12.5, max_cps, alpha, limited, lo, lo + 5e4)
    assert _bits(BUILT.csp_substeps(*args)) == _bits(PY.csp_substeps(*args))


@needs_build
@settings(max_examples=300, deadline=None)
@given(n=st.integers(1, 8), ramp=st.floats(0.0, 5e4), want=st.floats(-1e6, 1e6), tv=st.floats(-1e6, 1e6),
       pos=finite, vel=st.floats(-1e6, 1e6), max_cps=st.floats(1e3, 1e6), bw=st.floats(10.0, 5000.0),
       every=st.sampled_from([0, 4096, 1280000]))
def test_csv_substeps_compiled_equal_their_source(n, ramp, want, tv, pos, vel, max_cps, bw, every):
    h = 0.001 / n
    args = (n, h, ramp, want, tv, pos, vel, 3.0, max_cps, 1.0 - math.exp(-bw * h), every)
    assert _bits(BUILT.csv_substeps(*args)) == _bits(PY.csv_substeps(*args))


def _csp_consts(n, window, limits, bw):
    h = 0.001 / n
    max_cps = 3000.0 / 60.0 * 1280000
    return (n, h, max_cps, 1.0 - math.exp(-bw * h), 2.0 * math.pi / 1280000, 0.001 * max_cps, 300.0, 1.0,
            window, 17.0, 600.0 / 1280000, 0.1, 2e-4, 1e-3, 0.05, 1.27, limits[0], limits[1], 0x1237, 0.001,
            limits[0] > -math.inf or limits[1] < math.inf)


@needs_build
@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 6), steps=st.lists(st.integers(-3000, 3000), min_size=1, max_size=60),
       window=st.sampled_from([5e3, 1e5, 1e9]), lim=st.sampled_from([(-math.inf, math.inf), (-2e4, 2e4)]),
       bw=st.floats(200.0, 3000.0), start=st.integers(-10_000, 10_000))
def test_csp_cycles_compiled_equal_their_source(n, steps, window, lim, bw, start):
    # targets that move, stop (repeat: the still cycles), fault on the window or run into a limit switch
    targets, x = [], start
    for s in steps:
        x += s if s % 7 else 0
        targets.append(x)
    consts = _csp_consts(n, window, lim, bw)
    state = (float(start) - 17.0, 0.0, 1.5, float(start) - 17.0, None, 0.0, 0.0)
    outs = []
    for mod in (BUILT, PY):
        out = Stretch()
        res = mod.csp_cycles(targets, consts, state, None, out)
        outs.append((_bits(res), out.position_actual, out.velocity_actual, out.torque_actual,
                     out.following_error, out.statusword))
    assert outs[0] == outs[1]


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 4), steps=st.lists(st.integers(-3000, 3000), min_size=1, max_size=40),
       cut=st.integers(0, 40), bound=st.sampled_from([math.inf, 40.0, 300.0, 900.0]))
def test_csp_cycles_keep_the_first_cycle_over_the_bench_overspeed_bound(n, steps, cut, bound):
    """The bench's overspeed check (App. A 0x0602) reads 0x606C: csp_cycles keeps the first cycle whose velocity is
    above `Stretch.limit` (`over_at`, -1: none) over parts stepped one after the other, as a pass steps them
    (hil/stretch_pass.py, decision bench B174); the source, and the build where there is one."""
    targets, x = [], 0
    for s in steps:
        x += s if s % 5 else 0  # (stops: still cycles, written as a repeat)
        targets.append(x)
    consts = _csp_consts(n, 1e9, (-math.inf, math.inf), 1500.0)
    for mod in (PY, BUILT):
        out = Stretch(limit=bound)
        state, still = (-17.0, 0.0, 0.0, -17.0, None, 0.0, 0.0), None
        for part in (targets[:cut], targets[cut:]):
            state, still, ok = mod.csp_cycles(part, consts, state, still, out)
            assert ok
        va = out.velocity_actual
        assert len(va) == len(targets)
        assert out.over_at == next((k for k, v in enumerate(va) if abs(v) > bound), -1)


def test_an_axis_speeding_up_is_over_the_bound_from_its_first_fast_cycle():
    """A ramp of 0, 100, … 1,500 counts a cycle, stepped in two parts: 0x606C climbs past a bound of 300 once, and
    `over_at` is that cycle (in the second part), for the source and the build alike."""
    targets, x = [], 0
    for k in range(16):
        x += 100 * k
        targets.append(x)
    consts = _csp_consts(4, 1e9, (-math.inf, math.inf), 1500.0)
    for mod in (PY, BUILT):
        out = Stretch(limit=300.0)
        state, still, _ = mod.csp_cycles(targets[:5], consts, (-17.0, 0.0, 0.0, -17.0, None, 0.0, 0.0), None, out)
        assert out.over_at == -1 and max(map(abs, out.velocity_actual)) <= 300
        mod.csp_cycles(targets[5:], consts, state, still, out)
        first = next(k for k, v in enumerate(out.velocity_actual) if abs(v) > 300)
        assert first > 5 and out.over_at == first


@needs_build
@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 6), cycles=st.integers(1, 400), want=st.floats(-2e6, 2e6), tv=st.floats(-2e6, 2e6),
       vel=st.floats(-2e6, 2e6), every=st.sampled_from([0, 1280000, 4096]), ramp=st.floats(0.0, 3e4))
def test_csv_cycles_compiled_equal_their_source(n, cycles, want, tv, vel, every, ramp):
    h = 0.001 / n
    max_cps = 6000.0 / 60.0 * 1280000
    consts = (n, h, max_cps, 1.0 - math.exp(-1500.0 * h), 2.0 * math.pi / 1280000, 0.001 * max_cps, 3.0, ramp,
              want, every, 600.0 / 1280000, 0.1, 2e-4, 1e-3, 0.05, 1.27, 0x1237, 0.001)
    state = (123.25, vel, 0.5, 123.25, tv, 0.0, 0.0)
    outs = []
    for mod in (BUILT, PY):
        out = Stretch()
        res = mod.csv_cycles(cycles, consts, state, False, out)
        outs.append((_bits(res), out.position_actual, out.velocity_actual, out.torque_actual, out.statusword))
    assert outs[0] == outs[1]


def _round_outcome(f, x):
    try:
        r = f(x)
    except (ValueError, OverflowError) as exc:
        return type(exc)
    assert type(r) is int
    return r


# halves and their neighbours, where rounding to even and the fraction's exactness are decided
_HALVES = [k / 2.0 for k in range(-9, 10)] + [math.nextafter(k / 2.0, d) for k in range(-9, 10) for d in (-9.0, 9.0)]
_EDGES = [0.0, -0.0, 2.0 ** 52, -2.0 ** 52, 2.0 ** 52 - 0.5, -(2.0 ** 52) + 0.5, 2.0 ** 53 + 2.0, 1e300, -1e300,
          math.inf, -math.inf, math.nan, 5e-324, -5e-324, math.nextafter(-0.5, 0.0), math.nextafter(0.5, 0.0)]


@settings(max_examples=2000, deadline=None)
@given(x=st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from(_HALVES + _EDGES)
       | st.integers(-2 ** 40, 2 ** 40).map(lambda k: k / 2.0))
def test_nearest_is_round_for_every_double(x):
    """The kernels' round() on C doubles (B161): the builtin's int for every double, halves to even, its error for NaN
    and infinities; the source and the build alike."""
    want = _round_outcome(round, x)
    assert _round_outcome(PY.nearest, x) == want
    assert _round_outcome(BUILT.nearest, x) == want


@given(coulomb=st.floats(0.0, 1e6), vel=st.floats(allow_nan=True, allow_infinity=True))
def test_the_friction_term_is_copysign_above_one_count_a_second(coulomb, vel):
    want = math.copysign(coulomb, vel) if abs(vel) > 1 else 0.0
    for mod in (PY, BUILT):
        got = mod.coulomb_of(coulomb, vel)
        assert struct.pack("<d", got) == struct.pack("<d", want)


def test_a_build_older_than_its_source_is_not_run(tmp_path):
    src, built = tmp_path / "drive_kernel.py", tmp_path / "drive_kernel.cpython-311-x86_64-linux-gnu.so"
    src.write_text("")
    built.write_bytes(b"")
    os.utime(src, (1_000, 1_000))
    os.utime(built, (2_000, 2_000))
    assert kernels.build_of(str(built), str(src)) == "compiled"
    os.utime(src, (2_001, 2_001))  # written a moment after it: pip extracting a wheel
    assert kernels.build_of(str(built), str(src)) == "compiled"
    os.utime(src, (3_000, 3_000))  # the source edited (or checked out) after the build
    assert kernels.build_of(str(built), str(src)).startswith("python (the compiled build is older")
    assert kernels.build_of(str(src), str(src)).startswith("python (not compiled")
    assert kernels.build_of(None, str(src)).startswith("python (not compiled")


@settings(max_examples=300, deadline=None)
@given(rows=st.lists(st.lists(finite | st.sampled_from(_HALVES), min_size=3, max_size=3), min_size=1, max_size=8),
       c=st.integers(0, 8), cpu=st.sampled_from([256.0, 1e4 / 3.0, -128000.0, 1.0]),
       origin=st.sampled_from([0.0, 12.5, -3.25]))
def test_to_counts_are_the_axis_scalings_rounded_counts(rows, c, cpu, origin):
    """A stretch's 0x607A targets (B174): round((x - origin) × counts per unit) of each axis's setpoints from row c
    on, appended to the targets so far, halves to even; the source and the build alike."""
    scales = [(cpu, origin), (-cpu, -origin), (cpu * 2.0, origin)]
    want = [[7] + [round((r[i] - o) * k) for r in rows[c:]] for i, (k, o) in enumerate(scales)]
    for mod in (PY, BUILT):
        targets = [[7], [7], [7]]
        mod.to_counts(rows, c, scales, targets)
        assert targets == want


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 6), steps=st.lists(st.integers(-3000, 3000), min_size=1, max_size=60),
       cuts=st.lists(st.integers(0, 60), max_size=6), window=st.sampled_from([5e3, 1e9]),
       bound=st.sampled_from([math.inf, 300.0]))
def test_a_drive_stepped_in_parts_by_drive_parts_equals_one_csp_cycles(n, steps, cuts, window, bound):
    """A pass's drives a part at a time (hil/stretch_pass.py through `drive_parts`, decision bench B198): a CSP axis's
    CspCore over the parts its feeds cut, standing runs counted and written later, gives every cycle's feedback,
    the state, the first cycle over the bench's bound and where a fault stops it as csp_cycles over all the targets
    at once; the source, and the build where there is one."""
    targets, x = [-17], 0
    for s in steps:
        x += s if s % 3 else 0  # (stops: still cycles, a standing axis's lag)
        targets.append(x)
    consts = _csp_consts(n, window, (-math.inf, math.inf), 1500.0)
    state = (-17.0, 0.0, 0.0, -17.0, None, 0.0, 0.0)
    bounds = sorted({0, len(targets), *(min(c, len(targets)) for c in cuts)})
    got = []
    for mod in (PY, BUILT):
        once = Stretch(limit=bound)
        want_state, _, want_ok = mod.csp_cycles(targets, consts, state, None, once)
        out = Stretch(limit=bound)
        core = mod.CspCore(consts, state, out)
        stops = [mod.drive_parts([core], [targets], a, b, 1) for a, b in zip(bounds, bounds[1:])]
        if core.lag:
            core.settle()
        cols = [(c.position_actual, c.velocity_actual, c.torque_actual, c.following_error, c.statusword, c.over_at)
                for c in (once, out)]
        assert cols[0] == cols[1] and core.ok == want_ok
        assert _bits(core.state()) == _bits(want_state)
        # each part's answer: the first cycle a drive stopped before or went over the bound, else the part's end
        first = min(len(once.position_actual), once.over_at if once.over_at >= 0 else len(targets))
        assert [s if s < b else None for s, b in zip(stops, bounds[1:])] == \
            [first if first < b else None for b in bounds[1:]]
        got.append(cols[1])
    assert got[0] == got[1]
