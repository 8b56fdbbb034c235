"""Format rows of the manuals' chapters 2–3, written as the manual writes them (every optional word), each
run through `hil path --json` with the end point or state the row's description promises.

Rows are cited by id (docs/formats.md, `python docs/build_formats.py`): `N<section>-<k>` is the k-th row of
the NC5 G command guide's "Instruction format" tables under that section, `L<section>-<k>` the lathe guide's.
"""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import dataclass

import pytest

from lang_helpers import run_path
from tests.conftest import ROOT


@dataclass(frozen=True)
class FormatCase:
    rows: tuple[str, ...]
    program: str
    axes: str
    end: tuple[float, ...]  # the last move's work end point
    profile: str = "nc5-mill"
    machine: tuple[float, ...] | None = None  # the last move's machine end point, where offsets make it differ
    exact: tuple[bool, ...] | None = None  # exact stop (G09/G61) of the last moves


FORMAT_CASES = [
    FormatCase(("N3.3.1-1",), "G90 G00 X92. Y35. Z1.\nM30\n", "XYZ", (92.0, 35.0, 1.0)),
    FormatCase(("N3.3.3-1", "N3.3.3-2"), "G90 G00 X0 Y0\nG17 G02 X10. Y10. I10. J0 F100\nG03 X20. Y0 R10.\nM30\n",
               "XY", (20.0, 0.0)),
    FormatCase(("N3.3.3-3", "N3.3.3-4"), "G90 G00 X0 Z0\nG18 G02 X10. Z10. I0 K10. F100\nG03 X20. Z0 R10.\nM30\n",
               "XZ", (20.0, 0.0)),
    FormatCase(("N3.3.3-5", "N3.3.3-6"), "G90 G00 Y0 Z0\nG19 G02 Y10. Z10. J10. K0 F100\nG03 Y20. Z0 R10.\nM30\n",
               "YZ", (20.0, 0.0)),
    FormatCase(("N3.3.4-1", "N3.3.4-2"), "G90 G00 X0 Y0 Z0\nG2.4 X10. Y10. Z5. F300\nG2.4 X20. Y0 Z10.\nM30\n",
               "XYZ", (20.0, 0.0, 10.0)),
    FormatCase(("N3.3.4-3", "N3.3.4-4"), "G90 G00 X0 Y0 Z0\nG3.4 X10. Y10. Z5. F300\nG3.4 X20. Y0 Z10.\nM30\n",
               "XYZ", (20.0, 0.0, 10.0)),
    FormatCase(("N3.3.5-1", "N3.3.5-2"), "G90 G17 G00 X0 Y0\nG16 G01 X10. Y90. F100\nG15\nM30\n", "XY", (0.0, 10.0)),
    FormatCase(("N3.4.1-1",), "G90 G00 X0 Y0\nG09 G01 X10. Y5. F100\nX20.\nM30\n", "XY", (20.0, 5.0),
               exact=(True, False)),
    FormatCase(("N3.4.2-1", "N3.4.3-1"), "G90 G61\nG01 X10. F100\nX15.\nG64\nX20.\nM30\n", "X", (20.0,),
               exact=(True, True, False)),
    FormatCase(("N3.5.1-1", "N3.5.2-1"), "G90 G00 X10. Y10. Z0\nG28 X0 Y0\nG29 X30. Y20.\nM30\n", "XY", (30.0, 20.0)),
    FormatCase(("N3.5.4-1",), "G90 G00 X0 Y0\nG31 X50. F150. P1\nM30\n", "X", (50.0,)),
    FormatCase(("N3.6.1-1", "N3.6.1-2", "N3.6.1-3"),
               "G90 G00 X0 Y0 Z0\nG17 G01 X10. F100\nG18 G02 X20. Z0 R5.\nG19 G03 Y10. Z0 R5.\nM30\n", "XYZ",
               (20.0, 10.0, 0.0)),
    FormatCase(("N3.6.2-1",), "G10 L2 P1 X100. Y0\nG90 G54 G52 X5. Y5.\nG00 X0 Y0\nM30\n", "XY", (0.0, 0.0),
               machine=(105.0, 5.0)),
    FormatCase(("N3.6.3-1",), "G10 L2 P1 X100. Y50.\nG90 G54 G53 X10. Y10.\nM30\n", "XY", (-90.0, -40.0),
               machine=(10.0, 10.0), exact=(True,)),
    FormatCase(("N3.6.4-1",), "G10 L2 P1 X10. Y-1.\nG54\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(11.0, 1.0)),
    FormatCase(("N3.6.4-2",), "G10 L2 P2 X20. Y-2.\nG55\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(21.0, 0.0)),
    FormatCase(("N3.6.4-3",), "G10 L2 P3 X30. Y-3.\nG56\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(31.0, -1.0)),
    FormatCase(("N3.6.4-4",), "G10 L2 P4 X40. Y-4.\nG57\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(41.0, -2.0)),
    FormatCase(("N3.6.4-5",), "G10 L2 P5 X50. Y-5.\nG58\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(51.0, -3.0)),
    FormatCase(("N3.6.4-6",), "G10 L2 P6 X60. Y-6.\nG59\nG90 G00 X1. Y2.\nM30\n", "XY", (1.0, 2.0),
               machine=(61.0, -4.0)),
    FormatCase(("N3.6.5-1",), "G10 L20 P1 X7. Y-2.\nG54 P1\nG90 G00 X3. Y4.\nM30\n", "XY", (3.0, 4.0),
               machine=(10.0, 2.0)),
    FormatCase(("N3.6.6-1",), "G90 G00 X10. Y10.\nG92 X0 Y0\nG00 X5.\nM30\n", "X", (5.0,), machine=(15.0,)),
    FormatCase(("N3.7.1-1", "N3.7.2-1"), "G90 G00 X10.\nG91 G00 X5.\nM30\n", "X", (15.0,)),
    FormatCase(("N3.7.3-1",), "G20\nG90 G00 X1.\nM30\n", "X", (25.4,)),  # inch program, printed in mm
    FormatCase(("N3.7.3-2",), "G21\nG90 G00 X10.\nM30\n", "X", (10.0,)),
    FormatCase(("L2.1-1",), "G00 X20. Z5.\nG00 U10. W-5.\nM30\n", "XZ", (30.0, 0.0), "lathe-2018"),
    FormatCase(("L2.1-2",), "G00 X20. Z5.\nG01 U10. W-5. F100\nM30\n", "XZ", (30.0, 0.0), "lathe-2018"),
]


@pytest.mark.parametrize("case", FORMAT_CASES, ids=[c.rows[0] for c in FORMAT_CASES])
def test_format_row_runs_as_the_manual_writes_it(capsys, tmp_path, case: FormatCase):
    r = run_path(capsys, tmp_path, case.program, profile=case.profile)
    assert r.code == 0, (case.rows, r.alarm)
    assert r.moves and tuple(round(v, 6) for v in r.ends(*case.axes)[-1]) == case.end, case.rows
    if case.machine is not None:
        assert tuple(round(v, 6) for v in r.machine(*case.axes)[-1]) == case.machine, case.rows
    if case.exact is not None:
        assert tuple(bool(m.get("exact_stop")) for m in r.moves[-len(case.exact):]) == case.exact, case.rows


def _builder():
    spec = importlib.util.spec_from_file_location("build_formats", ROOT / "docs" / "build_formats.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["build_formats"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_formats_page_is_up_to_date_and_cites_only_real_rows():
    b = _builder()
    page = (ROOT / "docs" / "formats.md").read_text()
    if b.SEEDS.is_dir():
        assert page == b.build(), "docs/formats.md is stale: python docs/build_formats.py"
        ids = {r.id for r in b.manual_rows()}
    else:  # a clone without the manuals beside it (../shared/seeds): judge against the page's own rows
        rows = [line.split("|") for line in page.splitlines() if line.startswith(("| N", "| L"))]
        ids = {r[1].strip() for r in rows}
        marked = {r[1].strip() for r in rows if r[4].strip().startswith("`")}  # a test's name
        assert marked == set(b.tested_rows()), "docs/formats.md is stale: python docs/build_formats.py"
    assert not set(b.tested_rows()) - ids
    assert not set(b.unrun_rows()) - ids, "docs/formats-unrun.toml names a row the manuals do not have"


def test_every_format_row_is_run_by_a_test_or_says_why_not():
    """Issue 19: every G/M format row of chapters 2-3 of both manuals has a test (tests/test_formats*.py) or a
    reason in docs/formats-unrun.toml; the page (checked up to date above) lists none as untested."""
    page = (ROOT / "docs" / "formats.md").read_text()
    rows = [line.split("|") for line in page.splitlines() if line.startswith(("| N", "| L"))]
    untested = [r[1].strip() for r in rows if r[4].strip() == "untested"]
    assert not untested, f"format rows without a test or a reason: {untested}"
