"""NC → MLC status relays of App. B.2.2.1 a bench run publishes, read as an MLC reads them (the trace's device
columns, one row a cycle): M3x512… diameter/radius mode per axis slot (decision M21-3) and M3x035 axes auto
servo ON (decision M21-4), on the lathe and the mill bench."""

from __future__ import annotations

import csv

from tests.conftest import ROOT

SIGNALS = "M31512,M31513,M31514,M31035,M31036"


def _rows(hil, tmp_path, text: str, *bench: str) -> list[dict[str, str]]:
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    trace = tmp_path / "p.csv"
    r = hil("run", str(prog), *bench, "--trace", str(trace), "--trace-signals", SIGNALS)
    assert r.code == 0, r.out + r.err
    return list(csv.DictReader(trace.open()))


def test_lathe_x_is_in_diameter_mode_z_is_not(hil, tmp_path):
    rows = _rows(hil, tmp_path, "G98 G01 X40. Z90. F3000\nM30\n")
    # the lathe's X (axis slot 1) is programmed in diameter (N2.001 Bit10 = 0) from the first scan on; Z (slot 2) not
    assert all(r["M31512"] == "1" for r in rows)
    assert all(r["M31513"] == "0" and r["M31514"] == "0" for r in rows)


def test_mill_has_no_diameter_axis(hil, tmp_path):
    rows = _rows(hil, tmp_path, "G90 G01 X10. F3000\nM30\n", "--bench", str(ROOT / "benches" / "mill-3axis.toml"))
    assert all(r["M31512"] == "0" and r["M31513"] == "0" and r["M31514"] == "0" for r in rows)


def test_auto_servo_on_rises_with_system_ready_after_power_up(hil, tmp_path):
    rows = _rows(hil, tmp_path, "G98 G01 X40. Z90. F3000\nM30\n")
    on35 = [r["M31035"] == "1" for r in rows]
    on36 = [r["M31036"] == "1" for r in rows]
    # OFF while the drives power up, ON in the same scan as "system ready and servo ON", and with it
    # every cycle after (the bench's power-up is the NC's auto servo ON: N1.10 = 0)
    assert not on35[0] and any(on35)
    assert on35 == on36
    first = on35.index(True)
    program = [i for i, r in enumerate(rows) if r["line"] == "1"]
    assert program and first <= program[0]  # ON by the first cycle of the program


def test_per_axis_relays_count_the_lathe_axes_in_order():
    """Decision M21-3: the 16-wide families index the channel's axis slots. On the lathe (X, Z) Z is slot 2: JOG+
    M21385 moves Z (the relay App. B's default letters call the Y axis's), M21386 moves nothing."""
    from hil.bench import default_lathe
    from hil.scripting import Machine

    m = Machine(default_lathe())
    try:
        m.power_up()
        m.mode("JOG")
        x0, z0 = m.position("X"), m.position("Z")
        m.set("M21386", 1)
        m.wait(0.3)
        m.set("M21386", 0)
        m.settle()
        assert m.position("X") == x0 and m.position("Z") == z0
        m.set("M21385", 1)
        m.wait(0.3)
        m.set("M21385", 0)
        m.settle()
        assert m.position("X") == x0 and m.position("Z") > z0 + 1.0
        assert m.get("M31464") == 0 and m.get("M31465") == 0  # standing again: "moving" OFF for X and Z
    finally:
        m.close()
