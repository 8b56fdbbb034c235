"""`hil script`, `hil mpg` and `hil spindle` stopped by a signal (issue 17, bench decision B96): as `hil run` is (B9),
the motion is brought to rest under control — the operator's RESET with the jog keys let go: the spindle ramps down,
a jog or MPG move stops jerk-limited — the drives are disabled only at standstill, the drives' report is printed and
`hil` exits 128 + n. They used to drop everything where it was: a KeyboardInterrupt through the script, no report,
the drives never commanded off (on a field bus: enabled, the spindle turning, until the bus watchdog cut in).

In process, lock-step: a watcher the script adds records every cycle (the shutdown's too) and sends the signal
at a known simulated time."""

from __future__ import annotations

import json
import signal
from pathlib import Path

import numpy as np
import pytest

OP_ENABLED = 0x27  # statusword & 0x6F (CiA 402)

SCRIPT = '''
import json, os, signal

def main(machine, log, sig, what):
    sent = []
    out = open(log, "w", buffering=1)

    def watch(m):
        i = {"spindle": len(m.runner.axes), "jog": 1, "mpg": 1}[what]
        out.write(json.dumps([m.time, m.runner.tx[i].velocity_actual * m.runner.scales[i].drive_to_velocity(1)
                              if what != "spindle" else m.get_rpm(), m.runner.tx[i].statusword]) + "\\n")
        if m.time >= 1.5 and not sent:
            sent.append(m.time)
            os.kill(os.getpid(), getattr(signal, sig))

    machine.watchers.append(watch)
    if what == "spindle":
        machine.spindle(1000)
        machine.wait(100)
    elif what == "jog":
        machine.jog("Z", -1, 100)
    else:
        machine.mpg("Z", -20000, ratio=100, rate=200)
'''


def _rows(log: Path) -> np.ndarray:
    return np.array([json.loads(line) for line in log.read_text().splitlines()])


@pytest.mark.parametrize("what", ["spindle", "jog", "mpg"])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_a_signal_stops_a_script_under_control(tmp_path, capsys, what, sig):
    from hil.cli import main

    script = tmp_path / "s.py"
    script.write_text(SCRIPT)
    log = tmp_path / "log.jsonl"
    code = main(["script", str(script), str(log), sig.name, what])
    out, err = capsys.readouterr()
    assert code == 128 + sig, out + err
    assert f"stopped by {sig.name}" in err and "Traceback" not in err
    assert "alarms" in out and (what != "spindle" or "now      0.0 rpm" in out)  # the report, at rest
    rows = _rows(log)
    t, v, sw = rows[:, 0], rows[:, 1], rows[:, 2].astype(int)
    assert np.abs(v[t < 1.5]).max() > 1.0  # it was moving when the signal came
    enabled = (sw & 0x6F) == OP_ENABLED
    off = int(np.flatnonzero(enabled)[-1]) + 1
    assert off < len(sw) and not enabled[off:].any()  # disabled, and stays so
    assert abs(v[off - 1]) < 0.01  # only at standstill
    dv = np.abs(np.diff(v[t >= 1.5]))
    assert dv.max() < 0.2 * np.abs(v[t < 1.5]).max()  # a ramp, no step to zero


@pytest.mark.parametrize("argv", [["spindle", "1000", "--seconds", "100"],
                                  ["mpg", "Z", "-20000", "--ratio", "100", "--rate", "200"]], ids=lambda a: a[0])
def test_hil_spindle_and_mpg_stopped_by_a_signal_ramp_down(monkeypatch, capsys, argv):
    """`hil spindle 1000 --seconds 100` / `hil mpg Z -20000` and SIGTERM at 1.5 s: the spindle ramps down, the
    handwheel move stops jerk-limited, before the drive is disabled."""
    import os

    from hil.cli import main
    from hil.scripting import Machine

    rows: list[tuple[float, float, int]] = []
    real_power_up = Machine.power_up
    i = -1 if argv[0] == "spindle" else 1

    def power_up(self):
        real_power_up(self)

        def watch(m):
            tx = m.runner.tx[i]
            v = m.get_rpm() if argv[0] == "spindle" else m.runner.scales[i].drive_to_velocity(tx.velocity_actual)
            rows.append((m.time, v, tx.statusword))
            if m.time >= 1.5 and not getattr(m, "_sent", False):
                m._sent = True
                os.kill(os.getpid(), signal.SIGTERM)

        self.watchers.append(watch)

    monkeypatch.setattr(Machine, "power_up", power_up)
    assert main(argv) == 143
    err = capsys.readouterr().err
    assert f"hil {argv[0]}: stopped by SIGTERM" in err and "Traceback" not in err
    a = np.array(rows)
    t, v, sw = a[:, 0], a[:, 1], a[:, 2].astype(int)
    enabled = (sw & 0x6F) == OP_ENABLED
    off = int(np.flatnonzero(enabled)[-1]) + 1
    top = np.abs(v[t < 1.5]).max()
    assert top > 10 and abs(v[off - 1]) < 0.01 and not enabled[off:].any()
    assert np.abs(np.diff(v[t >= 1.5])).max() < 0.2 * top  # a ramp, no step


def test_two_signals_at_once_disable_the_script_s_drives_at_once(tmp_path, capsys):
    """Two Ctrl-C in the same cycle (before the script saw the first): the second's KeyboardInterrupt used to leave
    the drives enabled; now they are disabled at once (B9), `hil: interrupted`, exit 130."""
    from hil.cli import main

    script = tmp_path / "s.py"
    script.write_text(SCRIPT.replace("os.kill(os.getpid(), getattr(signal, sig))",
                                     "os.kill(os.getpid(), signal.SIGINT); os.kill(os.getpid(), signal.SIGINT)"))
    log = tmp_path / "log.jsonl"
    assert main(["script", str(script), str(log), "SIGINT", "spindle"]) == 130
    assert "interrupted" in capsys.readouterr().err
    sw = _rows(log)[:, 2].astype(int)
    assert (sw[-1] & 0x6F) != OP_ENABLED
