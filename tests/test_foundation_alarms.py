"""Issue 2: bad input gives a Delta alarm with line and block, a non-zero exit, and no traceback."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("text, code, line", [
    ("G00 X10.\nG01 X10. Q\n", "0x0222", 2),  # address without a value
    ("G00 X10.\nG01 X10. $5\n", "0x0206", 2),  # character that is no address
    ("G00 X10.\nG01 \u0386X10.\n", "0x0206", 2),  # a non-ASCII letter is no address either
    ("G00 X1.\nG01 O100.\n", "0x0201", 2),  # O inside a block (NC5 App. A example)
    ("G98\nG01 Z-10.\n", "0x1001", 2),  # no feed programmed
    ("G98 G00 X0 Z0\nG02 X100. Z0. R10. F100\n", "0x0259", 2),  # radius smaller than half the chord
    ("G98 G00 X0 Z0\nG02 X20. Z-20. I5. K0. F100\n", "0x025A", 2),  # end not on the circle
    ("G00 G01 X1.\n", "0x0202", 1),  # two group-01 codes in one block
    ("G123 X1.\n", "0x021D", 1),  # unsupported G code
    ("M3 M8 M9 M5 M30\n", "0x0248", 1),  # more than 4 M codes
    ("G04 P1.5\n", "0x0258", 1),  # decimal point in G04 P
])
def test_malformed_programs_raise_their_delta_alarm(hil, program, text, code, line):
    p = program(text)
    r = hil("path", p, "--json")
    assert r.code == 1
    alarm = r.json_lines()[-1]
    assert alarm["kind"] == "alarm"
    assert alarm["code"] == code
    assert alarm["line"] == line
    assert alarm["block"] == text.splitlines()[line - 1]
    assert alarm["message"]
    assert "Traceback" not in r.out + r.err


def test_missing_program_file(hil, tmp_path):
    r = hil("path", tmp_path / "nope.nc", "--json")
    assert r.code == 1
    assert r.json_lines()[-1]["code"] == "0x0002"


def test_run_on_malformed_program_refuses_to_start(hil, program, tmp_path):
    p = program("G98\nG00 X100. Z50.\nG01 X80. Q\n")
    trace = tmp_path / "t.csv"
    r = hil("run", p, "--trace", trace)
    assert r.code == 1
    assert "0x0222" in r.err and "line 3" in r.err
    assert not trace.exists()  # nothing written, nothing moved


def test_run_stops_under_control_at_an_impossible_arc(hil, program, tmp_path):
    p = program("G98\nG00 X100. Z50.\nG02 X0. Z50. R10. F300\n")
    trace = tmp_path / "t.csv"
    r = hil("run", p, "--trace", trace)
    assert r.code == 1
    assert "0x0259" in r.out
    assert "line 3" in r.out
    assert "Traceback" not in r.out + r.err
    # The bad block is found by read-ahead: the axes stop under control somewhere on block 2's
    # straight path from (X60, Z100) to (X50, Z50) and stand still; nothing heads toward block 3.
    import csv
    rows = list(csv.DictReader(open(trace)))
    for row in rows:
        x, z = float(row["X_cmd"]), float(row["Z_cmd"])
        assert 50.0 - 1e-6 <= x <= 60.0 + 1e-6 and 50.0 - 1e-6 <= z <= 100.0 + 1e-6
        # on the G00 line, to within one drive count per axis (X 5 mm, Z 10 mm per 1 280 000 counts)
        assert abs((x - 60.0) * 50.0 - (z - 100.0) * 10.0) <= 50.0 * 5.0 / 1_280_000 + 10.0 * 10.0 / 1_280_000
    last = rows[-1]
    assert abs(float(last["X_vel"])) < 0.01 and abs(float(last["Z_vel"])) < 0.01


def test_unknown_bus_is_a_usage_error(hil, program):
    p = program("G00 X1.\n")
    r = hil("run", p, "--bus", "token-ring")
    assert r.code == 2
    assert "unknown bus" in r.err
