"""``prima live``'s figures: how long a typed line takes to come back heard, how smoothly
the page draws, and whether the run keeps real time, with two applications at 1x.

Starts ``prima live`` on applications alone (FA1 beside EA1, the museum) at real time,
opens its page in headless Chromium (Debian's ``chromium`` and ``chromium-driver``,
through Selenium), and types N lines (default 50) into the page, one every 1.5 s of
wall time, each "Hey robot!" (FA1's name: it answers). Measured in the page, with its
own clock (``performance.now()``): from the Enter of each line to the arrival of its
``hear`` decision; the page's frame rate (``requestAnimationFrame`` calls per second)
over the whole run; and, from the server's status, how far the run's simulated time
fell behind the wall clock at its worst (the session measures it at each point where
the simulator could wait: a run that keeps real time is never more than a few
milliseconds behind). ``--screenshot FILE`` keeps a picture of the page at the
end (the docs' ``docs/live-*.png`` are made so).

    python bench/live.py [--actions 50] [--speed 1] [--screenshot docs/live-museum.png]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
APPS = [ROOT / "apps" / "fa" / "fa1-emotions.pxml", ROOT / "apps" / "ea" / "ea1-museum.pxml"]


def _browser() -> object:
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = shutil.which("chromium") or "chromium"
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1400,1000"):
        options.add_argument(argument)
    return webdriver.Chrome(options=options,
                            service=Service(shutil.which("chromedriver") or "chromedriver"))


def _wait(driver: object, script: str, timeout: float = 60.0) -> object:
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout, poll_frequency=0.02).until(
        lambda d: d.execute_script(script))


def _step(driver: object, seconds: float, times: int) -> None:
    """Paused, let the run go ``seconds`` further, ``times`` times (the page's Step)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    Select(driver.find_element(By.ID, "step-by")).select_by_value(f"{seconds:g}")  # type: ignore[attr-defined]
    for _ in range(times):
        clock = driver.execute_script("return window.primaLive.status().clock")  # type: ignore[attr-defined]
        driver.find_element(By.ID, "step").click()  # type: ignore[attr-defined]
        _wait(driver, f"const s = window.primaLive.status(); return s.idle && "
                      f"s.clock >= {clock} + {seconds} - 1e-6")


def picture(path: str) -> None:
    """The docs' picture: the museum visit of the tests (FA1 beside EA1, the visitor's
    walk and answers scripted), without the turn to the user before the robot speaks
    (``--policy connect-channel=off``: the judge finds it talking unfaced), the visitor's
    question typed over the guide's explanation, and the guide's answer under way."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    visit = ROOT / "tests" / "data" / "live" / "museum-visit.xml"
    process = subprocess.Popen(
        [sys.executable, "-m", "prima", "live", str(visit), "--script", "--paused",
         "--policy", "connect-channel=off", "--port", "0"], cwd=ROOT, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None
    url = process.stdout.readline().split()[2]
    driver = _browser()
    try:
        driver.get(url)  # type: ignore[attr-defined]
        _wait(driver, "return window.primaLive.ready() && window.primaLive.status()")
        _step(driver, 5, 6)
        _step(driver, 1, 4)
        driver.find_element(By.ID, "say").send_keys(  # type: ignore[attr-defined]
            "Excuse me, where is the toilet?" + Keys.ENTER)
        _step(driver, 0.5, 4)
        _wait(driver, "return window.primaLive.frames() > 0")
        time.sleep(1.5)  # (the page draws its latest timeline and findings)
        driver.save_screenshot(path)  # type: ignore[attr-defined]
    finally:
        driver.quit()  # type: ignore[attr-defined]
        process.terminate()
        process.communicate(timeout=60)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--actions", type=int, default=50)
    parser.add_argument("--speed", type=float, default=1.0)
    parser.add_argument("--every", type=float, default=1.5,
                        help="wall seconds between two typed lines (default 1.5)")
    parser.add_argument("--screenshot", metavar="FILE")
    parser.add_argument("--picture", metavar="FILE",
                        help="only make the docs' picture of the page (see picture())")
    args = parser.parse_args()
    if args.picture:
        picture(args.picture)
        return 0
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    process = subprocess.Popen(
        [sys.executable, "-m", "prima", "live", *map(str, APPS), "--port", "0", "--speed",
         str(args.speed)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None
    url = process.stdout.readline().split()[2]
    driver = _browser()
    try:
        driver.get(url)  # type: ignore[attr-defined]
        _wait(driver, "return window.primaLive.ready() && window.primaLive.status() && "
                      "!window.primaLive.status().paused")
        begun = time.monotonic()
        frames0 = driver.execute_script("return window.primaLive.frames()")  # type: ignore[attr-defined]
        box = driver.find_element(By.ID, "say")  # type: ignore[attr-defined]
        for k in range(args.actions):
            box.send_keys("Hey robot!" + Keys.ENTER)
            _wait(driver, f"return window.primaLive.heard().length > {k}")
            time.sleep(max(0.0, begun + (k + 1) * args.every - time.monotonic()))
        wall = time.monotonic() - begun
        frames = driver.execute_script("return window.primaLive.frames()") - frames0  # type: ignore[attr-defined]
        status = driver.execute_script("return window.primaLive.status()")  # type: ignore[attr-defined]
        said = driver.execute_script("return window.primaLive.said()")  # type: ignore[attr-defined]
        heard = driver.execute_script("return window.primaLive.heard()")  # type: ignore[attr-defined]
        if args.screenshot:
            driver.save_screenshot(args.screenshot)  # type: ignore[attr-defined]
    finally:
        driver.quit()  # type: ignore[attr-defined]
        process.terminate()
        process.communicate(timeout=60)
    if len(heard) != len(said):
        print(f"bench/live.py: {len(said)} lines typed, {len(heard)} heard", file=sys.stderr)
        return 1
    latencies = sorted(h["at"] - s for s, h in zip(said, heard, strict=True))
    median = statistics.median(latencies)
    print(f"prima live, FA1 + EA1 at {args.speed:g}x: {args.actions} typed lines, "
          f"{wall:.1f} s of wall time")
    print(f"  typed line -> its hear decision on the page: median {median:.1f} ms, "
          f"p90 {latencies[int(0.9 * (len(latencies) - 1))]:.1f} ms, max {latencies[-1]:.1f} ms")
    print(f"  the page's frame rate: {frames / wall:.1f} frames a second")
    print(f"  the run behind the wall clock (x{args.speed:g}): at most "
          f"{status['behind'] * 1000:.1f} ms of simulated time; more than 50 ms at "
          f"{status['late']} of the {status['points']} points where it could wait, in "
          f"{status['clock']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
