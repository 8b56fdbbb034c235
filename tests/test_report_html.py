"""hil report's interactive report.html: self-contained, titled from the trace's metadata, and in a
real browser (Debian chromium + chromedriver through selenium) it loads without console errors and
a zoom on one plot moves the x range of the linked time axes."""

import os
import re
import shutil
from pathlib import Path

import pytest

from hil.cli import main

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benches" / "lathe-2axis.toml"
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nG02 X30. Z-6. R3.\nM30\n"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    d = tmp_path_factory.mktemp("rh")
    (d / "p.nc").write_text(PROGRAM)
    assert main(["run", str(d / "p.nc"), "--bench", str(BENCH), "--trace", str(d / "run.parquet")]) == 0
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


def _driver():
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium not installed")
    chrome, drv = shutil.which("chromium"), shutil.which("chromedriver")
    if not chrome or not drv:
        pytest.skip("chromium / chromedriver not installed (apt-get install chromium chromium-driver)")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = chrome
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,1000"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(drv), options=opts)


def test_report_html_in_browser_zoom_links_axes(report):
    d = _driver()
    try:
        d.get(report.as_uri())
        assert d.execute_script("return document.querySelectorAll('.js-plotly-plot').length") == 2
        errors = [e for e in d.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
        d.save_screenshot(str(report.parent / "report.png"))
        d.execute_script("Plotly.relayout('time', {'xaxis.range': [0.1, 0.3]})")
        ranges = d.execute_script("var l=document.getElementById('time').layout;"
                                  "return [l.xaxis.range, l.xaxis4.range, l.xaxis7.range];")
        for r in ranges:  # shared x: the lowest plot (program line) follows the top one
            assert r == pytest.approx([0.1, 0.3])
        if os.environ.get("HIL_GUIDE_SHOTS"):  # HIL_GUIDE_SHOTS=1 refreshes the guide's screenshot
            d.save_screenshot(str(ROOT / "docs" / "guide" / "img" / "report-html.png"))
    finally:
        d.quit()
