"""The thread-phase check counts a pass and its chamfer pull-out as one pass."""

from __future__ import annotations


def test_g76_with_chamfer_passes_the_phase_check(hil, program, tmp_path):
    prog = program("G21 G18 G99\nS800 M03\nG00 X28. Z5.\nG76 P021060 Q100 R0.05\n"
                   "G76 X21.4 Z-22. P1300 Q400 F2.\nG00 X60. Z20.\nM30\n")
    path = hil("path", prog, "--json").json_lines()
    chamfers = [m for m in path if m["kind"] == "thread" and "chamfer" in m.get("tags", [])]
    assert chamfers  # the program really pulls out with a chamfer on every pass
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--trace", trace)
    assert r.code == 0, r.out + r.err
    r = hil("check", trace, "--program", prog, "--thread-phase", "0.5")
    assert r.code == 0, r.out
    assert "ok    thread phase" in r.out
