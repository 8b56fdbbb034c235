"""An alarm, a reset or a feed hold in the middle of a canned cycle stops the axes within their limits (decision
motion 63). Found by stopping a G76 thread cycle with `--max-time` at times spread over the run: 7 of 160 stops
broke the bench's limits — the thread's stop cut at its block's end (acceleration ×3.5, jerk ×77), its stop
started at a = 0 in the thread's ramp, a hold on the cycle's return rapid that ran on round the 90° corner into
the infeed at 110 mm/s (X at ×2 its acceleration, 0.12 mm off the path), a stop in the cycle a thread chain
changed blocks froze the axes at 27 mm/s, a stop while braking hard at low speed backed up along the path."""

from __future__ import annotations

import contextlib
import io

import pytest

import hil
from tests.conftest import ROOT

LATHE = str(ROOT / "benches" / "lathe-2axis.toml")
G76 = "G97 S800 M03\nG00 X28. Z5.\nG76 P011060 Q50 R0.05\nG76 X21.4 Z-22. P1300 Q400 F2.\nG00 X60. Z50.\nM05\nM30\n"


def _failed(tmp_path, program: str, bench: str, **kwargs) -> list[str]:
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    with contextlib.redirect_stdout(io.StringIO()):
        r = hil.run(str(prog), bench, check=True, **kwargs)
    return [str(c) for c in r.checks if not c.ok and not getattr(c, "skipped", False)]


# the stops that broke a limit before: in the ramp (2.5661), in a thread pass near its pull-out corner (3.5164,
# 6.8059, 11.7767: cut at the block's end, then braked through the corner), in the cycle the chain entered its
# pull-out (16.7095: the planner looked at rest, the axes froze at 27 mm/s), on the return rapid (3.8088, 7.3907,
# 10.6802: round the corner into the infeed; 18.7076: braking hard at low speed, the stop backed up the path)
@pytest.mark.parametrize("at", [2.5661, 3.5164, 3.8088, 6.8059, 7.3907, 10.6802, 11.7767, 16.7095, 18.7076])
def test_an_alarm_in_a_g76_cycle_stops_within_the_limits(tmp_path, at):
    assert _failed(tmp_path, G76, LATHE, max_time=at) == []
