"""M2x012 "Servo ON or OFF for all of connected servo drives in the corresponding channel" holds the channel's
spindle drive too (decision M23-2): OFF, the spindle drive is disabled once it stands; a spindle the program wants
turning while it is OFF is App. A 0x0C06 "The spindle is not enabled", and a turning one ramps down after the
channel's stop. Lathe bench (S1 a CiA 402 velocity-mode drive), `hil run --at`, read from the trace."""

from __future__ import annotations

import csv

import pytest

SIGNALS = "M31710,M31705"  # 1st Spindle Ready, 1st Spindle Zero Speed


def _enabled(sw: str) -> bool:
    return int(sw) & 0x6F == 0x27  # CiA 402 operation enabled


def _run(hil, tmp_path, program: str, *at: str):
    prog = tmp_path / "p.nc"
    prog.write_text(program)
    trace = tmp_path / f"p-{len(at)}.csv"
    args = [a for e in at for a in ("--at", e)]
    r = hil("run", str(prog), "--no-check", "--trace", str(trace), "--trace-signals", SIGNALS, *args)
    return r, list(csv.DictReader(trace.open()))


def test_servo_all_off_disables_the_standing_spindle_and_an_m03_of_it_is_0C06(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "G04 X0.2\nM03 S1000\nG04 X0.5\nM30\n", "cycle=1:set M21012=0")
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x0C06 axis S1 at line 2" in r.out and "M21012 OFF" in r.out and "result         STOPPED" in r.out
    # the spindle stood: disabled within the first cycles, M3x710 "ready" OFF; never turned
    assert all(not _enabled(row["S1_sw"]) and row["M31710"] == "0" for row in rows[20:])
    assert all(abs(float(row["S1_rpm_act"])) < 1.0 for row in rows)


def test_servo_all_off_while_the_spindle_turns_ramps_it_down_with_0C06_then_disables_it(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "M03 S1000\nG04 X2.\nM30\n", "t=1.0:set M21012=0")
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x0C06 axis S1 at line 2" in r.out
    k = next(i for i, row in enumerate(rows) if "0x0C06" in row["alarm"])
    assert float(rows[k]["S1_rpm_act"]) > 990.0  # turning at S1000 when the relay fell
    rpm = [abs(float(row["S1_rpm_act"])) for row in rows[k:]]
    assert sum(1 for v in rpm if v > 10.0) > 20  # ramped down over tens of cycles, not cut
    off = next(i for i, row in enumerate(rows) if i > k and not _enabled(row["S1_sw"]))
    assert abs(float(rows[off - 1]["S1_rpm_act"])) < 1.0  # disabled at zero speed, not before
    # no speed command from the relay's cycle on: down within 0.3 s, not at the 2 s dwell's end
    assert all(float(row["S1_rpm_cmd"]) == 0.0 for row in rows[k:]) and float(rows[off]["t"]) < 1.3
    assert all(not _enabled(row["S1_sw"]) for row in rows[off:])


def test_servo_all_back_on_enables_the_spindle_and_it_turns_as_without_the_relay(hil, tmp_path):
    program = "G04 X0.3\nM03 S1000\nG04 X0.5\nM05\nM30\n"
    r, rows = _run(hil, tmp_path, program, "cycle=1:set M21012=0", "t=0.2:set M21012=1")
    assert r.code == 0, r.out + r.err
    assert "alarms         none" in r.out
    assert any(not _enabled(row["S1_sw"]) for row in rows[10:200])
    back = next(i for i, row in enumerate(rows) if i > 10 and _enabled(row["S1_sw"]))
    assert 0.2 < float(rows[back]["t"]) < 0.21 and rows[back]["M31710"] == "1"
    assert max(float(row["S1_rpm_act"]) for row in rows) == pytest.approx(1000.0, abs=1.0)
