"""`hil script`: a bad argument to the Machine API is the script's error, with its file and line (decision B80)."""

from __future__ import annotations

import pytest

from hil.cli import main

BAD_CALLS = [
    ("machine.wait(-1)", "machine.wait(-1): -1 is not a duration: simulated seconds, a finite number >= 0"),
    ("machine.wait(float('nan'))", "machine.wait(nan): nan is not a duration"),
    ("machine.wait(float('inf'))", "machine.wait(inf): inf is not a duration"),
    ("machine.wait('1')", "machine.wait('1'): '1' is not a duration"),
    ("machine.jog('Z', 1, -0.5)", "machine.jog('Z', 1, -0.5): -0.5 is not a duration"),
    ("machine.jog('Z', 0, 0.5)", "machine.jog: direction 0 must be 1 (+) or -1 (-)"),
    ("machine.jog('Z', 1, 0.5, percent=-20)", "machine.jog: percent -20 must be a whole number 0-100"),
    ("machine.mpg('X', 2.5)", "machine.mpg: pulses 2.5 must be a whole number of detents (+ or -)"),
    ("machine.mpg('X', 5, rate=float('nan'))", "MPG rate nan: detents per second must be > 0"),
    ("machine.inc('X', 1, units=-1000)", "machine.inc: units -1000 must be a whole number 0-4294967295"),
    ("machine.cycle(-3)", "machine.cycle: n -3 must be a whole number >= 0"),
    ("machine.wait_until(lambda: False, timeout=-1)", "machine.wait_until(…, timeout=-1): -1 is not a duration"),
    ("machine.home('X', timeout=0)", "machine.home('X', timeout=0): 0 is not a duration: simulated seconds, a finite number > 0"),
    ("machine.mdi('G01 X1 F100', timeout=float('inf'))", "machine.run_program(…, timeout=inf): inf is not a duration"),
    ("machine.spindle(float('nan'))", "machine.spindle: rpm nan must be a finite number"),
    ("machine.spindle_override(-5)", "machine.spindle_override: percent -5 must be a whole number 0-65535"),
    ("machine.set('D21006', float('nan'))", "machine.set('D21006', …): value nan must be a finite number"),
    ("machine.set('D21006', 2.5)", "machine.set('D21006', 2.5): the device holds an integer (u16)"),
    ("machine.set('D100', 7.25)", "machine.set('D100', 7.25): the device holds an integer (u16)"),
    ("machine.get('Q12')", "machine.get('Q12'): "),
    ("machine.pulse(21000, cycles=0)", "machine.pulse: cycles 0 must be a whole number >= 1"),
    ("machine.mode(3)", "machine.mode: mode 3 must be a string"),
]


@pytest.mark.parametrize("call,message", BAD_CALLS, ids=[c for c, _ in BAD_CALLS])
def test_a_bad_argument_is_refused_with_the_scripts_line(tmp_path, capsys, call, message):
    script = tmp_path / "bad.py"
    script.write_text(f"def main(machine):\n    machine.wait(0.01)\n    {call}\n    machine.wait(5)\n")
    code = main(["script", str(script)])
    out = capsys.readouterr()
    assert code == 1, out
    assert f"hil script: {script} at line 3: {message}" in out.err, out.err
    assert "Traceback" not in out.err + out.out and "alarms  none" in out.out  # the drives' report still prints


def test_good_arguments_still_run(tmp_path, capsys):
    # numpy numbers, a zero wait and whole floats where a duration is asked for are durations as before
    script = tmp_path / "good.py"
    script.write_text("import numpy as np\nmachine.wait(0)\nmachine.wait(np.float64(0.02))\n"
                      "machine.jog('Z', -1, 0.1, percent=np.int64(50))\nmachine.mpg('X', np.int32(10), ratio=10)\n"
                      "machine.cycle(0)\nprint('t', round(machine.time, 3))\n")
    code = main(["script", str(script)])
    out = capsys.readouterr()
    assert code == 0 and "Traceback" not in out.err, out
    x = next(ln for ln in out.out.splitlines() if ln.startswith("X ")).split()
    assert abs(float(x[3]) - float(x[1]) - 0.1) < 1e-6, x  # 10 detents × 10 × 0.001 mm


def test_machine_set_writes_an_f32_register_as_the_float_and_get_reads_it_back(tmp_path, capsys):
    """Decision B129: App. B's f32 pairs (D2x256 MLC axis target, D2x288 velocity) take the float in both words, as
    `hil run --at set` writes them; `machine.set` wrote int(value) into the first word (30.5 -> 30: the MLC axis read
    4.2e-44 mm) and `machine.get` read that word."""
    script = tmp_path / "f32.py"
    script.write_text("def main(machine):\n    machine.set('D21256', 30.5)\n    machine.set('D21288', -1200)\n"
                      "    print('read back', machine.get('D21256'), machine.get('D21288'), "
                      "machine.mlc.mem.f32(21256))\n")
    code = main(["script", str(script)])
    out = capsys.readouterr()
    assert code == 0, out
    assert "read back 30.5 -1200.0 30.5" in out.out, out.out
