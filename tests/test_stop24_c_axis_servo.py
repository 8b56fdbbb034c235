"""M2x012 OFF while the spindle is the C axis (M66, a position axis of the channel): the C axis is held as any axis
of the channel (decision M24-2, as M22-1/M23-1), not as a spindle (M23-2's speed hold): a C move under way stops
along the path, jerk-limited, App. A 0x0A07 names C, and its drive is disabled once C stands; no spindle alarm
0x0C06 (the spindle does not turn in C mode). Lathe bench with a C axis, `hil run --at`, read from the trace."""

from __future__ import annotations

import csv
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)
PROGRAM = "G98 G00 X100. Z10.\nM66\nG00 X30. C0.\nG01 C270. F3000.\nG04 X1.\nM30\n"


def test_servo_all_off_during_a_c_move_stops_c_along_the_path_with_0A07_then_disables_it(hil, tmp_path):
    prog = tmp_path / "c.nc"
    prog.write_text(PROGRAM)
    trace = tmp_path / "c.csv"
    r = hil("run", str(prog), "--bench", str(ROOT / "benches" / "lathe-c-axis.toml"), "--no-check", "--trace",
            str(trace), "--at", "t=5.0:set M21012=0")
    rows = list(csv.DictReader(trace.open()))
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x0A07 axis C at line 4" in r.out and "0x0C06" not in r.out, r.out
    k = next(i for i, row in enumerate(rows) if row["alarm"])
    assert float(rows[k]["t"]) == 5.0 and float(rows[k]["C_vel"]) > 45.0  # C at its 50 °/s when the relay fell
    c = [float(row["C_cmd"]) for row in rows[k:]]
    steps = [b - a for a, b in zip(c, c[1:])]
    # (the last row's command is the disabled drive's actual position, within its encoder's resolution)
    stand = next(i for i in range(len(steps)) if all(abs(t) < 1e-4 for t in steps[i:]))
    assert 20 < stand < 300  # braked over tens of cycles (jerk-limited), not cut, and not run on to C270
    assert all(s >= 0.0 for s in steps[:stand]) and max(steps) <= steps[0] + 1e-9  # no reversal, never faster
    assert c[-1] < 60.0
    assert int(rows[-1]["C_sw"]) & 0x6F != OP_ENABLED and int(rows[k + stand]["C_sw"]) & 0x6F == OP_ENABLED
