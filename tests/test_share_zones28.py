"""The filter's share λ along the path (nc.motion.share_zones, decision motion 45), compiled with the planner since
session 28 (decision bench B157): λ of a blend's zone, hard junctions near it planned raw, blends kept clear of a hard
junction's reach; and the compiled zones answer every question as the source run as Python does, bit for bit."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np

from nc.motion import share_zones
from nc.motion.share_zones import RAMP, ShareZones

SOURCE = Path(share_zones.__file__).with_name("share_zones.py")


def _source_module():
    """nc/motion/share_zones.py run as Python (whatever the import above took, a build or the source)."""
    spec = importlib.util.spec_from_file_location("share_zones_source", SOURCE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses looks its module up there
    spec.loader.exec_module(mod)
    return mod


def test_lambda_is_zero_on_a_blend_and_rises_over_its_ramp() -> None:
    z = ShareZones(0.004)  # T1 + T2 = 4 ms: reach 0.4 mm at 100 mm/s
    z.add_blend(10.0, 12.0, 100.0)  # core [9.6, 12.4], ramps of RAMP · 100 = 3 mm on both sides
    assert z.lam(11.0) == 0.0
    assert abs(z.lam(9.6 - 1.5) - 0.5) < 1e-12  # the smoothstep's middle, before the core
    assert abs(z.lam(12.4 + 1.5) - 0.5) < 1e-12  # and after it
    z.stop(14.0)  # a stop closes the zone there: λ is 1 beyond it
    assert z.zones[-1].hi == 14.0
    assert z.lam(14.5) == 1.0
    assert not z.zones  # passed: dropped
    assert not z.inside(30.0, 100.0)
    assert RAMP == 0.03


def test_a_hard_junction_near_a_blend_is_planned_raw_and_a_blend_stays_clear_of_one() -> None:
    z = ShareZones(0.004)
    z.add_blend(10.0, 12.0, 100.0)
    assert z.hard(13.0, 100.0)  # λ < 1 reaches it: planned as without the filter
    assert not z.hard(50.0, 100.0)  # the filter's own: λ = 1 needed up to 50.4
    # a blend whose ramp would start before 50.4 is not built; one far enough on is
    assert not z.blend_allowed(50.5, 100.0, 0.0, False)
    assert z.blend_allowed(60.0, 100.0, 0.0, False)
    assert not z.blend_allowed(60.0, 100.0, 57.0, False)  # λ would jump under the sample going out
    assert z.blend_allowed(60.0, 100.0, 57.0, True)  # at rest it may


def test_compiled_zones_answer_as_the_source_bit_for_bit() -> None:
    src = _source_module()
    rng = np.random.default_rng(157)
    for _ in range(40):
        a, b = ShareZones(0.004), src.ShareZones(0.004)
        s = 0.0
        for _ in range(60):
            s += float(rng.uniform(0.01, 3.0))
            v = float(rng.uniform(1.0, 200.0))
            now = s - float(rng.uniform(0.0, 10.0))
            op = int(rng.integers(6))
            if op == 0:
                got, want = a.hard(s, v), b.hard(s, v)
            elif op == 1:
                rest = bool(rng.integers(2))
                got, want = a.blend_allowed(s, v, now, rest), b.blend_allowed(s, v, now, rest)
            elif op == 2:
                a.add_blend(s, s + 0.5, v)
                b.add_blend(s, s + 0.5, v)
                got = want = None
            elif op == 3:
                a.block(s, v)
                b.block(s, v)
                got = want = None
            elif op == 4 and rng.random() < 0.2:
                a.stop(s)
                b.stop(s)
                got = want = None
            else:
                got, want = a.inside(s, v), b.inside(s, v)
            assert got == want
            x = now + float(rng.uniform(-2.0, 2.0))
            assert (a.near(x, x + 1.0), a.lam(x)) == (b.near(x, x + 1.0), b.lam(x))
            assert [(q.lo, q.c0, q.c1, q.rr, q.hi) for q in a.zones] == [(q.lo, q.c0, q.c1, q.rr, q.hi) for q in b.zones]
            assert (a._stop, a._hard) == (b._stop, b._hard)
    assert math.isinf(ShareZones(0.004)._hard)
