"""Headless Chromium for the tests that open a page PRIMA writes (``prima show``): the
Debian package and its driver, through Selenium; the test is skipped without them."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from typing import Any

import pytest

CHROMIUM, CHROMEDRIVER = shutil.which("chromium"), shutil.which("chromedriver")


def headless_chromium(*extra: str) -> Iterator[Any]:
    """A headless Chromium driver (1400 x 1000, the browser's log kept) with these
    arguments besides the usual ones, quit when the generator is closed."""
    if not (CHROMIUM and CHROMEDRIVER):
        pytest.skip("Chromium and its driver are not installed (apt-get install chromium "
                    "chromium-driver; .ci/run does)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = CHROMIUM
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1400,1000", *extra):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
    try:
        yield driver
    finally:
        driver.quit()


WAIT = 300.0
"""Seconds :func:`until` waits at most: a bound against a page that never gets there,
not a speed it must keep (a loaded machine only makes the wait longer)."""


def until(driver: Any, script: str, *args: Any) -> Any:
    """What ``script`` (JavaScript, run in the page) returns once it is truthy: the page
    loaded, a sound's data read, a redraw done. Waits for the page, not for a time."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, WAIT, poll_frequency=0.05).until(
        lambda d: d.execute_script(script, *args))


STEPPED_CLOCK = """
const frames = [];
window.primaShow.useClock(function (callback) { frames.push(callback); });
window.stepClock = function (stamp) {
  frames.splice(0).forEach(function (callback) { callback(stamp); });
};
"""
"""Hands the page's clock (prima/show/player.js: its animation frames) to the test:
``stepClock(ms)`` runs the frames due with that time stamp, so playing for 600 ms is two
steps, ``stepClock(0)`` and ``stepClock(600)``, however long the machine takes."""
