"""What a `hil run` imports (issue 17: the user times the whole process, imports included): the scipy.special
package (≈ 0.17 s) is not imported for the corner blends' Fresnel integrals, whose values stay scipy's."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _python(code: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


def test_the_blends_fresnel_integrals_are_scipys_without_importing_scipy_special():
    code = ("import sys, numpy as np; from nc.motion.clothoid import fresnel; "
            "before = 'scipy.special' in sys.modules; "
            "x = np.concatenate([np.linspace(-40, 40, 100001), [0.0, 5e-324, 1e-300, 1e300, np.inf, -np.inf]]); "
            "s, c = fresnel(x); "
            "import scipy.special as sp; s2, c2 = sp.fresnel(x); "
            "same = lambda a, b: np.array_equal(a, b, equal_nan=True); "  # 1e300: nan from both
            "print(before, same(s, s2), same(c, c2), fresnel is sp.fresnel)")
    assert _python(code) == ["False", "True", "True", "True"]


def test_a_run_with_blends_and_a_parquet_trace_does_not_import_scipy_special(tmp_path):
    trace = tmp_path / "t.parquet"
    code = ("import sys; from hil.cli import main; import nc.motion.clothoid as c; calls = []; f = c.fresnel; "
            "c.fresnel = lambda x: calls.append(1) or f(x); "  # counted: the demo's corners are blended
            f"rc = main(['run', 'examples/lathe_demo.nc', '--trace', {str(trace)!r}]); "
            "print(rc, len(calls) > 0, 'scipy.special' in sys.modules)")
    out = _python(code)
    assert out[-3:] == ["0", "True", "False"]
    assert trace.stat().st_size > 0
