"""Headless Debian chromium through selenium + chromedriver, for the report and scope tests; the
test skips with the reason when either is missing (CI installs them, .ci/run)."""

import shutil

import pytest


def chromium_driver():
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


def console_errors(driver) -> list:
    return [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
