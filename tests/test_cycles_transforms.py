"""Scaling G51, mirror G24/G51.1, rotation G68 (nc.transforms) — composition order, arc and
compensation side swap under mirror (A56–A58), through `hil path` where the interpreter applies them."""

from __future__ import annotations

import math

import pytest

from cycles_helpers import run
from nc.alarms import NcAlarm
from nc.transforms import TransformStack


def ends(r, line):
    return [(round(m["end"]["X"], 6), round(m["end"]["Y"], 6)) for m in r.moves if m["line"] == line]


def test_stack_order_mirror_scale_rotate_and_inverse():
    ts = TransformStack(mirror={"X": 10.0}, scale={"X": 2.0, "Y": 2.0}, scale_center={"X": 0.0, "Y": 0.0},
                        rot_angle=90.0, rot_center=(0.0, 0.0), rot_plane=("X", "Y"))
    p = {"X": 4.0, "Y": 1.0, "Z": 3.0}
    # mirror about X10 → (16, 1); scale ×2 → (32, 2); rotate +90° → (−2, 32)
    out = ts.apply(p)
    assert out["X"] == pytest.approx(-2.0) and out["Y"] == pytest.approx(32.0) and out["Z"] == 3.0
    back = ts.inverse(out)
    assert back["X"] == pytest.approx(4.0) and back["Y"] == pytest.approx(1.0)
    assert ts.reflected(("X", "Y"))
    ts.mirror["Y"] = 0.0
    assert not ts.reflected(("X", "Y"))  # two reflections: arcs keep their direction


def test_unequal_scaling_refuses_arcs():
    ts = TransformStack(scale={"X": 2.0}, scale_center={"X": 0.0})
    with pytest.raises(NcAlarm) as e:
        ts.check_arc(("X", "Y"))
    assert e.value.alarm.code == 0x025F


def test_mirror_swaps_arc_direction(capsys, tmp_path):
    prog = "G17 G21 G90 G94\nG00 X0. Y0. Z5.\nG24 X50.\nG01 X10. Y10. F100\nG02 X20. Y20. R10.\nG25 X50.\nM30\n"
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    assert r.code == 0, r.alarm
    assert ends(r, 4) == [(90.0, 10.0)]
    arc = [m for m in r.moves if m["line"] == 5][0]
    assert (arc["end"]["X"], arc["end"]["Y"]) == (80.0, 20.0)
    assert arc["dir"] == "ccw"  # G02 mirrored in one axis runs as G03 (A57)
    assert math.hypot(arc["end"]["X"] - arc["center"]["X"], arc["end"]["Y"] - arc["center"]["Y"]) == pytest.approx(10.0)


def test_rotation_and_scaling(capsys, tmp_path):
    prog = ("G17 G21 G90 G94\nG00 X0. Y0. Z5.\nG68 X0. Y0. R90.\nG01 X10. Y0. F100\nG69\n"
            "G51 X0. Y0. P2000\nG01 X10. Y5.\nG50\nG01 X10. Y5.\nM30\n")
    r = run(capsys, tmp_path, prog, profile="nc5-mill")
    assert r.code == 0, r.alarm
    assert ends(r, 4) == [(0.0, 10.0)]  # +90° about the origin (CCW positive)
    assert ends(r, 7) == [(20.0, 10.0)]  # P2000 = ×2.0 about X0 Y0
    assert ends(r, 9) == [(10.0, 5.0)]  # G50 cancels


def test_rotation_incremental_angle():
    class Host:
        class profile:
            axes = ("X", "Y", "Z")
            diameter_axes = ()

            @staticmethod
            def param(name, default=0.0):
                return default

        class state:
            plane = 17
            absolute = False

        @staticmethod
        def work_position():
            return {"X": 0.0, "Y": 0.0, "Z": 0.0}

        @staticmethod
        def distance(w, axis=None):
            return w.value

    from nc import transforms
    from nc.program.blocks import Block, Word

    h = Host()
    transforms.modal(h, "G68", Block(1, "G68 R30.", [Word("R", 30.0, "R30.", True)]))
    transforms.modal(h, "G68", Block(2, "G68 R15.", [Word("R", 15.0, "R15.", True)]))
    assert transforms.stack(h).rot_angle == pytest.approx(45.0)  # G91: angles add (A58)
    with pytest.raises(NcAlarm):
        transforms.modal(h, "G68", Block(3, "G68 R400.", [Word("R", 400.0, "R400.", True)]))
