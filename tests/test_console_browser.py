"""The operator console in a real browser: headless Chromium driven by Selenium.

One browser for the whole module (starting Chromium costs seconds on a
shared machine).  The give-bottle-distracted scenario runs live behind the
page, as fast as the machine allows, started paused so that the test sets a
breakpoint first; a second run is answered from the page; its log is then
replayed with the slider.  Skipped, with the reason, where Chromium, its
driver or Selenium is missing (``.ci/run`` installs them).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
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

from shary.console.replay import Replay, named_schemes
from shary.console.server import serving
from shary.log.contextlog import read_events
from sim.cli import live_run
from sim.scenario import find_scenario


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from chromium(1400, 1000)


def act_lines(driver: Any) -> list[str]:
    return driver.execute_script(
        "return [...document.querySelectorAll('#lines .line.act .what')]"
        ".map(e => e.textContent)")


@pytest.fixture(scope="module")
def watched(browser: Any, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """give-bottle-distracted watched live: paused at the start, a breakpoint on
    WAIT-ATTENTION, a screenshot there, then to the end.  Yields the run's folder."""
    out = tmp_path_factory.mktemp("distracted")
    live = live_run(find_scenario("give-bottle-distracted"), out=out, speed=0, paused=True)
    with serving(live) as url:
        browser.get(url)
        wait(lambda: status(browser).startswith("paused"), message="paused at the start")
        browser.find_element(By.ID, "bp-act").send_keys("WAIT-ATTENTION")
        browser.find_element(By.ID, "bp-add").click()
        wait(lambda: browser.find_elements(By.CSS_SELECTOR, "#breakpoints .chip"),
             message="the breakpoint's chip")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: "breakpoint WAIT-ATTENTION" in status(browser), message="the breakpoint")
        wait(lambda: browser.find_elements(
            By.CSS_SELECTOR, '.task g.active[data-state="suspended"]'),
            message="the diagram's highlight")
        browser.save_screenshot(str(out / "at-wait-attention.png"))
        browser.execute_script("window.atBreakpoint = document.getElementById('lines')"
                               ".textContent;")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: status(browser) == "ended", message="the end of the run")
        yield out


def test_the_page_shows_the_states_in_order(browser: Any, watched: Path):
    acts = act_lines(browser)
    top = [a for a in acts if a.endswith("give-object")]
    assert top == ["[ASK-TASK] give-object", "[REALIZE-TASK] give-object",
                   "[WAIT-ATTENTION] give-object", "[END-TASK] give-object"]
    assert browser.find_element(By.ID, "verdict").text.startswith("PASSED")
    lines = browser.find_element(By.ID, "lines").text
    assert "breakpoint" in lines and "resume" in lines  # the operator's actions, logged
    done = [(e.agent, e.data["action"]) for e in read_events(watched / "log.sqlite")
            if e.kind == "operator"]
    assert done == [("operator", "breakpoint"), ("operator", "resume"), ("operator", "resume")]


def test_a_screenshot_at_the_breakpoint_shows_the_key_elements(browser: Any, watched: Path):
    from PIL import Image

    shot = Image.open(watched / "at-wait-attention.png")
    assert shot.size[0] >= 1200
    # the highlight colour of the active state is on the picture, and the page's parts
    # were there when it was taken
    colours = {c for _, c in shot.convert("RGB").getcolors(1_000_000)}
    assert (0xff, 0xe6, 0x80) in colours
    text = browser.execute_script("return window.atBreakpoint")
    assert "[WAIT-ATTENTION] give-object" in text and "[END-TASK]" not in text
    for selector in ("#agents .agent", "#tree li", "#timeline rect", "#facts tr", "#agenda tr"):
        assert browser.find_elements(By.CSS_SELECTOR, selector), selector


def test_a_run_that_has_ended_offers_nothing_to_steer(browser: Any, watched: Path):
    assert status(browser) == "ended"
    assert offered(browser) == []  # no cancel, H-AGREE, take-control … of a run that is over


