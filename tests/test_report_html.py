"""hil report's interactive report.html: self-contained, titled from the trace's metadata, and in a
real browser (Debian chromium + chromedriver through selenium) it loads without console errors and
a zoom on one plot moves the x range of the linked time axes."""

import os
import re
from pathlib import Path

import numpy as np
import pytest

from hil.cli import main
from tests.browser_helpers import chromium_driver, console_errors

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benches" / "lathe-2axis.toml"
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nG02 X30. Z-6. R3.\nM30\n"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    d = tmp_path_factory.mktemp("rh")
    (d / "p.nc").write_text(PROGRAM)
    assert main(["run", str(d / "p.nc"), "--bench", str(BENCH), "--trace", str(d / "run.parquet"),
                 "--trace-signals", "M_STROBE,S_STROBE,T_STROBE,MST_FINISH,M_CODE,S_CODE,T_CODE"]) == 0
    assert main(["report", str(d / "run.parquet"), "--out", str(d / "rep"), "--bench", str(BENCH)]) == 0
    return d / "rep" / "report.html"


def test_report_html_is_self_contained_and_titled(report):
    page = report.read_text()
    assert "<script src=\"http" not in page and "plotly.js" in page.lower()  # JS embedded: opens offline
    assert "p.nc" in page and "bench lathe-2axis" in page and "deltahil " in page
    for name in ("following error", "velocity", "acceleration", "jerk", "spindle", "cycle jitter",
                 "program line", "contour error magnified"):
        assert name in page
    # the figures are JSON in the page: undo its escapes of "/" and non-ASCII before reading the units
    page = re.sub(r"\\u([0-9a-fA-F]{4})", lambda m: chr(int(m.group(1), 16)), page).replace("\\/", "/")
    for unit in ("µm", "mm/s", "mm/s²", "mm/s³", "rpm", "µs", "time (s)"):  # units on every axis
        assert unit in page
    assert "Interactive report" in (report.parent / "index.html").read_text()


def test_report_html_in_browser_zoom_links_axes(report):
    d = chromium_driver()
    try:
        d.get(report.as_uri())
        assert d.execute_script("return document.querySelectorAll('.js-plotly-plot').length") == 2
        assert console_errors(d) == []
        d.save_screenshot(str(report.parent / "report.png"))
        d.execute_script("Plotly.relayout('time', {'xaxis.range': [0.1, 0.3]})")
        ranges = d.execute_script("var l=document.getElementById('time').layout;"
                                  "return [l.xaxis.range, l.xaxis4.range, l.xaxis7.range, l.xaxis8.range];")
        for r in ranges:  # shared x: the lowest plot (program line) follows the top one
            assert r == pytest.approx([0.1, 0.3])
        if os.environ.get("HIL_GUIDE_SHOTS"):  # HIL_GUIDE_SHOTS=1 refreshes the guide's screenshot
            d.save_screenshot(str(ROOT / "docs" / "guide" / "img" / "report-html.png"))
        # the M/S/T lane: M03 and S600 strobed at power-up of the program, each answered by the MLC
        lane = d.execute_script("return document.getElementById('time').data.filter(t => t.name && "
                                "t.name.endsWith(' handshake')).map(t => [t.name, t.x, t.text]);")
        by = {name: (x, text) for name, x, text in lane}
        assert set(by) == {"M handshake", "S handshake"}
        mx, mtext = by["M handshake"]
        assert mtext[0].startswith("M3") and mx[1] > mx[0] and "answered after" in mtext[1]
        assert by["S handshake"][1][0].startswith("S600") and by["S handshake"][0][1] > by["S handshake"][0][0]
    finally:
        d.quit()


def test_circular_test_on_known_deviation():
    """An actual path 2 µm oval (cos 2θ) about a 10 mm circle: G = 4 µm, F = ±2 µm; not for a line."""
    from hil.circular_test import full_circles

    th = np.linspace(0, 2 * np.pi, 2000)
    r_act = 10.0 + 0.002 * np.cos(2 * th)
    cols = {"line": np.full(th.size, 7), "X_cmd": 5 + 10 * np.cos(th), "Y_cmd": 10 * np.sin(th),
            "X_act": 5 + r_act * np.cos(th), "Y_act": r_act * np.sin(th)}
    (c,) = full_circles(cols, ("X", "Y"))
    assert c.line == 7 and c.radius == pytest.approx(10.0) and c.centre == pytest.approx((5.0, 0.0), abs=1e-9)
    assert c.G == pytest.approx(0.004, rel=1e-3) and (c.F_min, c.F_max) == pytest.approx((-0.002, 0.002), rel=1e-3)
    cols["Y_cmd"] = cols["Y_act"] = np.zeros(th.size)
    assert full_circles(cols, ("X", "Y")) == []


def test_report_html_full_circle_gets_iso_230_4(tmp_path):
    (tmp_path / "c.nc").write_text("G90 G17\nG00 X10. Y0.\nG01 X20. F3000.\nG02 I-10. J0. F3000.\nG00 X0. Y0.\nM30\n")
    mill = ROOT / "benches" / "mill-3axis.toml"
    assert main(["run", str(tmp_path / "c.nc"), "--bench", str(mill), "--trace", str(tmp_path / "c.parquet")]) == 0
    assert main(["report", str(tmp_path / "c.parquet"), "--out", str(tmp_path / "r"), "--bench", str(mill)]) == 0
    m = re.search(r"ISO 230-4 circular test, line 4: R ([\d.]+) mm .*circular deviation G ([\d.]+) µm",
                  (tmp_path / "r" / "report.html").read_text())
    assert m and float(m.group(1)) == pytest.approx(10.0, abs=0.01) and 0 < float(m.group(2)) < 20


def test_report_without_html_for_campaigns(report, tmp_path):
    """`hil campaign --no-report-html`: the PNG report only, no report.html and no link to one."""
    from hil.report import write_report

    rep = write_report(report.parent.parent / "run.parquet", tmp_path / "r", interactive=False)
    assert rep.interactive is None and not (tmp_path / "r" / "report.html").exists()
    page = (tmp_path / "r" / "index.html").read_text()
    assert "report.html" not in page and "<img" in page


def test_circular_hysteresis_when_the_circle_is_run_both_ways():
    """ISO 230-4 H: the same 10 mm circle CCW (actual +1 µm) then CW (actual −2 µm + 1 µm cos θ):
    H is the largest radius difference at one angle, 4 µm at θ = 0; one direction alone gives no H."""
    from hil.circular_test import format_circular, full_circles, hysteresis

    th = np.linspace(0, 2 * np.pi, 2000)
    back = th[::-1]
    r1, r2 = 10.001 + 0 * th, 9.998 + 0.001 * np.cos(back)
    cols = {"line": np.r_[np.full(th.size, 7), np.full(th.size, 9)],
            "X_cmd": np.r_[10 * np.cos(th), 10 * np.cos(back)], "Y_cmd": np.r_[10 * np.sin(th), 10 * np.sin(back)],
            "X_act": np.r_[r1 * np.cos(th), r2 * np.cos(back)], "Y_act": np.r_[r1 * np.sin(th), r2 * np.sin(back)]}
    tests = full_circles(cols, ("X", "Y"))
    assert [t.direction for t in tests] == [1, -1]
    ((a, b, h),) = hysteresis(tests)
    assert (a, b) == (7, 9) and h == pytest.approx(0.004, abs=2e-5)
    assert "ISO 230-4 circular hysteresis, lines 7 and 9: H 4.00 µm" in format_circular(tests)
    assert hysteresis(tests[:1]) == [] and "hysteresis" not in format_circular(tests[:1])
