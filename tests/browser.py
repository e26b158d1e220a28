"""Headless Chromium for the console's browser tests (Debian's, driven by Selenium).

Importing this module skips the importing test module, with the reason, where
Selenium, Chromium or its driver is missing (``.ci/run`` installs them).  Each
module starts one browser (:func:`chromium`, from a module-scoped fixture):
starting Chromium costs seconds on a shared machine.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
webdriver = pytest.importorskip("selenium.webdriver",
                                reason="Selenium is not installed (pip install '.[test]')")
if not (Path(CHROMIUM).exists() and Path(DRIVER).exists()):
    pytest.skip("no headless browser: apt-get install chromium chromium-driver",
                allow_module_level=True)

from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402

__all__ = ["By", "chromium", "offered", "overlapping_labels", "status", "wait"]


def chromium(width: int = 1400, height: int = 1000) -> Iterator[Any]:
    """One headless Chromium with a window of that size, quit when the fixture ends."""
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                f"--window-size={width},{height}", "--disable-gpu"):
        options.add_argument(arg)
    options.binary_location = CHROMIUM
    driver = webdriver.Chrome(options=options, service=Service(DRIVER))
    try:
        yield driver
    finally:
        driver.quit()


def wait(what: Callable[[], Any], seconds: float = 90, message: str = "") -> Any:
    """``what()``'s first true value, asked every 50 ms; fails after ``seconds``."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        found = what()
        if found:
            return found
        time.sleep(0.05)
    raise AssertionError(f"waited {seconds} s in vain: {message}")


def status(driver: Any) -> str:
    """The page's status line (paused, running, ended …)."""
    return driver.find_element(By.ID, "status").text


def offered(driver: Any) -> list[str]:
    """The buttons a person could press now: shown and not disabled."""
    return driver.execute_script(
        "return [...document.querySelectorAll('button')]"
        ".filter(b => b.offsetParent !== null && !b.disabled).map(b => b.textContent)")


def overlapping_labels(driver: Any) -> list[list[str]]:
    """Pairs of the timeline's texts that cover each other, or a text and another item's
    bar it covers, by their boxes on the page (a pixel of slack)."""
    return driver.execute_script("""
        const boxes = [...document.querySelectorAll('#timeline text:not(.lane-name)')]
          .filter(t => t.textContent).map(t => [t, t.getBoundingClientRect()]);
        const bars = [...document.querySelectorAll('#timeline rect')]
          .map(r => [r, r.getBoundingClientRect()]);
        const meet = (a, b) => a.left < b.right - 1 && b.left < a.right - 1 &&
                               a.top < b.bottom - 1 && b.top < a.bottom - 1;
        const found = [];
        boxes.forEach(([t, a], i) => {
          for (const [u, b] of boxes.slice(i + 1)) if (meet(a, b))
            found.push([t.textContent, u.textContent]);
          for (const [r, b] of bars) if (r !== t.previousElementSibling && meet(a, b))
            found.push([t.textContent, 'the bar of ' + (r.textContent || r.getAttribute('class'))]);
        });
        return found;""")
