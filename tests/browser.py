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

__all__ = ["CLEAR", "By", "broken_words", "chromium", "first_screen", "in_view", "offered",
           "overlapping_labels", "resize", "small_texts", "status", "wait"]


def chromium(width: int = 1600, height: int = 1000) -> Iterator[Any]:
    """One headless Chromium whose page is that size (the window's inside, without its
    frame), quit when the fixture ends."""
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                f"--window-size={width},{height}", "--disable-gpu"):
        options.add_argument(arg)
    options.binary_location = CHROMIUM
    driver = webdriver.Chrome(options=options, service=Service(DRIVER))
    try:
        resize(driver, width, height)
        yield driver
    finally:
        driver.quit()


def resize(driver: Any, width: int, height: int) -> None:
    """Make the page (the window's inside) ``width`` x ``height`` pixels."""
    inner = driver.execute_script("return [outerWidth - innerWidth, outerHeight - innerHeight]")
    driver.set_window_size(width + inner[0], height + inner[1])


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


def in_view(driver: Any, selector: str) -> list[str]:
    """Why the first element that ``selector`` finds is not seen whole without scrolling
    (the page's or a box's it scrolls in); empty when it is."""
    return driver.execute_script("""
        const e = document.querySelector(arguments[0]);
        if (!e) return ['nothing matches ' + arguments[0]];
        const r = e.getBoundingClientRect(), why = [];
        if (!r.width || !r.height) why.push('not shown');
        if (r.left < 0 || r.top < 0 || r.right > innerWidth || r.bottom > innerHeight)
          why.push('outside the window: ' + JSON.stringify(r));
        for (let box = e.parentElement; box; box = box.parentElement) {
          const s = getComputedStyle(box);
          if (!/(auto|scroll|hidden)/.test(s.overflow + s.overflowX + s.overflowY)) continue;
          const b = box.getBoundingClientRect();
          if (r.left < b.left - 1 || r.top < b.top - 1 || r.right > b.right + 1 ||
              r.bottom > b.bottom + 1)
            why.push('scrolled out of ' + (box.id || box.className));
        }
        return why;""", selector)


def small_texts(driver: Any, least: float = 11) -> list[str]:
    """The texts shown smaller than ``least`` pixels at the page's zoom: an element's own
    text by its font size, a diagram's by its font size times the drawing's scale on
    screen, a question's picture by the caption's size (sim/png.py) times its scale."""
    from sim.png import caption_font_size

    return driver.execute_script("""
        const least = arguments[0], found = [];
        const shown = (e) => e.getClientRects().length > 0 &&
          getComputedStyle(e).visibility !== 'hidden';
        for (const e of document.querySelectorAll('body *')) {
          if (e.closest('svg') || e.tagName === 'OPTION' || !shown(e)) continue;
          const own = [...e.childNodes].filter(n => n.nodeType === 3 && n.textContent.trim());
          const px = parseFloat(getComputedStyle(e).fontSize);
          if (own.length && px < least)
            found.push(px.toFixed(1) + ' px: ' + e.textContent.slice(0, 40));
        }
        for (const t of document.querySelectorAll('svg text')) {
          if (!t.textContent.trim() || !shown(t)) continue;
          const px = parseFloat(getComputedStyle(t).fontSize) * t.getScreenCTM().a;
          if (px < least - 0.01) found.push(px.toFixed(1) + ' px in a drawing: ' + t.textContent);
        }
        return found;""", least) + [
        f"{size:.1f} px: the caption of {src}" for src, scale, height in driver.execute_script(
            "return [...document.querySelectorAll('.question img')].filter(i => i.naturalWidth)"
            ".map(i => [i.src, i.getBoundingClientRect().width / i.naturalWidth, i.naturalHeight])")
        if (size := scale * caption_font_size(height)) < least]


def broken_words(driver: Any) -> list[str]:
    """The words shown on two lines (``Robonaut-`` / ``B``): each word of each text of the
    page, measured as a range of its own."""
    return driver.execute_script("""
        const found = [], walk = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
        for (let n = walk.nextNode(); n; n = walk.nextNode()) {
          if (n.parentElement.closest('svg, option, script, style')) continue;
          for (const m of n.textContent.matchAll(/\\S+/g)) {
            const range = document.createRange();
            range.setStart(n, m.index); range.setEnd(n, m.index + m[0].length);
            const tops = new Set([...range.getClientRects()].map(r => Math.round(r.top)));
            if (tops.size > 1) found.push(m[0]);
          }
        }
        return found;""")


def first_screen(driver: Any, *selectors: str) -> dict[str, Any]:
    """Where the page's first screen falls short: each selector's element not seen whole
    without scrolling, texts under 11 px, words broken over two lines, the page taller
    than its window, and the errors in the browser's console since the last look."""
    # a diagram comes when the server has drawn it, a picture when it has loaded
    wait(lambda: all(driver.execute_script(
        "const e = document.querySelector(arguments[0]);"
        "return e !== null && (e.tagName !== 'IMG' || (e.complete && e.naturalWidth > 0))", s)
        for s in selectors), 30, f"the elements {selectors}")
    return {"hidden": {s: why for s in selectors if (why := in_view(driver, s))},
            "small": small_texts(driver), "broken": broken_words(driver),
            "taller": driver.execute_script(
                "return document.getElementById('screen').getBoundingClientRect().bottom"
                " - innerHeight"),
            "errors": [e["message"] for e in driver.get_log("browser")
                       if e["level"] == "SEVERE"]}


CLEAR = {"hidden": {}, "small": [], "broken": [], "taller": 0, "errors": []}
"""What :func:`first_screen` finds on a page that tells its story."""
