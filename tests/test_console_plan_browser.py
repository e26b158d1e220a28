"""A JAHRVIS shared plan in the operator console, in a real browser (headless Chromium).

One browser for the module.  stack-not-seen runs live behind the page, as fast as
the machine allows, started paused: the test sets a breakpoint on a task going
NOT_SEEN in Alice's view from the plan's panel, takes a screenshot there (the
robot's view says EXECUTED, Alice's NOT_SEEN), steps the clock until her next
action is under way and reports it done from the page, and runs to the end,
where the robot has told her and her view says EXECUTED.  The log is then
replayed with the slider.  Skipped, with the reason, where Chromium, its driver
or Selenium is missing.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from browser import By, chromium, status, wait  # skips this module without a browser
from selenium.webdriver.support.ui import Select

from shary.console.replay import Replay, named_schemes
from shary.console.server import serving
from shary.log.contextlog import read_events
from sim.cli import live_run
from sim.scenario import find_scenario

GREEN_PICK = "Pick(pr2, green_cube)"
GREEN_PLACE = "Place(pr2, green_cube, blue_cube_2)"
VIEWS = """
const out = {};
for (const row of shary.plan.rows.values()) {
  if (row.tr.hidden) continue;
  out[row.label] = Object.fromEntries([...row.cells].map(([v, c]) => [v, c.textContent]));
}
return out;
"""
"""Each task shown in the plan's table: its state per view, as the page shows it."""
KEY_ELEMENTS = [
    ".plan-table td.ps.NOT_SEEN", ".plan-table td.ps.EXECUTED", ".plan-table tr.option.chosen",
    '.plan-diagram g.est[data-state="not-seen"]', '.plan-diagram g.active[data-state="executed"]',
    ".plan-robot .head", ".recognized .rec.achieved", "#timeline rect.not-seen",
    "#timeline rect.recognized-achieved", "#plan-panel .chip", "#agents .agent", "#tree li"]
"""What the page shows at the NOT_SEEN breakpoint (the screenshot's moment)."""


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from chromium(1400, 1000)


def views(driver: Any) -> dict[str, dict[str, str]]:
    return driver.execute_script(VIEWS)


def set_break(driver: Any, state: str, view: str) -> None:
    """A breakpoint on a task state in one view, set from the plan's panel."""
    Select(driver.find_element(By.ID, "bp-state")).select_by_value(state)
    Select(driver.find_element(By.ID, "bp-view")).select_by_value(view)
    driver.find_element(By.ID, "bp-state-add").click()
    wait(lambda: f"{state} in {view}" in driver.find_element(By.CSS_SELECTOR,
                                                              "#plan-panel .chips").text,
         message="the breakpoint's chip")


def clear_break(driver: Any) -> None:
    driver.find_element(By.CSS_SELECTOR, "#plan-panel .chip").click()
    wait(lambda: not driver.find_elements(By.CSS_SELECTOR, "#plan-panel .chip"),
         message="the breakpoint cleared")


@pytest.fixture(scope="module")
def watched(browser: Any, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """stack-not-seen watched live (see the module's docstring); yields its folder, with
    the page's state at the breakpoint kept as ``window.atBreakpoint``."""
    out = tmp_path_factory.mktemp("not-seen")
    live = live_run(find_scenario("stack-not-seen"), out=out, speed=0, paused=True)
    with serving(live) as url:
        browser.get(url)
        wait(lambda: status(browser).startswith("paused"), message="paused at the start")
        operator = browser.find_element(By.ID, "operator")
        operator.clear()
        operator.send_keys("tester")
        if not browser.find_elements(By.ID, "bp-state"):  # the plan comes with the first steps
            browser.find_element(By.ID, "step").click()
        wait(lambda: browser.find_elements(By.CSS_SELECTOR, '#bp-view option[value="alice"]'),
             message="the plan's panel, with Alice's view")
        set_break(browser, "NOT_SEEN", "alice")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: "breakpoint NOT_SEEN" in status(browser), message="the breakpoint")
        wait(lambda: views(browser).get(GREEN_PICK, {}).get("alice") == "NOT_SEEN",
             message="NOT_SEEN in Alice's view")
        browser.execute_script(  # follow the task she missed: its states in the diagram
            "for (const r of shary.plan.rows.values()) if (r.label === arguments[0] && "
            "!r.tr.hidden) r.tr.querySelector('.label').click();", GREEN_PICK)
        wait(lambda: browser.find_elements(By.CSS_SELECTOR,
                                           '.plan-diagram g.est[data-state="not-seen"]'),
             message="the diagram, recoloured for the task followed")
        browser.execute_script("document.getElementById('plan-panel').scrollIntoView()")
        browser.save_screenshot(str(out / "at-not-seen.png"))
        browser.execute_script("window.atBreakpoint = arguments[0]", views(browser))
        browser.execute_script("window.present = arguments[0].filter("
                               "s => document.querySelector(s))", KEY_ELEMENTS)
        # step until her hand moves toward the stick (she is placing the blue cube on it),
        # and report that done from the page
        clear_break(browser)
        for _ in range(200):
            if "handMovingTowardstick" in browser.execute_script(
                    "return [...document.querySelectorAll('#facts tr')]"
                    ".map(r => r.textContent).join(' ')"):
                break
            browser.find_element(By.ID, "step").click()  # 0.1 s of the run
            time.sleep(0.15)
        else:
            raise AssertionError("her hand never moved toward the stick")
        report = wait(lambda: [b for b in browser.find_elements(By.CSS_SELECTOR,
                                                                "button.human-did")
                               if b.is_displayed()], message="the report button")
        assert len(report) == 1 and report[0].text == "done by alice"
        report[0].click()
        wait(lambda: "human-action" in browser.find_element(By.ID, "lines").text,
             message="the report, logged")
        assert not browser.find_element(By.ID, "reply").text  # not refused
        browser.find_element(By.ID, "resume").click()
        wait(lambda: status(browser) == "ended", message="the end of the run")
        yield out


