"""Blocks that switch scaling, mirror or rotation on carry the centre in their axis words: no motion."""

from __future__ import annotations

PROGRAM = """G17 G90 G00 X0 Y0 Z0
G68 X10. Y0. R90.
G01 X20. Y0. F1000
G69
G51 X0. Y0. P2.
G01 X5. Y5.
G50
G24 X50.
G01 X40. Y0.
G25 X0
M30
"""


def test_transform_blocks_do_not_move_and_the_next_move_is_transformed(hil, program):
    moves = hil("path", program(PROGRAM), "--profile", "nc5-mill", "--json").json_lines()
    assert [m["line"] for m in moves] == [1, 3, 6, 9]  # lines 2, 5, 8 and 10 set centres only
    ends = {m["line"]: (m["end"]["X"], m["end"]["Y"]) for m in moves}
    assert ends[3] == (10.0, 10.0)  # (20, 0) rotated 90 degrees about (10, 0)
    assert ends[9] == (60.0, 0.0)  # (40, 0) mirrored about X50
