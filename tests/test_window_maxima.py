"""FilterCorners.window's sliding maxima (`_MaxQ`, decision bench B134) against the maxima taken outright: appends
at the back, drops at the front (with the lists' room given back), and the stretch growing backwards (push_front,
which the CAM program never reaches). Compiled, `_MaxQ`'s methods are C only, so this runs the module's source in a
child with DELTAHIL_PYTHON_PLANNER=1; the compiled class is held to the same setpoints by
tests/test_planner_compiled.py."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import nc.motion.compiled as compiled

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import random
from nc.motion.blending import _MaxQ
rng = random.Random(7)
for trial in range(40):
    vals = {}  # sequence number -> value, the stretch [lo, hi)
    q = _MaxQ()
    lo = hi = 1000
    falling = trial % 2 == 1  # values falling along the path: every one stays queued, the front's drops pile up
    for step in range(600):
        r = rng.random()
        if r < 0.5 or hi == lo:  # J advances: a new junction at the back
            x = 1e4 - step if falling else rng.choice([1.0, 2.0, 3.0, rng.random() * 4.0])
            vals[hi] = x
            q.push(hi, x)
            hi += 1
            q.drop(lo)
        elif r < 0.85:  # the stretch's start moves on
            lo += rng.randint(0, min(hi - lo - 1, 3))
            q.drop(lo)
        elif lo > 0:  # the stretch grows backwards by one junction older than all
            lo -= 1
            x = 2e4 if falling else rng.choice([1.0, 2.0, 3.0, rng.random() * 4.0])
            vals[lo] = x
            q.push_front(lo, x)
        want = max(vals[k] for k in range(lo, hi))
        assert q.front() == want, (trial, step, q.front(), want)
        assert q.seqs[q.head] >= lo
print("ok")
"""


def test_sliding_maxima_equal_the_maxima_over_the_stretch():
    env = dict(os.environ, **{compiled.ENV: "1"})
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "ok"
