"""Subprogram calls on the bench: `hil run` takes files of several O programs and `--lib DIR|FILE`
like `hil path`, so M98 / G65 resolve when the program runs through the virtual bus."""

from __future__ import annotations

import re


def final_position(out: str) -> dict[str, float]:
    m = re.search(r"final machine position\s+(.*)", out)
    assert m, out
    vals = m.group(1).split()
    return {vals[i]: float(vals[i + 1]) for i in range(0, len(vals), 2)}


def test_run_subprogram_in_same_file(hil, tmp_path):
    f = tmp_path / "main.nc"
    f.write_text("O0001\nG98 G00 X20. Z2.\nM98 P0002\nM30\nO0002\nG01 X30. Z-5. F3000\nM99\n")
    r = hil("run", f)
    assert r.code == 0, r.out + r.err
    assert "alarms         none" in r.out
    pos = final_position(r.out)
    assert abs(pos["X"] - 15.0) < 0.01 and abs(pos["Z"] - (-5.0)) < 0.01  # X radius in machine coords


def test_run_lib_file_g65_and_nested_m98(hil, tmp_path):
    lib = tmp_path / "lib.nc"
    lib.write_text("O0100\nG65 P0101 A36.\nM99\nO0101\nG01 X#1 Z-#1 F3000\nM99\n")
    f = tmp_path / "m.nc"
    f.write_text("G98 G00 X20. Z2.\nM98 P0100\nM30\n")
    r = hil("run", f, "--lib", lib)
    assert r.code == 0, r.out + r.err
    pos = final_position(r.out)
    assert abs(pos["X"] - 18.0) < 0.01 and abs(pos["Z"] - (-36.0)) < 0.01


def test_run_lib_folder_nc5_search_order(hil, tmp_path):
    root = tmp_path / "disk"
    (root / "GLOBAL" / "O_MACRO").mkdir(parents=True)
    (root / "PATH_1").mkdir()
    (root / "GLOBAL" / "O_MACRO" / "O0200.NC").write_text("O0200\nG01 X10. Z-1. F3000\nM99\n")
    (root / "PATH_1" / "O0200").write_text("O0200\nG01 X24. Z-2. F3000\nM99\n")  # found first
    f = tmp_path / "m.nc"
    f.write_text("G98 G00 X20. Z2.\nM98 P0200\nM30\n")
    r = hil("run", f, "--lib", root)
    assert r.code == 0, r.out + r.err
    pos = final_position(r.out)
    assert abs(pos["X"] - 12.0) < 0.01 and abs(pos["Z"] - (-2.0)) < 0.01


def test_run_missing_subprogram_alarm_and_bad_lib(hil, tmp_path):
    f = tmp_path / "m.nc"
    f.write_text("G98 G00 X20. Z2.\nM98 P0300\nM30\n")
    r = hil("run", f)
    assert r.code == 1
    assert "0x0263" in r.out and "line 2" in r.out
    r = hil("run", f, "--lib", tmp_path / "nope")
    assert r.code == 2 and "no such file or folder" in r.err
