"""The shipped lathe part program (G71 / G70 with G42 / G76) runs through `hil path` and draws."""

from __future__ import annotations

from pathlib import Path

import pytest

from cycles_helpers import distance_to, run, samples
from hil.cli import main
from nc.compensation.nose import tip_vector
from nc.cycles.geometry import Seg

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "lathe_part_g71_g70_g76.nc"

# the finished contour N100–N200 in (Z, X radius), chamfer X24 Z-3, R3 fillet
CONTOUR = [Seg((0.0, 9.0), (-3.0, 12.0)), Seg((-3.0, 12.0), (-25.0, 12.0)), Seg((-25.0, 12.0), (-25.0, 14.0)),
           Seg((-25.0, 14.0), (-35.0, 16.0)), Seg((-35.0, 16.0), (-38.0, 19.0), (-35.0, 19.0), True),
           Seg((-38.0, 19.0), (-50.0, 19.0)), Seg((-50.0, 19.0), (-50.0, 22.0))]


def test_example_part_program(capsys, tmp_path):
    r = run(capsys, tmp_path, EXAMPLE.read_text(), name=EXAMPLE.name)
    assert r.code == 0, r.alarm
    assert r.tagged("G71", "rough") and r.tagged("G71", "profile")
    fin = [m for m in r.tagged("G70", "finish") if "comp" in m["tags"] and m["kind"] != "rapid"]
    assert fin and {m["tip"] for m in fin} == {3} and {m["comp_radius"] for m in fin} == {0.8}
    tv = tip_vector(3, 0.8)
    for m in fin[1:]:  # after the start-up onto the face
        for z, x in samples(m, 16):
            assert distance_to(CONTOUR, (z - tv[0], x - tv[1])) == pytest.approx(0.8, abs=1e-6)
    threads = [m for m in r.tagged("G76") if m["kind"] == "thread" and "chamfer" not in m["tags"]]
    assert len({m["start_angle"] for m in threads}) == 1 and {m["lead"] for m in threads} == {2.0}
    assert min(m["end"]["X"] for m in threads) == pytest.approx(10.7)


def test_plot_png(capsys, tmp_path):
    out = tmp_path / "path.png"
    capsys.readouterr()
    assert main(["path", str(EXAMPLE), "--plot", str(out)]) == 0
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20000
    assert main(["path", str(EXAMPLE), "--plot", str(tmp_path / "no" / "dir" / "x.png")]) == 2
