"""The StackBuildingTask on the simulated PR2: every stack scenario meets its expectations."""

from __future__ import annotations

import json
import sqlite3

import pytest

from sim.run import run_scenario
from sim.scenario import SCENARIOS_DIR

STACK = sorted(p.stem for p in SCENARIOS_DIR.glob("stack-*.yaml"))


def test_the_seven_stack_scenarios_and_the_regressions_are_shipped():
    assert STACK == ["stack-failure-said-on-the-phone", "stack-flicker",
                     "stack-human-chooses-placement", "stack-human-leaves-it-to-robot",
                     "stack-human-unexpected-action", "stack-inform-during-pick",
                     "stack-inform-waits-for-the-head", "stack-look-back-when-due",
                     "stack-nominal", "stack-not-seen", "stack-partner-walks-out",
                     "stack-place-fails-twice", "stack-told-across-a-replan"]


LOOK_BACK_AT = [2.0 * i for i in range(12)]
"""When the partner looks away (for two seconds), over the nominal run's 22 s."""


@pytest.mark.parametrize("at", LOOK_BACK_AT)
def test_the_partner_may_look_back_at_any_moment_and_the_plan_is_achieved(tmp_path, at):
    """Whatever the robot does when she looks back (its own action, her next action
    due, an inform under way), the head ends up where the plan needs it."""
    path = tmp_path / "stack-look-back.yaml"
    text = (SCENARIOS_DIR / "stack-nominal.yaml").read_text()
    path.write_text(text.replace("profile: {choices: [placement_1, Pick], delay: 1}",
                                 "profile: {choices: [placement_1, Pick], delay: 1, "
                                 f"look-away: {{at: {at}, for: 2}}}}")
                    .split("expect:")[0] + "expect:\n  plan: [started, achieved]\n"
                    "  facts: [[blue_cube_1, isOn, green_cube]]\n")
    result = run_scenario(path)
    assert result.passed, result.differences


@pytest.mark.parametrize("name", [s for s in STACK if s != "stack-not-seen"])
def test_a_stack_scenario_passes(name):
    result = run_scenario(SCENARIOS_DIR / f"{name}.yaml")
    assert result.passed, result.differences


def test_not_seen_is_told_and_the_timeline_shows_the_plan(tmp_path):
    result = run_scenario(SCENARIOS_DIR / "stack-not-seen.yaml", out=tmp_path)
    assert result.passed, result.differences
    with sqlite3.connect(tmp_path / "log.sqlite") as db:
        rows = [(kind, agent, json.loads(data)) for kind, agent, data in db.execute(
            "SELECT kind, agent, data FROM events WHERE kind IN ('plan-task', 'speech', "
            "'belief') ORDER BY seq")]
    missed = [i for i, (kind, agent, data) in enumerate(rows) if kind == "belief"]
    told = [i for i, (kind, agent, data) in enumerate(rows)
            if kind == "speech" and "placed the green cube" in data["text"]]
    assert missed and told and missed[0] < told[0]
    timeline = (tmp_path / "timeline.svg").read_text()
    assert 'class="plan-task plan-NOT_SEEN"' in timeline and "plan-ONGOING" in timeline
    assert (tmp_path / "tree.svg").read_text().count("StackBuildingTask") >= 1


def test_a_shared_plan_section_with_mistakes_is_refused_at_its_lines(tmp_path):
    from hostile import assert_refused, run_inprocess

    path = tmp_path / "bad.yaml"
    path.write_text((SCENARIOS_DIR / "stack-nominal.yaml").read_text()
                    .replace("problem: stack\n", "problem: stak\n")
                    .replace("partner: alice\n", "partner: bob\n"))
    outcome = run_inprocess("validate", path)
    assert_refused(outcome, path, message="no planner problem 'stak'")
    assert "the partner 'bob' is not one of the scenario's people" in outcome.err


def test_a_partner_who_leaves_is_not_called_for_their_task_and_the_plan_fails(tmp_path):
    """She walks out: the robot says goodbye, her task becomes NOT_STARTING, and the
    ask ends at once untold (nobody is called in an empty room): the plan fails."""
    path = tmp_path / "stack-leaves.yaml"
    path.write_text((SCENARIOS_DIR / "stack-nominal.yaml").read_text()
                    .replace("scenario: stack-nominal", "scenario: stack-leaves")
                    .replace("delay: 1}", 'delay: 1, leave: {after: "Place(alice, red_cube_2"}}')
                    .split("expect:")[0] + "expect:\n  plan: [started, failed]\n"
                    "  task-states: [[pr2, \"Pick(alice, stick)\", NOT_STARTING]]\n"
                    "  said: [\"Goodbye, Alice.\"]\n  no-acts: [CALL-ATTENTION]\n")
    result = run_scenario(path)
    assert result.passed, result.differences


def test_a_look_away_without_when_or_with_both_is_refused_at_its_line(tmp_path):
    from hostile import assert_refused, run_inprocess

    for when in ("{for: 2}", '{during: "Pick(pr2, green_cube)", at: 3, for: 2}'):
        path = tmp_path / "bad.yaml"
        path.write_text((SCENARIOS_DIR / "stack-look-back-when-due.yaml").read_text()
                        .replace('look-away: {during: "Pick(pr2, green_cube)", for: 2}',
                                 f"look-away: {when}"))
        outcome = run_inprocess("validate", path)
        assert_refused(outcome, path, message="look-away needs when: during")