def test_not_seen_in_her_view_then_executed_once_told(browser: Any, watched: Path):
    at_break = browser.execute_script("return window.atBreakpoint")
    assert at_break[GREEN_PICK] == {"pr2": "EXECUTED", "alice": "NOT_SEEN"}
    now = views(browser)
    assert now[GREEN_PICK] == {"pr2": "EXECUTED", "alice": "EXECUTED"}
    assert now[GREEN_PLACE] == {"pr2": "EXECUTED", "alice": "EXECUTED"}
    assert browser.find_element(By.ID, "verdict").text.startswith("PASSED")
    said = browser.find_element(By.CSS_SELECTOR, ".plan-robot .says").text
    assert said == "pr2 says “I placed the green cube on the blue cube on the stick.”"
    assert "d2: alice chose Pick(alice, blue_cube_2)" in browser.find_element(By.ID,
                                                                            "lines").text


def test_the_operator_actions_are_logged_with_who_did_them(watched: Path):
    events = read_events(watched / "log.sqlite")
    done = [(e.agent, e.data["action"]) for e in events if e.kind == "operator"]
    assert done[:2] == [("tester", "step"), ("tester", "breakpoint")] or \
        done[:1] == [("tester", "breakpoint")]
    assert [a for _, a in done].count("breakpoint") == 1
    assert ("tester", "human-action") in done and ("tester", "clear-breakpoint") in done
    reported = [e for e in events if e.kind == "recognition"
                and e.data.get("cause") == "reported by tester"]
    assert len(reported) == 1 and reported[0].agent == "alice"
    assert reported[0].data["state"] == "achieved"


def test_a_screenshot_at_the_breakpoint_shows_the_key_elements(browser: Any, watched: Path):
    from PIL import Image

    shot = Image.open(watched / "at-not-seen.png").convert("RGB")
    colours = {c for _, c in shot.getcolors(1_000_000)}
    assert (0x80, 0x7d, 0xba) in colours  # a NOT_SEEN cell (and the timeline's bar)
    assert (0xa1, 0xd9, 0x9b) in colours  # EXECUTED cells
    assert browser.execute_script("return window.present") == KEY_ELEMENTS


def test_an_undue_report_is_refused_and_said(browser: Any, watched: Path):
    task = browser.execute_script(
        "for (const [t, r] of shary.plan.rows) if (r.label === arguments[0]) return t;",
        GREEN_PICK)
    browser.execute_script("shary.ws.send(JSON.stringify({kind: 'human-action', by: 'tester',"
                           " agent: 'alice', plan_task: arguments[0], id: 7}))", task)
    wait(lambda: "refused" in browser.find_element(By.ID, "reply").text, message="refusal")
    assert "the run is over" in browser.find_element(By.ID, "reply").text


def test_replay_slider_shows_each_view_at_a_chosen_time(browser: Any, watched: Path):
    events = read_events(watched / "log.sqlite")
    unseen = min(e.time for e in events if e.kind == "plan-task"
                 and e.data["state"] == "NOT_SEEN")
    told = min(e.time for e in events if e.kind == "plan-task" and e.agent == "alice"
               and e.data["name"] == GREEN_PICK and e.data["state"] == "EXECUTED")
    with serving(Replay(watched / "log.sqlite", named_schemes())) as url:
        browser.get(url)
        wait(lambda: status(browser) == "replay", message="the replay")
        for at, alice in ((round((unseen + told) / 2, 1), "NOT_SEEN"),
                          (round(told + 0.5, 1), "EXECUTED")):
            browser.execute_script(
                "const s = document.getElementById('slider'); s.value = arguments[0];"
                "s.dispatchEvent(new Event('input'));", at)
            wait(lambda a=alice: views(browser).get(GREEN_PICK, {}).get("alice") == a,
                 message=f"Alice's view at {at} s")
            assert views(browser)[GREEN_PICK]["pr2"] == "EXECUTED"
