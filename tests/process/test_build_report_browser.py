"""The report opens in headless Chromium from disk, with the network closed: no console
errors, the slider changes the layer shown, and a screenshot is not blank.

Needs Debian's ``chromium`` and ``chromium-driver`` (``make test`` and ``.ci/run`` install
them when ``/usr/bin/chromium`` is missing) and ``selenium`` (the ``test`` extra). Without
them the test skips with the reason, except in CI (``CI`` set), where it fails.
"""

from __future__ import annotations

import io
import os
import shutil

import numpy as np
import pytest

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--window-size=1400,1800"]


def _need(what: str):
    msg = f"browser test cannot run: {what}"
    print(msg)
    if os.environ.get("CI"):
        pytest.fail(msg + " (CI must run it: .ci/run installs chromium and chromium-driver)")
    pytest.skip(msg)


@pytest.fixture(scope="module")
def coil_report(coil_build):
    """The report of the session's coil build (tests/conftest.py)."""
    assert coil_build.code == 0, coil_build.stderr
    return coil_build.out / "report.html"


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _need("selenium is not installed (pip install -e '.[test]')")
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver_path = shutil.which("chromedriver")
    if not chromium or not driver_path:
        _need("chromium / chromedriver not found (apt-get install -y chromium chromium-driver)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = chromium
    for f in CHROMIUM_FLAGS:
        opts.add_argument(f)
    opts.add_argument(f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    drv = webdriver.Chrome(service=Service(executable_path=driver_path), options=opts)
    drv.set_page_load_timeout(60)
    try:
        yield drv
    finally:
        drv.quit()


def _png_array(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def test_build_report_in_headless_chromium(browser, coil_report):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    html = coil_report.read_text(encoding="utf-8")
    assert "http://" not in html.replace("http://www.w3.org", "") and "https://" not in html  # nothing to fetch
    browser.get(coil_report.as_uri())
    assert browser.execute_script("return document.readyState") == "complete"
    assert "coil sensor" in browser.title
    slider = browser.find_element(By.ID, "layerSlider")
    img = browser.find_element(By.ID, "layerImg")
    first_layer, first_src = img.get_attribute("data-layer"), img.get_attribute("src")
    assert first_layer == "0" and first_src.startswith("data:image/png;base64,")
    assert browser.execute_script("return arguments[0].naturalWidth", img) > 100
    label0 = browser.find_element(By.ID, "layerLabel").text
    slider.click()
    slider.send_keys(Keys.HOME)
    for _ in range(9):
        slider.send_keys(Keys.ARROW_RIGHT)
    assert img.get_attribute("data-layer") == "9"
    assert img.get_attribute("src") != first_src
    assert browser.find_element(By.ID, "layerLabel").text != label0
    passes = browser.find_element(By.ID, "passTable").text
    assert "silver" in passes and "plaster" in passes and "flash heat" in passes
    assert len(browser.find_elements(By.CSS_SELECTOR, "#prints img")) == 4  # 2 materials x 2 inks in layer 9
    shot = _png_array(browser.get_screenshot_as_png())
    assert shot.std() > 10 and len(np.unique(shot.reshape(-1, 3), axis=0)) > 50
    layer = _png_array(img.screenshot_as_png)
    assert len(np.unique(layer.reshape(-1, 3), axis=0)) >= 3  # background and two materials at least
    errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert errors == [], errors
