"""The operator console on a distributed team, in a real browser (headless Chromium).

``shary team up weld-human-supports-robot --console``: every agent its own
process, the page served from the managers' process.  Stopped by a breakpoint
at K-10's question, the page offers only what the managers can do: each member
marked "own process", IVA answering "from their own interface" (no answer
buttons), no control, teleoperation, breakpoint or SHARY-task cancel buttons for
the robots; the team task's cancel (the Task Manager's) stays.  The Facts panel
shows the site as the world perceives it.  Skipped, with the reason, where
Chromium, its driver or Selenium is missing (``.ci/run`` installs them).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from browser import By, chromium, wait  # skips this module without a browser
from test_console_distributed import Page, _team_up


def test_the_page_offers_only_what_the_managers_can_do(tmp_path: Path) -> None:
    def look(page: Page) -> None:
        assert page.send("breakpoint", act="question")["ok"]
        for driver in chromium(1400, 1000):
            _at_the_question(driver, page.http)
        assert page.send("clear-breakpoint", act="question")["ok"]
        assert page.send("resume")["ok"]
        page.read(lambda: page.status.get("state") == "ended", timeout=120)

    status, err = _team_up("weld-human-supports-robot", tmp_path / "logs", look)
    assert status == 0, err


def _at_the_question(driver: Any, address: str) -> None:
    driver.get(address + "/")
    question = wait(lambda: driver.find_elements(By.CSS_SELECTOR, ".team-question"), 120,
                    "K-10's question on the page")[0]
    wait(lambda: "paused" in driver.find_element(By.ID, "status").text, 30, "paused")
    assert "Is this seam okay?" in question.text
    assert "IVA answers from their own interface" in question.text
    assert not question.find_elements(By.CSS_SELECTOR, "button")
    for name in ("K-10", "Robonaut-B", "IVA"):
        block = driver.find_element(By.CSS_SELECTOR, f'.team-agent[data-agent="{name}"]')
        assert "own process" in block.text, name
    notes = [e.text for e in driver.find_elements(By.CSS_SELECTOR, ".robot-controls")]
    assert len(notes) == 2 and all("runs in its own process" in n for n in notes)
    shown = [b.text for b in driver.find_elements(By.TAG_NAME, "button") if b.is_displayed()
             and b.text in ("take control", "hand back", "breakpoint", "teleoperate",
                            "cancel", "yes", "no")]
    assert shown == ["cancel"]  # the running team task's, in the Task Manager's table
    assert driver.find_element(By.CSS_SELECTOR, "#team-tasks button").text == "cancel"
    facts = driver.find_element(By.ID, "facts").text
    assert "verdict" in facts and "welded" in facts
