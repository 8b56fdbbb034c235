"""Spindle ↔ C axis (M66/M77, lathe P358/P359) and M19 orientation through `hil run`:
the spindle drive's mode of operation goes CSV (9) → CSP (8) → CSV, shown by M3x709 which
follows the drive's 0x6061 mode display, and the C position lands on the spindle's angle."""

from __future__ import annotations

import csv

from tests.conftest import ROOT

BENCH = str(ROOT / "benches" / "lathe-c-axis.toml")


def _run(hil, tmp_path, text: str, signals: str):
    prog, trace = tmp_path / "p.nc", tmp_path / "t.csv"
    prog.write_text(text)
    r = hil("run", str(prog), "--bench", BENCH, "--trace", str(trace),
            "--trace-signals", signals)
    assert r.code == 0, r.out + r.err
    return list(csv.DictReader(trace.open()))


def _edges(rows, col):
    return [(i, rows[i][col]) for i in range(1, len(rows)) if rows[i][col] != rows[i - 1][col]]


def _angle_error(angle: float, want: float) -> float:
    return abs((angle - want + 180.0) % 360.0 - 180.0)


def test_m66_c_axis_positioning_then_m77_spins_again(hil, tmp_path):
    rows = _run(hil, tmp_path, "O1\nM03 S600\nG04 X0.5\nM66\nG00 C90.\nM77\nM03 S600\nG04 X0.5\nM05\nM30\n",
                "M31709,M2239,M21708")
    mode = _edges(rows, "M31709")
    assert [v for _, v in mode] == ["1", "0"]  # drive mode 9 → 8 → 9, once
    up, down = mode[0][0], mode[1][0]
    assert float(rows[up]["S1_rpm_act"]) < 1.0  # M05 came first: stopped before CSP
    done = _edges(rows, "M2239")
    assert [v for _, v in done] == ["1", "0"] and up < done[0][0] < done[1][0] <= down
    c_start = next(i for i in range(len(rows)) if float(rows[i]["C_cmd"]) > 0.0)
    assert c_start > done[0][0]  # C moves only after the switch is finished
    at = rows[down - 1]  # last cycle in C mode
    assert abs(float(at["C_act"]) - 90.0) <= 0.01
    assert _angle_error(float(at["S1_angle"]), 90.0) <= 0.01  # the spindle is the C axis
    assert max(float(r["S1_rpm_act"]) for r in rows[down:]) > 599.0  # spins again in CSV


def test_m66_without_index_runs_m29_first(hil, tmp_path):
    rows = _run(hil, tmp_path, "O2\nM66\nG00 C45.\nM77\nM30\n", "M31709,M2239")
    mode = _edges(rows, "M31709")
    assert [v for _, v in mode] == ["1", "0"]
    assert max(float(r["S1_rpm_act"]) for r in rows[: mode[0][0]]) > 10.0  # index search in CSV
    at = rows[mode[1][0] - 1]
    assert _angle_error(float(at["S1_angle"]), 45.0) <= 0.01


def test_m19_orients_at_the_index(hil, tmp_path):
    rows = _run(hil, tmp_path, "O3\nM03 S900\nG04 X0.3\nM19\nG04 X0.1\nM20\nM30\n", "M31706,M31709")
    reached = _edges(rows, "M31706")
    assert [v for _, v in reached] == ["1", "0"]
    for i in range(reached[0][0], reached[1][0]):
        assert _angle_error(float(rows[i]["S1_angle"]), 0.0) <= 0.01
        assert rows[i]["M31709"] == "1"
    assert rows[-1]["M31709"] == "0"  # M20: back to CSV
