"""The operator console on an HRI/OS team, in a real browser (headless Chromium, Selenium).

One browser and one live run for the module: weld-question-expires on its
PyBullet site, as fast as the machine allows, started paused.  Unanswered,
IVA (away) lets K-10's "Is this seam okay?" expire, it falls back to "no" and
the weld is respawned (the scenario's expectation, which tests/test_weld.py
checks).  Here the operator breaks on the question, answers "yes" for IVA
from the page, then takes control of K-10 for IVA, teleoperates it, hands it
back: the weld is not respawned.  Skipped, with the reason, where Chromium,
its driver or Selenium is missing (``.ci/run`` installs them).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from browser import (  # skips this module without a browser
    By,
    chromium,
    offered,
    overlapping_labels,
    status,
    wait,
)
from selenium.webdriver.support.ui import Select

from shary.console.server import serving
from shary.log.contextlog import read_events
from sim.cli import live_run
from sim.scenario import find_scenario

MEMBERS = ["K-10", "Robonaut-B", "IVA", "SRA", "CM"]


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from chromium(1400, 1100)


def text(driver: Any, element: str) -> str:
    return driver.find_element(By.ID, element).text


def robot(driver: Any, name: str, selector: str) -> Any:
    return driver.find_element(By.CSS_SELECTOR, f'.team-agent[data-agent="{name}"] {selector}')


def facts(driver: Any, name: str) -> str:
    return robot(driver, name, ".team-facts").text


@pytest.fixture(scope="module")
def steered(browser: Any, tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """The run, steered from the page; yields what the page showed on the way."""
    out = tmp_path_factory.mktemp("question-expires")
    seen: dict[str, Any] = {"out": out}
    live = live_run(find_scenario("weld-question-expires"), out=out, speed=0, paused=True)
    with serving(live) as url:
        browser.get(url)
        wait(lambda: len(browser.find_elements(By.CSS_SELECTOR, ".team-agent")) == 5,
             message="a block per member")
        seen["blocks"] = browser.execute_script(
            "return [...document.querySelectorAll('#agents .agent')].map(a => [a.dataset.agent,"
            " a.querySelector('.team-agent').className])")
        seen["tasks"] = text(browser, "team-tasks")
        browser.find_element(By.ID, "operator").clear()
        browser.find_element(By.ID, "operator").send_keys("tester")
        # control authority, paused at the start: for IVA, take K-10, aim it, hand it back
        Select(robot(browser, "K-10", "select.person")).select_by_value("IVA")
        robot(browser, "K-10", "button.team-act:nth-of-type(1)").click()
        wait(lambda: "take-control" in text(browser, "lines"), message="logged")
        browser.find_element(By.ID, "step").click()  # TAKE-CONTROL is a message: it goes
        wait(lambda: "driven by IVA" in facts(browser, "K-10"), message="user mode")
        Select(robot(browser, "K-10", "select.atomic")).select_by_value("aim")
        robot(browser, "K-10", 'input[name="target"]').send_keys("P1-P2")
        robot(browser, "K-10", "button.team-act:last-of-type").click()
        wait(lambda: "aim P1-P2" in text(browser, "lines"), message="the teleoperated aim")
        for _ in range(100):  # step the clock until the aim is over
            if browser.execute_script("return [...shary.items.keys()].some(k => "
                                      "k.startsWith('xK-10/t') && !shary.open.has(k))"):
                break
            browser.find_element(By.ID, "step").click()
            time.sleep(0.05)
        robot(browser, "K-10", "button.team-act:nth-of-type(2)").click()
        wait(lambda: "hand-back" in text(browser, "lines"), message="logged")
        browser.find_element(By.ID, "step").click()
        wait(lambda: "mode: system" in facts(browser, "K-10"), message="handed back")
        # then break on the question, and answer it for IVA
        browser.find_element(By.ID, "bp-act").send_keys("question")
        browser.find_element(By.ID, "bp-add").click()
        wait(lambda: browser.find_elements(By.CSS_SELECTOR, "#breakpoints .chip"),
             message="the breakpoint's chip")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: "breakpoint question" in status(browser), message="the question")
        yes = wait(lambda: browser.find_elements(
            By.CSS_SELECTOR, '.team-question[data-agent="IVA"] button[data-text="yes"]'),
            message="the question, put to IVA")
        wait(lambda: browser.execute_script(
            "const i = document.querySelector('.team-question img');"
            "return i && i.complete && i.naturalWidth > 0"), message="K-10's picture")
        seen["image"] = browser.execute_script(
            "return document.querySelector('.team-question img').naturalWidth")
        seen["questions"] = text(browser, "team-questions")
        qid = browser.execute_script(  # its id (the order of the run's messages makes it)
            "return document.querySelector('.team-question').dataset.question")
        browser.save_screenshot(str(out / "at-the-question.png"))
        yes[0].click()
        wait(lambda: "answer for_agent=IVA" in text(browser, "lines"), message="logged")
        browser.find_element(By.ID, "step").click()  # the answer goes out with the clock
        wait(lambda: f"answers {qid}" in text(browser, "lines"), message="IVA's answer")
        seen["lines"] = text(browser, "lines")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: status(browser) == "ended", message="the end of the run")
        seen["verdict"] = text(browser, "verdict")
        seen["final tasks"] = text(browser, "team-tasks")
        seen["events"] = list(read_events(out / "log.sqlite"))
    yield seen


def test_the_page_has_a_block_per_agent_and_the_task_table(steered: dict):
    assert [name for name, _ in steered["blocks"]] == MEMBERS
    assert [kind.split()[-1] for _, kind in steered["blocks"]] == [
        "robot", "robot", "human", "software", "software"]
    assert "weld-P2-P3" in steered["tasks"] and "inspect-P2-P3" in steered["tasks"]


def test_the_question_shows_with_its_picture_priority_and_expiry(steered: dict):
    assert steered["image"] == 480  # K-10's camera picture, served from the run's folder
    line = steered["questions"]
    assert "Is this seam okay?" in line and "priority 5" in line and "IVA" in line
    assert "expires in 20.0 s" in line  # paused at the question: simulated time stands


def test_an_answer_from_the_page_reaches_the_robot_and_changes_the_outcome(steered: dict):
    events = steered["events"]
    answers = [(e.agent, e.data.get("value")) for e in events if e.kind == "answer"]
    assert answers == [("IVA", "yes")]  # unanswered, it expires and falls back to "no"
    assert not [e for e in events if e.kind == "respawn"]  # … which respawns the weld
    operator = [e.data["action"] for e in events if e.kind == "operator" and e.agent == "tester"]
    assert operator[-5:] == ["breakpoint", "resume", "answer", "step", "resume"]
    assert "respawn" in steered["verdict"] and steered["verdict"].startswith("FAILED")
    assert "inspect-P2-P3" in steered["final tasks"]
    assert "done" in steered["final tasks"] and "respawned" not in steered["final tasks"]


def test_take_control_teleoperate_and_hand_back_from_the_page(steered: dict):
    events = steered["events"]
    control = [(e.agent, e.data["mode"], e.data["by"]) for e in events if e.kind == "control"]
    assert control == [("K-10", "user", "IVA"), ("K-10", "system", "IVA")]
    teleop = [e for e in events if e.kind == "exec-request" and e.data.get("by") == "IVA"]
    assert [(e.data["atomic"], e.data["args"]) for e in teleop] == [("aim", {"target": "P1-P2"})]
    done = [e for e in events if e.kind == "exec-result" and e.data["request"] ==
            teleop[0].data["request"]]
    assert done and done[0].data["status"] == "done"
    operator = [e.data["action"] for e in events if e.kind == "operator" and e.agent == "tester"]
    assert operator[:3] == ["take-control", "step", "teleoperate"]
    assert "hand-back" in operator
    lines = steered["lines"]
    assert "user mode, driven by IVA" in lines and "system mode (handed back by IVA)" in lines


def test_a_screenshot_at_the_question_shows_the_key_elements(steered: dict):
    from PIL import Image

    shot = Image.open(steered["out"] / "at-the-question.png").convert("RGB")
    assert shot.size[0] >= 1200
    colours = {c for _, c in shot.getcolors(1_000_000)}
    assert (0xff, 0xf8, 0xdc) in colours  # the question's box
    assert (0x1f, 0x4e, 0x79) in colours  # the header and the delegations' share bars


def test_the_team_timeline_draws_no_label_over_another_and_ends_offering_nothing(
        browser: Any, steered: dict):
    assert overlapping_labels(browser) == []
    assert offered(browser) == []