def test_the_main_scheme_of_a_task_is_drawn_legibly(browser: Any, watched: Path):
    """give-object-attentive, the task's own scheme (the agent's second task, after its
    session), is drawn at the session's scale: state names 11 px high, not 4 px."""
    heights = dict(browser.execute_script(
        "return [...document.querySelectorAll('.task')].map(t => [t.querySelector('h3')"
        ".firstChild.textContent.trim(), Math.max(...[...t.querySelectorAll("
        "'.diagram g.node text')].map(x => x.getBoundingClientRect().height))])"))
    assert heights["give-object"] >= 10.5
    assert heights["give-object"] == pytest.approx(heights["session"], abs=0.1)


def test_the_timeline_draws_no_label_over_another(browser: Any, watched: Path):
    assert overlapping_labels(browser) == []


def test_an_answer_from_the_page_changes_the_outcome(browser: Any, tmp_path: Path):
    live = live_run(find_scenario("give-bottle-distracted"), out=tmp_path, speed=0,
                    paused=True)
    with serving(live) as url:
        browser.get(url)
        no = wait(lambda: browser.find_elements(
            By.CSS_SELECTOR, '.question button[data-agent="alice"][data-act="H-DISAGREE"]'),
            message="the robot's question")
        browser.find_element(By.ID, "operator").clear()
        browser.find_element(By.ID, "operator").send_keys("tester")
        no[0].click()
        wait(lambda: "H-DISAGREE" in browser.find_element(By.ID, "lines").text,
             message="the answer logged")
        browser.find_element(
            By.CSS_SELECTOR, 'button.agent-act[data-agent="jido"]').click()  # take-control
        wait(lambda: "control-authority" in browser.find_element(By.ID, "reply").text,
             message="take-control refused, and said so")
        browser.find_element(By.ID, "resume").click()
        wait(lambda: status(browser) == "ended", message="the end of the run")
        lines = browser.find_element(By.ID, "lines").text
        assert "tester" in lines  # who answered is in the log
        acts = [a for a in act_lines(browser) if a.endswith("give-object")]
        assert acts == ["[ASK-TASK] give-object", "[END-TASK] give-object"]
        assert browser.find_element(By.ID, "verdict").text.startswith("FAILED")
        # a second answer to a question no longer asked is refused, and said so
        browser.execute_script("shary.ws.send(JSON.stringify({kind: 'answer', by: 'tester', "
                               "task: 'n1', agent: 'alice', act: 'H-AGREE', id: 99}))")
        wait(lambda: "refused" in browser.find_element(By.ID, "reply").text,
             message="the refusal")


def test_replay_slider_shows_the_tree_at_a_chosen_time(browser: Any, watched: Path):
    with serving(Replay(watched / "log.sqlite", named_schemes())) as url:
        browser.get(url)
        wait(lambda: status(browser) == "replay", message="the replay")
        tree = lambda: browser.find_element(By.ID, "tree").text  # noqa: E731
        assert "pick" in tree()  # at the end
        # two moments read from the log: while asking, and while fetching the bottle
        starts = {e.data["name"]: e.time for e in read_events(watched / "log.sqlite")
                  if e.kind == "task-start"}
        fetching = round((starts["fetch"] + starts["go-to-person"]) / 2, 1)
        for at, present, absent in ((round(starts["fetch"] / 2, 1), "ASK-TASK", "fetch"),
                                    (fetching, "pick", "REALIZE-TASK x go-to-person")):
            browser.execute_script(
                "const s = document.getElementById('slider'); s.value = arguments[0];"
                "s.dispatchEvent(new Event('input'));", at)
            wait(lambda p=present, a=absent: p in tree() and a not in tree(),
                 message=f"the tree at {at} s")
            assert browser.find_element(By.ID, "clock").text == f"{at:.1f} s"
